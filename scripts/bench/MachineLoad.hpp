// What else the machine was doing while a benchmark run took its time: the
// 1-minute load average (/proc/loadavg) and the CPU that other processes used
// during the run (all CPUs' busy time from /proc/stat minus this process's
// own user + system time).  The machines are shared: a run taken while
// another process computed is flagged and left out of min / median.
#pragma once
#include <sys/resource.h>
#include <unistd.h>

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

// One timed run: construct before it, call finish(wallSeconds) after it.
struct LoadProbe {
    double load1 = loadAverage1();
    double busy0 = machineBusySeconds();
    double own0 = ownCpuSeconds();
    // Cores that other processes kept busy on average during the run
    // (resolution: one clock tick, 10 ms, over the run's wall time).
    double othersCores(double wallSeconds) const {
        const double others = (machineBusySeconds() - busy0) - (ownCpuSeconds() - own0);
        return wallSeconds > 0 ? (others > 0 ? others : 0.0) / wallSeconds : 0.0;
    }
};

// The rule every benchmark here applies.  The load average counts this
// benchmark's own running threads too, so a run on `threads` threads is
// judged on load1 - (threads - 1) (the literal "load > 1.5" for one thread).
struct BusyRule {
    double maxLoad = 1.5;     // 1-minute load average, own extra threads discounted
    double maxOthers = 0.2;   // cores used by other processes during the run
    bool busy(double load1, double others, int threads) const {
        return load1 - (threads - 1) > maxLoad || others > maxOthers;
    }
};

}  // namespace bench
