// What one OpenMP synchronisation costs on this machine: the time from the
// master entering a parallel region to the second thread starting its work
// (fork), from the last thread reaching a barrier to both leaving it
// (barrier), and from the last thread finishing to the master leaving the
// region (join), for 2 threads, after a stretch of serial work in the master
// (as between the phases of a step).  The step of the 27-cube stack passes
// ~20 such points (doc/dev/performance_notebook.md, "What a fork costs"), so their price
// decides how the small phases scale.
//
//   omp_sync [--iterations 300] [--serial-us 5,100,1000] [--work-us 50] > omp_sync.json
//
// The price depends on the wait policy the process was started with
// (OMP_WAIT_POLICY, GOMP_SPINCOUNT: read once by libgomp at start), so the
// driver scripts/bench/omp_sync.py runs this program under each policy,
// interleaved.  Also recorded: the guest's idle-poll window
// (/sys/module/haltpoll/parameters/guest_halt_poll_ns, on KVM guests), which
// decides how long a sleeping thread's vCPU takes to wake.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "BenchStats.hpp"
#include "MachineLoad.hpp"

namespace {

// Busy work for about `us` microseconds (a dependent chain: no memory traffic).
double spin(double us) {
    const double t0 = omp_get_wtime();
    double x = 1.0;
    while (omp_get_wtime() - t0 < 1e-6 * us) x = std::sqrt(x + 1.0);
    return x;
}

std::string fileText(const char* path) {
    std::ifstream f(path);
    std::string s;
    if (f) std::getline(f, s);
    if (s.empty()) return "null";
    std::string q = "\"";  // (built by appends: GCC 12 warns falsely on "..." + string)
    q += s;
    q += '"';
    return q;
}

std::string envText(const char* name) {
    const char* v = std::getenv(name);
    if (!v) return "null";
    std::string q = "\"";
    q += v;
    q += '"';
    return q;
}

struct Point {
    double serialUs;
    Stats fork, barrier, join;
};

}  // namespace

int main(int argc, char** argv) {
    int iterations = 300;
    double workUs = 50;
    std::vector<double> serial = {5, 100, 1000};
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--iterations" && i + 1 < argc) {
            iterations = std::atoi(argv[++i]);
        } else if (a == "--work-us" && i + 1 < argc) {
            workUs = std::atof(argv[++i]);
        } else if (a == "--serial-us" && i + 1 < argc) {
            serial.clear();
            std::stringstream ss(argv[++i]);
            for (std::string t; std::getline(ss, t, ',');) serial.push_back(std::atof(t.c_str()));
        } else {
            std::fprintf(stderr, "usage: omp_sync [--iterations N>=20] [--serial-us A,B,..] [--work-us W]\n");
            return 2;
        }
    }
    if (iterations < 20 || serial.empty() || !(workUs >= 0)) {
        std::fprintf(stderr, "omp_sync: need --iterations >= 20, at least one --serial-us, --work-us >= 0\n");
        return 2;
    }
    bench::OwnLoad own;
    own.update();
    const double busy0 = bench::machineBusySeconds(), cpu0 = bench::ownCpuSeconds(), wall0 = omp_get_wtime();
    double sink = 0;
    std::vector<Point> points;
    for (double s : serial) {
        Point p{s, {}, {}, {}};
        for (int it = 0; it < iterations + 10; ++it) {
            sink += spin(s);
            double enter[2] = {0, 0}, arrive[2] = {0, 0}, leave[2] = {0, 0}, done[2] = {0, 0};
            const double tFork = omp_get_wtime();
#pragma omp parallel num_threads(2) reduction(+ : sink)
            {
                const int t = omp_get_thread_num();
                enter[t] = omp_get_wtime();
                sink += spin(workUs);
                arrive[t] = omp_get_wtime();
#pragma omp barrier
                leave[t] = omp_get_wtime();
                sink += spin(workUs * (1 + t));  // thread 1 finishes last: the master waits for it
                done[t] = omp_get_wtime();
            }
            const double tJoin = omp_get_wtime();
            if (it < 10) continue;  // warm-up: threads created, poll windows settled
            p.fork.v.push_back(1e6 * (enter[1] - tFork));
            p.barrier.v.push_back(1e6 * (std::max(leave[0], leave[1]) - std::max(arrive[0], arrive[1])));
            p.join.v.push_back(1e6 * (tJoin - std::max(done[0], done[1])));
        }
        points.push_back(p);
    }
    const double wall = omp_get_wtime() - wall0;
    const double others = (bench::machineBusySeconds() - busy0 - (bench::ownCpuSeconds() - cpu0)) / wall;
    std::printf("{\"benchmark\": \"omp_sync\", \"threads\": 2, \"iterations\": %d, \"work_us\": %g, "
                "\"OMP_WAIT_POLICY\": %s, \"GOMP_SPINCOUNT\": %s, \"cpuidle_driver\": %s, "
                "\"guest_halt_poll_ns\": %s, \"load1\": %.2f, \"own_load\": %.2f, \"other_cores\": %.2f, "
                "\"unit\": \"us\", \"points\": [",
                iterations, workUs, envText("OMP_WAIT_POLICY").c_str(), envText("GOMP_SPINCOUNT").c_str(),
                fileText("/sys/devices/system/cpu/cpuidle/current_driver").c_str(),
                fileText("/sys/module/haltpoll/parameters/guest_halt_poll_ns").c_str(), bench::loadAverage1(),
                own.update(), others);
    for (std::size_t i = 0; i < points.size(); ++i)
        std::printf("%s{\"serial_us\": %g, \"fork\": %s, \"barrier\": %s, \"join\": %s}", i ? ", " : "",
                    points[i].serialUs, points[i].fork.json("%.3g").c_str(), points[i].barrier.json("%.3g").c_str(),
                    points[i].join.json("%.3g").c_str());
    std::printf("], \"sink\": %d}\n", sink > 0 ? 1 : 0);
    return 0;
}
