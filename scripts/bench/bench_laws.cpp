// Element-kernel cost per material law, in isolation: elementBatch over the
// tets of one 8x8x8-cell, 12-tets-per-cell cube (6,144 tets, in cache),
// each law and mode timed for many short rounds, interleaved, so that on a
// shared machine the minimum over rounds estimates the uncontended cost and
// both laws see the same noise.  One thread.  Prints JSON (ns per tet, min
// and median over the rounds, and the SNH/SVK ratios).
//
//   bench_laws [rounds=300]
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <type_traits>
#include <vector>

#include "element/ElementKernel.hpp"
#include "element/MaterialLaw.hpp"
#include "mesh/BoxMesh.hpp"
#include "world/World.hpp"
#include "BenchStats.hpp"

using namespace qdem;

namespace {

double sink = 0;  // keeps the results alive

template <class Law, bool Viscous>
double timeKernel(const Law& law, const World& w, const ElementParams& p, std::vector<double>& f) {
    const auto T = static_cast<int32_t>(w.nTets());
    BatchOut out;
    const double t0 = omp_get_wtime();
    for (int32_t e0 = 0; e0 < T; e0 += kLanes) {
        const int count = std::min<int32_t>(kLanes, T - e0);
        elementBatch<Law, Viscous, false>(law, e0, count, w.tetNodes.data(), w.pos.data(), w.vel.data(),
                                          w.tetB.data(), w.tetVol0.data(), p, out);
        for (int l = 0; l < count; ++l) {
            const int32_t* c = &w.tetNodes[4 * (e0 + l)];
            for (int k = 0; k < 4; ++k)
                for (int i = 0; i < 3; ++i) f[3 * c[k] + i] += out.f[k][i][l];
        }
    }
    const double t = omp_get_wtime() - t0;
    sink += f[0];
    return 1e9 * t / T;
}


}  // namespace

int main(int argc, char** argv) {
    const int rounds = argc > 1 ? std::atoi(argv[1]) : 300;
    World w;
    Material m;
    w.addPiece(boxMesh(8, 8, 8, 1.0, 1.0, 1.0, 12), w.addMaterial(m));
    for (std::size_t i = 0; i < w.pos.size(); ++i) {
        w.pos[i] += 1e-3 * ((i * 2654435761u) % 1000 / 1000.0 - 0.5);
        w.vel[i] = 1e-3 * ((i * 40503u) % 1000 / 1000.0 - 0.5);
    }
    const ElementParams p{m.lambda(), m.mu(), m.beta()};
    const SaintVenantKirchhoff svk(m.lambda(), m.mu());
    const StableNeoHookean snh(m.lambda(), m.mu());
    std::vector<double> f(w.pos.size(), 0.0);
    Stats s[2][2];  // [law][viscous]
    for (int r = 0; r < rounds; ++r) {
        s[0][1].v.push_back(timeKernel<SaintVenantKirchhoff, true>(svk, w, p, f));
        s[1][1].v.push_back(timeKernel<StableNeoHookean, true>(snh, w, p, f));
        s[0][0].v.push_back(timeKernel<SaintVenantKirchhoff, false>(svk, w, p, f));
        s[1][0].v.push_back(timeKernel<StableNeoHookean, false>(snh, w, p, f));
    }
    std::printf("{\"tets\": %zu, \"rounds\": %d, \"kernel_ns_per_tet\": {", w.nTets(), rounds);
    const char* names[2] = {"saintVenantKirchhoff", "stableNeoHookean"};
    for (int l = 0; l < 2; ++l)
        std::printf("%s\"%s\": {\"viscous\": {\"min\": %.3f, \"median\": %.3f}, \"elastic\": {\"min\": %.3f, "
                    "\"median\": %.3f}}",
                    l ? ", " : "", names[l], s[l][1].min(), s[l][1].median(), s[l][0].min(), s[l][0].median());
    std::printf("}, \"snh_over_svk\": {\"viscous_min\": %.3f, \"viscous_median\": %.3f, \"elastic_min\": %.3f, "
                "\"elastic_median\": %.3f}, \"sink\": %g}\n",
                s[1][1].min() / s[0][1].min(), s[1][1].median() / s[0][1].median(), s[1][0].min() / s[0][0].min(),
                s[1][0].median() / s[0][0].median(), sink);
    return 0;
}
