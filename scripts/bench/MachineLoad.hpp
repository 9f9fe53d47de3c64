// What else the machine was doing while a benchmark run took its time: the
// 1-minute load average (/proc/loadavg) and the CPU that other processes used
// during the run (all CPUs' busy time from /proc/stat minus this process's
// own user + system time).  The machines are shared: a run taken while
// another process computed is flagged and left out of min / median.
#pragma once
#include <sys/resource.h>
#include <unistd.h>

#include <time.h>

#include <cmath>
#include <cstdio>

namespace bench {

inline double loadAverage1() {
    double l = -1;
    if (FILE* f = std::fopen("/proc/loadavg", "r")) {
        if (std::fscanf(f, "%lf", &l) != 1) l = -1;
        std::fclose(f);
    }
    return l;
}

// Busy seconds of all CPUs since boot (user, nice, system, irq, softirq, steal).
inline double machineBusySeconds() {
    unsigned long long u = 0, n = 0, s = 0, idle = 0, io = 0, irq = 0, sirq = 0, steal = 0;
    if (FILE* f = std::fopen("/proc/stat", "r")) {
        if (std::fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &u, &n, &s, &idle, &io, &irq, &sirq,
                        &steal) != 8)
            u = n = s = irq = sirq = steal = 0;
        std::fclose(f);
    }
    return double(u + n + s + irq + sirq + steal) / double(sysconf(_SC_CLK_TCK));
}

inline double ownCpuSeconds() {
    rusage r{};
    getrusage(RUSAGE_SELF, &r);
    return r.ru_utime.tv_sec + r.ru_stime.tv_sec + 1e-6 * (r.ru_utime.tv_usec + r.ru_stime.tv_usec);
}

// This process's own share of the load average: the kernel's 1-minute load
// is an exponential average (time constant 60 s) of the running threads, so
// the same average of this process's CPU use (cores) estimates how much of
// load1 is the benchmark itself.  Updated at each probe (runs back to back).
struct OwnLoad {
    double ema = 0, lastWall = -1, lastCpu = 0;
    double update() {
        timespec ts{};
        clock_gettime(CLOCK_MONOTONIC, &ts);
        const double wall = ts.tv_sec + 1e-9 * ts.tv_nsec, cpu = ownCpuSeconds();
        if (lastWall >= 0 && wall > lastWall) {
            const double w = std::exp(-(wall - lastWall) / 60.0);
            ema = w * ema + (1 - w) * (cpu - lastCpu) / (wall - lastWall);
        }
        lastWall = wall;
        lastCpu = cpu;
        return ema;
    }
};
inline OwnLoad& ownLoad() {
    static OwnLoad o;
    return o;
}

// One timed run: construct before it, call othersCores(wallSeconds) after it.
struct LoadProbe {
    double own = ownLoad().update();  // this benchmark's share of load1
    double load1 = loadAverage1();
    double busy0 = machineBusySeconds();
    double own0 = ownCpuSeconds();
    // Cores that other processes kept busy on average during the run
    // (resolution: one clock tick, 10 ms, over the run's wall time).
    double othersCores(double wallSeconds) const {
        const double others = (machineBusySeconds() - busy0) - (ownCpuSeconds() - own0);
        return wallSeconds > 0 ? (others > 0 ? others : 0.0) / wallSeconds : 0.0;
    }
    // The load average less this benchmark's own share: what others put there.
    double othersLoad() const { return load1 - own > 0 ? load1 - own : 0.0; }
};

// The rule every benchmark here applies: a run is busy when other processes
// used more than 0.2 cores during it (all CPUs' busy time less this
// process's own, over the run's wall time).  The 1-minute load average is
// recorded with each run but does not decide: it lags by about a minute, so
// it still holds the benchmark's own set-up and whatever ran just before
// (measured 2026-11-24: load 1.6 "less own share" over 1 on runs during
// which other processes used 0.00 cores, right after another benchmark).
struct BusyRule {
    double maxOthers = 0.2;   // cores used by other processes during the run
    bool busy(const LoadProbe&, double others) const { return others > maxOthers; }
};

}  // namespace bench
