// The machine's two ceilings, measured: floating-point peak (a loop of
// independent fused multiply-adds, the widest vectors this build targets) and
// memory bandwidth (STREAM's triad a = b + s c, on arrays far larger than the
// L3 cache and on arrays that fit in it), on 1 and 2 threads.  The element
// phase's floors in doc/dev/performance_notebook.md are its flops over the first and its
// bytes over the second.
//
//   roofline [--repeats 7] [--max-others 0.2] > roofline.json
//
// Every measurement is repeated, interleaved, with the 1-minute load average
// and the CPU other processes used recorded per run (MachineLoad.hpp); busy
// runs are flagged and left out of min / median / max ("clean").
//
// Bytes of the triad are counted as STREAM counts them: 24 per element (two
// loads, one store).  A store that misses the cache also reads its line
// first (write-allocate), so the traffic the memory really carries is 32 per
// element; `triad_dram_with_write_allocate` reports that reading too.
#include <immintrin.h>
#include <omp.h>

#include <time.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "BenchStats.hpp"
#include "MachineLoad.hpp"

namespace {

#if defined(__AVX512F__)
constexpr const char* kIsa = "AVX-512 (8 doubles per FMA)";
constexpr int kLanes = 8;
using Vec = __m512d;
inline Vec splat(double x) { return _mm512_set1_pd(x); }
inline Vec fmadd(Vec a, Vec b, Vec c) { return _mm512_fmadd_pd(a, b, c); }
inline double sum(Vec a) {  // (GCC 12's _mm512_reduce_add_pd warns from its own header)
    alignas(64) double t[8];
    _mm512_store_pd(t, a);
    return t[0] + t[1] + t[2] + t[3] + t[4] + t[5] + t[6] + t[7];
}
#elif defined(__AVX2__) && defined(__FMA__)
constexpr const char* kIsa = "AVX2 (4 doubles per FMA)";
constexpr int kLanes = 4;
using Vec = __m256d;
inline Vec splat(double x) { return _mm256_set1_pd(x); }
inline Vec fmadd(Vec a, Vec b, Vec c) { return _mm256_fmadd_pd(a, b, c); }
inline double sum(Vec a) {
    alignas(32) double t[4];
    _mm256_store_pd(t, a);
    return t[0] + t[1] + t[2] + t[3];
}
#else
#error "roofline: needs AVX2+FMA or AVX-512 (built with -march=native on such a machine)"
#endif

// 12 independent chains: covers an FMA latency of 4 cycles on 2 pipes with
// room to spare (8 would do on paper; more spill nothing on 32 registers).
constexpr int kChains = 12;

// Flops of `iters` rounds of kChains FMAs on one thread; returns a value that
// depends on every chain so the compiler keeps them all.
double fmaLoop(long iters, double seed) {
    Vec acc[kChains];
    for (int j = 0; j < kChains; ++j) acc[j] = splat(seed + j);
    const Vec m = splat(0.999999), a = splat(1e-7);  // bounded: x -> 0.1 + small
    for (long i = 0; i < iters; ++i) {
#pragma GCC unroll 12
        for (int j = 0; j < kChains; ++j) acc[j] = fmadd(acc[j], m, a);
    }
    double s = 0;
    for (int j = 0; j < kChains; ++j) s += sum(acc[j]);
    return s;
}

double sink = 0;  // keeps results alive

double threadCpuSeconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// GFLOP/s of the FMA loop on `threads` threads, each doing `iters` rounds;
// `cpu`: the threads' CPU seconds added up (the time they held a core).
double fmaPeak(int threads, long iters, double& wall, double& cpu) {
    double total = 0, cpuSum = 0;
    const double t0 = omp_get_wtime();
#pragma omp parallel num_threads(threads) reduction(+ : total, cpuSum)
    {
        const double c0 = threadCpuSeconds();
        total += fmaLoop(iters, omp_get_thread_num());
        cpuSum += threadCpuSeconds() - c0;
    }
    wall = omp_get_wtime() - t0;
    cpu = cpuSum;
    sink += total;
    return 2.0 * kLanes * kChains * double(iters) * threads / wall * 1e-9;
}

struct Arrays {
    std::size_t n;
    double *a, *b, *c;
    explicit Arrays(std::size_t n_) : n(n_) {
        a = static_cast<double*>(std::aligned_alloc(64, n * sizeof(double)));
        b = static_cast<double*>(std::aligned_alloc(64, n * sizeof(double)));
        c = static_cast<double*>(std::aligned_alloc(64, n * sizeof(double)));
        if (!a || !b || !c) {
            std::fprintf(stderr, "roofline: cannot allocate 3 x %zu doubles\n", n);
            std::exit(1);
        }
    }
    ~Arrays() {
        std::free(a);
        std::free(b);
        std::free(c);
    }
    // First touch by the threads that will use each part (static schedule).
    void init(int threads) {
#pragma omp parallel for schedule(static) num_threads(threads)
        for (std::size_t i = 0; i < n; ++i) a[i] = 0, b[i] = 1.0 + 1e-9 * double(i % 1000), c[i] = 2.0;
    }
};

// GB/s of `passes` triads over the arrays (24 bytes per element).
double triad(Arrays& x, int threads, int passes, double& wall, double& cpu) {
    const double s = 3.0;
    double* __restrict a = x.a;
    const double* __restrict b = x.b;
    const double* __restrict c = x.c;
    const std::size_t n = x.n;
    double cpuSum = 0;
    const double t0 = omp_get_wtime();
#pragma omp parallel num_threads(threads) reduction(+ : cpuSum)
    {
        const double c0 = threadCpuSeconds();
        for (int p = 0; p < passes; ++p) {
#pragma omp for schedule(static) nowait
            for (std::size_t i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
#pragma omp barrier
        }
        cpuSum += threadCpuSeconds() - c0;
    }
    wall = omp_get_wtime() - t0;
    cpu = cpuSum;
    sink += a[n / 3];
    return 24.0 * double(n) * passes / wall * 1e-9;
}

struct Run {
    double value, onCpu, load1, ownLoad, others;
    bool busy;
};

struct Measure {
    std::string name, unit;
    int threads;
    std::vector<Run> runs;
};

}  // namespace

int main(int argc, char** argv) {
    int repeats = 7;
    bench::BusyRule rule;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--repeats")) repeats = std::atoi(argv[i + 1]);
        else if (!std::strcmp(argv[i], "--max-others")) rule.maxOthers = std::atof(argv[i + 1]);
        else {
            std::fprintf(stderr, "roofline: unknown option %s\nusage: roofline [--repeats N] "
                                 "[--max-others C]\n", argv[i]);
            return 2;
        }
    }
    if (argc % 2 == 0 || repeats < 1) {
        std::fprintf(stderr, "usage: roofline [--repeats N>=1] [--max-others C]\n");
        return 2;
    }
    // DRAM: 3 x 256 MB (24x the 32 MB L3); L3: 3 x 2 MB = 6 MB (fits the L3,
    // not the 1 MB of L2 per core).
    Arrays big(std::size_t(32) << 20), small(std::size_t(256) << 10);
    big.init(2);
    small.init(2);
    std::vector<Measure> ms;
    for (int th : {1, 2}) {
        ms.push_back({"fma_peak", "GFLOP/s", th, {}});
        ms.push_back({"triad_dram", "GB/s", th, {}});
        ms.push_back({"triad_l3", "GB/s", th, {}});
    }
    const long fmaIters = 100000000;  // 1.2e9 FMAs per thread: ~0.1-0.3 s
    for (int r = 0; r < repeats; ++r)
        for (Measure& m : ms) {
            const bench::LoadProbe probe;
            double wall = 0, cpu = 0, v = 0;
            if (m.name == "fma_peak") v = fmaPeak(m.threads, fmaIters, wall, cpu);
            else if (m.name == "triad_dram") v = triad(big, m.threads, 5, wall, cpu);
            else v = triad(small, m.threads, 400, wall, cpu);
            const double others = probe.othersCores(wall);
            // The rate while the threads held their cores: the work over
            // their mean CPU time (time-shared runs lose the rest).
            const double onCpu = cpu > 0 ? v * wall / (cpu / m.threads) : v;
            m.runs.push_back({v, onCpu, probe.load1, probe.own, others, rule.busy(probe, others)});
            std::fprintf(stderr, "roofline %-10s %d thread(s) round %d: %.1f %s (%.1f on CPU); load %.2f (own %.2f), others %.2f "
                         "cores%s\n",
                         m.name.c_str(), m.threads, r, v, m.unit.c_str(), m.runs.back().onCpu, probe.load1, probe.own, others,
                         m.runs.back().busy ? " BUSY (excluded)" : "");
        }
    char date[32];
    const std::time_t now = std::time(nullptr);
    std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
    std::printf("{\"benchmark\": \"roofline\", \"date\": \"%s\", \"isa\": \"%s\", \"cpus\": %d, \"fma_chains\": %d, "
                "\"triad_bytes_per_element\": 24, \"dram_array_mb\": %.0f, \"l3_array_mb\": %.0f, "
                "\"busy_rule\": {\"max_other_cores\": %g}, \"results\": [",
                date, kIsa, omp_get_num_procs(), kChains, big.n * 8.0 / (1 << 20), small.n * 8.0 / (1 << 20),
                rule.maxOthers);
    for (std::size_t i = 0; i < ms.size(); ++i) {
        Stats clean, all, cpuClean, cpuAll;
        std::string list;
        for (const Run& x : ms[i].runs) {
            char b[200];
            std::snprintf(b, sizeof b,
                          "%s{\"value\": %.2f, \"on_cpu\": %.2f, \"load1\": %.2f, \"own_load\": %.2f, "
                          "\"other_cores\": %.2f, \"busy\": %s}",
                          list.empty() ? "" : ", ", x.value, x.onCpu, x.load1, x.ownLoad, x.others,
                          x.busy ? "true" : "false");
            list += b;
            all.v.push_back(x.value);
            cpuAll.v.push_back(x.onCpu);
            if (!x.busy) clean.v.push_back(x.value), cpuClean.v.push_back(x.onCpu);
        }
        std::printf("%s{\"name\": \"%s\", \"threads\": %d, \"unit\": \"%s\", \"clean\": %s, \"all\": %s, "
                    "\"on_cpu\": {\"clean\": %s, \"all\": %s}, \"runs\": [%s]}",
                    i ? ", " : "", ms[i].name.c_str(), ms[i].threads, ms[i].unit.c_str(), clean.json().c_str(),
                    all.json().c_str(), cpuClean.json().c_str(), cpuAll.json().c_str(), list.c_str());
        if (ms[i].name == "triad_dram") {  // the same runs, write-allocate traffic counted
            for (Stats* st : {&clean, &all, &cpuClean, &cpuAll})
                for (double& v : st->v) v *= 32.0 / 24.0;
            std::printf(", {\"name\": \"triad_dram_with_write_allocate\", \"threads\": %d, \"unit\": \"GB/s\", "
                        "\"clean\": %s, \"all\": %s, \"on_cpu\": {\"clean\": %s, \"all\": %s}, "
                        "\"note\": \"the triad_dram runs, 32 bytes per element\"}",
                        ms[i].threads, clean.json().c_str(), all.json().c_str(), cpuClean.json().c_str(),
                        cpuAll.json().c_str());
        }
    }
    std::printf("], \"sink\": %g}\n", sink > 0 ? 1.0 : 0.0);
    return 0;
}
