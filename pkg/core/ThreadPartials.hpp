// Per-thread partial sums added in thread order.  OpenMP's reduction(+)
// combines the threads' partials in the order the threads arrive, so with
// three threads or more the last bits of a floating-point sum (an energy
// booked by a contact loop) vary from run to run; a thread writes its
// partials into its own row here and sum() adds the rows 0, 1, 2, ... in
// order: the same bits at a given thread count, whatever the scheduling.
// Fixed storage (no allocation per step): rows for up to kMaxThreads threads.
#pragma once
#include <array>
#include <stdexcept>
#include <string>

namespace qdem {

template <int N>
class ThreadPartials {
public:
    static constexpr int kMaxThreads = 256;

    // nThreads: the most threads the region may run (rows beyond the
    // threads that ran stay zero).
    explicit ThreadPartials(int nThreads) : n_(nThreads) {
        if (nThreads < 1 || nThreads > kMaxThreads)
            throw std::invalid_argument("ThreadPartials: " + std::to_string(nThreads) + " threads, at most " +
                                        std::to_string(kMaxThreads) + " supported: run QDEM on fewer threads");
        for (int t = 0; t < n_; ++t) rows_[t].fill(0.0);
    }

    void set(int thread, const std::array<double, N>& partial) { rows_[thread] = partial; }

    std::array<double, N> sum() const {
        std::array<double, N> s{};
        for (int t = 0; t < n_; ++t)
            for (int k = 0; k < N; ++k) s[k] += rows_[t][k];
        return s;
    }

private:
    int n_;
    std::array<std::array<double, N>, kMaxThreads> rows_;
};

}  // namespace qdem
