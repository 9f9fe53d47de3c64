// Element + integration cost on the seed paper's Figure 6 mesh: 27 cubes of
// 8x8x8 cells, 12 tets per cell (165,888 tets, 33,507 nodes), at 1 and 2
// threads, for each material law (Saint-Venant-Kirchhoff and Stable
// Neo-Hookean, runs interleaved so that machine noise hits both alike).
// Prints JSON (ns per tet per step: min and median over the repeats) to stdout.
//
//   bench_elements [steps=200] [cubesPerAxis=3] [repeats=5]
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <memory>

#include "mesh/BoxMesh.hpp"
#include "world/World.hpp"
#include "BenchStats.hpp"

using namespace qdem;

namespace {

// (by pointer: a World is not copied or moved, its phases refer to it)
std::unique_ptr<World> makeScene(int cubesPerAxis, MaterialLaw law) {
    auto wp = std::make_unique<World>();
    World& w = *wp;
    Material m;  // seed Table 1
    m.law = law;
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
    return wp;
}

struct Figures {
    double elementNs, integrateNs, stepNs;
};

Figures run(World& w, int threads, int steps, bool viscous) {
    omp_set_num_threads(threads);
    w.settings.viscosityOn = viscous;
    const double dt = 0.5 * w.stableDt().combined;
    for (int i = 0; i < 5; ++i) w.step(dt);  // warm-up, builds the thread layout
    double el = 0, in = 0;
    const double t0 = omp_get_wtime();
    for (int i = 0; i < steps; ++i) {
        w.step(dt);
        const PhaseReport r = w.report();
        el += r.second("elements");
        in += r.second("integrate");
    }
    const double total = omp_get_wtime() - t0;
    const double perTetStep = 1e9 / (double(steps) * w.nTets());
    return {el * perTetStep, in * perTetStep, total * perTetStep};
}


}  // namespace

int main(int argc, char** argv) {
    const int steps = argc > 1 ? std::atoi(argv[1]) : 200;
    const int cubes = argc > 2 ? std::atoi(argv[2]) : 3;
    const int repeats = argc > 3 ? std::atoi(argv[3]) : 5;
    const MaterialLaw laws[2] = {MaterialLaw::SaintVenantKirchhoff, MaterialLaw::StableNeoHookean};
    const std::unique_ptr<World> owners[2] = {makeScene(cubes, laws[0]), makeScene(cubes, laws[1])};
    World* worlds[2] = {owners[0].get(), owners[1].get()};
    std::printf("{\"tets\": %zu, \"nodes\": %zu, \"steps\": %d, \"repeats\": %d, \"threads\": {", worlds[0]->nTets(),
                worlds[0]->nNodes(), steps, repeats);
    const int maxThreads = omp_get_num_procs();
    for (int th = 1; th <= std::min(2, maxThreads); ++th) {
        // [law][viscous]: element + integrate ns/tet/step; element only
        Stats total[2][2], element[2][2];
        for (int r = 0; r < repeats; ++r)
            for (int l = 0; l < 2; ++l)
                for (int v = 0; v < 2; ++v) {
                    const Figures f = run(*worlds[l], th, steps, v == 1);
                    total[l][v].v.push_back(f.elementNs + f.integrateNs);
                    element[l][v].v.push_back(f.elementNs);
                }
        std::printf("%s\"%d\": {", th > 1 ? ", " : "", th);
        for (int l = 0; l < 2; ++l) {
            std::printf("%s\"%s\": {", l ? ", " : "", lawName(laws[l]));
            for (int v = 1; v >= 0; --v)
                std::printf("%s\"%s\": {\"ns_per_tet_step_min\": %.3f, \"ns_per_tet_step_median\": %.3f, "
                            "\"element_ns_per_tet_step_min\": %.3f, \"element_ns_per_tet_step_median\": %.3f}",
                            v == 1 ? "" : ", ", v ? "viscous" : "elastic", total[l][v].min(), total[l][v].median(),
                            element[l][v].min(), element[l][v].median());
            std::printf("}");
        }
        std::printf(", \"element_ratio_snh_over_svk_min\": {\"viscous\": %.3f, \"elastic\": %.3f}",
                    element[1][1].min() / element[0][1].min(), element[1][0].min() / element[0][0].min());
        std::printf(", \"element_ratio_snh_over_svk_median\": {\"viscous\": %.3f, \"elastic\": %.3f}",
                    element[1][1].median() / element[0][1].median(), element[1][0].median() / element[0][0].median());
        // The default law's figures under the keys merge_elements.py and
        // doc/performance.md have always read (medians).
        std::printf(", \"ns_per_tet_step\": %.3f, \"element_ns_per_tet_step\": %.3f, "
                    "\"elastic_only_ns_per_tet_step\": %.3f}",
                    total[1][1].median(), element[1][1].median(), total[1][0].median());
        std::fflush(stdout);
    }
    std::printf("}}\n");
    return 0;
}
