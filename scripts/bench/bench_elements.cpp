// Element + integration cost on the seed paper's Figure 6 mesh: 27 cubes of
// 8x8x8 cells, 12 tets per cell (165,888 tets, 33,507 nodes), at 1 and 2
// threads.  Prints JSON (ns per tet per step) to stdout.
//
//   bench_elements [steps=200] [cubesPerAxis=3]
#include <omp.h>

#include <cstdio>
#include <cstdlib>

#include "mesh/BoxMesh.hpp"
#include "world/World.hpp"

using namespace qdem;

namespace {

World makeScene(int cubesPerAxis) {
    World w;
    Material m;  // seed Table 1
    const int mat = w.addMaterial(m);
    const double size = 1.0, gap = 0.1;
    for (int i = 0; i < cubesPerAxis; ++i)
        for (int j = 0; j < cubesPerAxis; ++j)
            for (int k = 0; k < cubesPerAxis; ++k) {
                TetMesh c = boxMesh(8, 8, 8, size, size, size, 12);
                for (std::size_t n = 0; n < c.nNodes(); ++n) {
                    c.nodes[3 * n] += i * (size + gap);
                    c.nodes[3 * n + 1] += j * (size + gap);
                    c.nodes[3 * n + 2] += k * (size + gap);
                }
                w.addPiece(c, mat);
            }
    // A small random-looking velocity field so that the viscous term works.
    for (std::size_t i = 0; i < w.vel.size(); ++i) w.vel[i] = 1e-3 * ((i * 2654435761u) % 1000 / 1000.0 - 0.5);
    w.gravity = Eigen::Vector3d(0, 0, -9.80665);
    return w;
}

struct Figures {
    double elementNs, integrateNs, stepNs;
};

Figures run(World& w, int threads, int steps, bool viscous) {
    omp_set_num_threads(threads);
    w.viscosityOn = viscous;
    const double dt = 0.5 * w.stableDt().combined;
    for (int i = 0; i < 5; ++i) w.step(dt);  // warm-up, builds the thread layout
    double el = 0, in = 0;
    const double t0 = omp_get_wtime();
    for (int i = 0; i < steps; ++i) {
        w.step(dt);
        el += w.timings.elements;
        in += w.timings.integrate;
    }
    const double total = omp_get_wtime() - t0;
    const double perTetStep = 1e9 / (double(steps) * w.nTets());
    return {el * perTetStep, in * perTetStep, total * perTetStep};
}

}  // namespace

int main(int argc, char** argv) {
    const int steps = argc > 1 ? std::atoi(argv[1]) : 200;
    const int cubes = argc > 2 ? std::atoi(argv[2]) : 3;
    World w = makeScene(cubes);
    std::printf("{\"tets\": %zu, \"nodes\": %zu, \"steps\": %d, \"threads\": {", w.nTets(), w.nNodes(), steps);
    const int maxThreads = omp_get_num_procs();
    for (int th = 1; th <= std::min(2, maxThreads); ++th) {
        const Figures v = run(w, th, steps, true);
        const Figures e = run(w, th, steps, false);
        std::printf("%s\"%d\": {\"ns_per_tet_step\": %.3f, \"element_ns_per_tet_step\": %.3f, "
                    "\"integrate_ns_per_tet_step\": %.3f, \"elastic_only_ns_per_tet_step\": %.3f}",
                    th > 1 ? ", " : "", th, v.elementNs + v.integrateNs, v.elementNs, v.integrateNs,
                    e.elementNs + e.integrateNs);
        std::fflush(stdout);
    }
    std::printf("}}\n");
    return 0;
}
