// QDEM's own OpenMP thread count.  QDEM shares the OpenMP runtime with YADE,
// whose ForceContainer keeps one buffer per thread of YADE's own count (yade
// -j N): changing the process-wide count would make YADE's InteractionLoop
// write past those buffers.  So QDEM never changes it for good: each step
// runs inside a ThreadScope that sets QDEM's count and restores YADE's.
#pragma once
#include <omp.h>

namespace qdem {

// Threads QDEM uses; 0 = whatever the caller (YADE) uses.
inline int& qdemThreads() {
    static int n = 0;
    return n;
}

inline int effectiveThreads() { return qdemThreads() > 0 ? qdemThreads() : omp_get_max_threads(); }

class ThreadScope {
public:
    ThreadScope() : saved_(omp_get_max_threads()) {
        if (qdemThreads() > 0) omp_set_num_threads(qdemThreads());
    }
    ~ThreadScope() { omp_set_num_threads(saved_); }
    ThreadScope(const ThreadScope&) = delete;
    ThreadScope& operator=(const ThreadScope&) = delete;

private:
    int saved_;
};

}  // namespace qdem
