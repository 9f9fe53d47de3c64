"""OpenMP synchronisation points per step of the moving 27-cube stack
(scripts/arch/scenes.py), counted, not timed: a small LD_PRELOAD library
(compiled here with gcc into a temporary directory) counts the calls into
libgomp that synchronise threads: GOMP_parallel (a fork and a join each, unless
the region's `if` clause kept it on one thread), GOMP_barrier (a barrier:
the end of a static `omp for` without nowait, or an explicit one) and
GOMP_loop_end (the end of a dynamic `omp for` without nowait).  A region
whose `if` clause is false (num_threads 1) does not fork; barrier and
loop-end calls are made by every thread: divided by the thread count they
are synchronisations.  Multiply by the price of one (scripts/bench/omp_sync.py)
to get what waiting costs a step.

    PYTHONPATH=build/python /usr/bin/python3.11 scripts/bench/contacts/sync_points.py [--threads 2] [--steps 20]
"""
import argparse
import ctypes
import os
import subprocess
import sys
import tempfile

SHIM = r"""
#define _GNU_SOURCE
#include <dlfcn.h>
static long n[4];
static void* gomp(void) { static void* h; if (!h) h = dlopen("libgomp.so.1", RTLD_NOW | RTLD_GLOBAL); return h; }
void GOMP_parallel(void (*fn)(void*), void* data, unsigned nt, unsigned flags) {
    static void (*real)(void (*)(void*), void*, unsigned, unsigned);
    if (!real) real = (void (*)(void (*)(void*), void*, unsigned, unsigned))dlsym(gomp(), "GOMP_parallel");
    __atomic_add_fetch(&n[0], 1, __ATOMIC_RELAXED);
    if (nt != 1) __atomic_add_fetch(&n[3], 1, __ATOMIC_RELAXED); /* (1: the region's `if` was false) */
    real(fn, data, nt, flags);
}
void GOMP_barrier(void) {
    static void (*real)(void);
    if (!real) real = (void (*)(void))dlsym(gomp(), "GOMP_barrier");
    __atomic_add_fetch(&n[1], 1, __ATOMIC_RELAXED);
    real();
}
void GOMP_loop_end(void) {
    static void (*real)(void);
    if (!real) real = (void (*)(void))dlsym(gomp(), "GOMP_loop_end");
    __atomic_add_fetch(&n[2], 1, __ATOMIC_RELAXED);
    real();
}
long syncCount(int k) { return n[k]; }
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--cells", type=int, default=8)
    a = ap.parse_args()
    if os.environ.get("QDEM_SYNC_SHIM") is None:
        # Re-run this script with the library preloaded (libgomp is loaded
        # with the qdem module, after the preload: the shim finds it by name).
        tmp = tempfile.mkdtemp(prefix="qdem_sync_")
        src, lib = os.path.join(tmp, "shim.c"), os.path.join(tmp, "shim.so")
        with open(src, "w") as f:
            f.write(SHIM)
        subprocess.run(["gcc", "-O2", "-shared", "-fPIC", src, "-o", lib, "-ldl"], check=True)
        env = dict(os.environ, LD_PRELOAD=lib, QDEM_SYNC_SHIM=lib)
        sys.exit(subprocess.run([sys.executable] + sys.argv, env=env, timeout=600).returncode)
    shim = ctypes.CDLL(os.environ["QDEM_SYNC_SHIM"])
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "arch"))
    from qdem import _core
    import scenes
    _core.setThreads(a.threads)
    w, dt = scenes.cubes27World(a.cells)
    w.core.step(dt, 5)
    r0 = w.core.verletRebuilds
    c0 = [shim.syncCount(k) for k in range(4)]
    w.core.step(dt, a.steps)
    c = [(shim.syncCount(k) - c0[k]) / a.steps for k in range(4)]
    forks, barriers = c[3], (c[1] + c[2]) / a.threads
    print("%d thread(s), %d steps (%d with a Verlet rebuild), per step: %.1f parallel regions, %.1f of them forked "
          "(a fork and a join each), %.1f barriers inside regions: %.1f synchronisations"
          % (a.threads, a.steps, w.core.verletRebuilds - r0, c[0], forks, barriers,
             2 * forks + barriers if a.threads > 1 else 0))


if __name__ == "__main__":
    main()
