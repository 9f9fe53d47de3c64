// Where the element phase's time goes: the element kernel taken apart into
// its gather (node positions and velocities into lanes, NodeGather.hpp), its
// arithmetic (elementLanes, ElementKernel.hpp) and its force scatter
// (scatterForces), each timed alone and in the combinations the phase runs,
// on one thread.  Two data sets: the seed's Figure 6 mesh (27 Hilbert-ordered
// cubes, 165,888 tets, as qdem.addPiece builds them: ~22 MB, in L3) walked
// block after block as the element phase walks it, and its first 8 blocks
// walked over and over (node data and blocks in L1), so that memory drops out.
//
//   element_parts [--rounds 7] [--passes 20] [--laws svk,snh] [--modes viscous,elastic]
//
// Every variant is one pass (or --passes passes, the best kept) over the
// blocks; the variants are interleaved round after round so that machine
// noise hits all alike.  Time: the thread's CPU time (CLOCK_THREAD_CPUTIME_ID:
// what the thread held the core for; wall clock alongside).  JSON on stdout:
// per law, mode and variant, ns per tet, min / median / max over the rounds,
// the load average before and after, and the parts derived from the L1 times:
//   gather  = (gather + arithmetic + scatter) - (arithmetic + scatter)
//   scatter = (gather + arithmetic + scatter) - (gather + arithmetic)
//   memory  = whole mesh - the same work in L1
// The integration phase is not here (bench_elements times it).
#include <omp.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "BenchArgs.hpp"
#include "BenchStats.hpp"
#include "MachineLoad.hpp"
#include "element/ElementKernel.hpp"
#include "element/MaterialLaw.hpp"
#include "mesh/BoxMesh.hpp"
#include "mesh/Hilbert.hpp"
#include "world/World.hpp"

using namespace qdem;

namespace {

double cpuSeconds() {
    timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

double sink = 0;  // keeps every variant's results alive

using Blocks = std::vector<TetBlock, AlignedAllocator<TetBlock>>;
using Forces = std::vector<double, AlignedAllocator<double>>;

// The arithmetic alone, as a call per block like elementBlock (not inlined
// into the timing loop, so that it is compiled as the element phase runs it).
template <class Law, bool Viscous>
__attribute__((noinline)) void lanesOnly(const Law& law, const TetBlock& b, const double (&dx)[3][3][kLanes],
                                         const double (&dv)[3][3][kLanes], const ElementParams& p, BatchOut& out) {
    elementLanes<Law, Viscous, false>(law, b, dx, dv, p, out);
}

// The gather alone, into lane arrays the caller keeps (as elementBlock
// gathers: plain loads where no corner is the arrays' last node).
template <bool Viscous>
__attribute__((noinline)) void gatherOnly(const TetBlock& b, const double* X, const double* V, int32_t last,
                                          double (&dx)[3][3][kLanes], double (&dv)[3][3][kLanes]) {
    gatherBlockEdges<Viscous>(X, V, last, b.node, dx, dv);
}

enum Variant { kWhole, kGatherArith, kArithScatter, kArith, kGather, kScatter, kNVariants };
const char* kVariantName[kNVariants] = {"gather+arithmetic+scatter", "gather+arithmetic", "arithmetic+scatter",
                                        "arithmetic", "gather", "scatter"};

struct Scene {
    World w;
    Blocks blocks;  // every tet, in the element phase's order
    Blocks l1;      // the first 8 blocks
    Forces buf;     // force buffer, kForceStride doubles per node
};

// As qdem.addPiece(boxMesh((1,1,1), (8,8,8), 12), mat, pos=...) places each
// cube (bench_elements.cpp does the same): Hilbert-reordered, then translated.
std::unique_ptr<Scene> makeScene(MaterialLaw law) {
    auto s = std::make_unique<Scene>();
    World& w = s->w;
    Material m;
    m.law = law;
    const int mat = w.addMaterial(m);
    TetMesh cube = boxMesh(8, 8, 8, 1.0, 1.0, 1.0, 12);
    hilbertReorder(cube);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) {
                TetMesh c = cube;
                for (std::size_t n = 0; n < c.nNodes(); ++n) {
                    c.nodes[3 * n] += 1.1 * i;
                    c.nodes[3 * n + 1] += 1.1 * j;
                    c.nodes[3 * n + 2] += 1.1 * k;
                }
                w.addPiece(c, mat);
            }
    // Deformed a little and moving, so that no lane computes zeros.
    for (std::size_t i = 0; i < w.pos.size(); ++i) {
        w.pos[i] += 1e-3 * ((i * 40503u) % 1000 / 1000.0 - 0.5);
        w.vel[i] = 1e-3 * ((i * 2654435761u) % 1000 / 1000.0 - 0.5);
    }
    const auto T = static_cast<int32_t>(w.nTets());
    for (int32_t e0 = 0; e0 < T; e0 += kLanes) {
        TetBlock b;
        fillTetBlock(b, e0, std::min<int32_t>(kLanes, T - e0), w.tetNodes.data(), w.tetB.data(), w.tetVol0.data());
        s->blocks.push_back(b);
    }
    s->l1.assign(s->blocks.begin(), s->blocks.begin() + 8);
    s->buf.assign(kForceStride * w.nNodes() + kForceStride, 0.0);
    return s;
}

// One pass of variant v over blocks; ns per tet of (cpu, wall).
template <class Law, bool Viscous>
void pass(const Law& law, const Scene& s, const Blocks& blocks, std::size_t nBlocks, Variant v, Forces& buf,
          double& cpuNs, double& wallNs) {
    const ElementParams p{s.w.materials[0].lambda(), s.w.materials[0].mu(), Viscous ? s.w.materials[0].beta() : 0.0};
    const double* X = s.w.pos.data();
    const double* V = s.w.vel.data();
    const auto last = static_cast<int32_t>(s.w.nNodes()) - 1;
    BatchOut out{};
    alignas(64) double dx[3][3][kLanes], dv[3][3][kLanes];
    gatherOnly<true>(blocks[0], X, V, last, dx, dv);  // edges for the variants without gather
    lanesOnly<Law, Viscous>(law, blocks[0], dx, dv, p, out);  // forces for the scatter alone
    const std::size_t mask = blocks.size() - 1;  // blocks.size(): a power of two, or all of them
    const bool all = nBlocks == blocks.size();
    std::fill(buf.begin(), buf.end(), 0.0);
    const double c0 = cpuSeconds(), w0 = omp_get_wtime();
    for (std::size_t i = 0; i < nBlocks; ++i) {
        const TetBlock& b = blocks[all ? i : (i & mask)];
        switch (v) {
            case kWhole:
                elementBlock<Law, Viscous, false>(law, b, X, V, last, p, out);
                scatterForces(out.f, b.node, kLanes, buf.data(), 0);
                break;
            case kGatherArith:
                elementBlock<Law, Viscous, false>(law, b, X, V, last, p, out);
                sink += out.f[1][2][i & 7];
                break;
            case kArithScatter:
                lanesOnly<Law, Viscous>(law, b, dx, dv, p, out);
                scatterForces(out.f, b.node, kLanes, buf.data(), 0);
                break;
            case kArith:
                lanesOnly<Law, Viscous>(law, b, dx, dv, p, out);
                sink += out.f[1][2][i & 7];
                break;
            case kGather:
                gatherOnly<Viscous>(b, X, V, last, dx, dv);
                sink += dx[1][2][i & 7];
                break;
            case kScatter:
                scatterForces(out.f, b.node, kLanes, buf.data(), 0);
                break;
            default:
                break;
        }
    }
    const double c1 = cpuSeconds(), w1 = omp_get_wtime();
    sink += buf[5];
    const double tets = static_cast<double>(nBlocks) * kLanes;
    cpuNs = 1e9 * (c1 - c0) / tets;
    wallNs = 1e9 * (w1 - w0) / tets;
}

struct Options {
    int rounds = 7, passes = 20;
    std::vector<MaterialLaw> laws{MaterialLaw::SaintVenantKirchhoff, MaterialLaw::StableNeoHookean};
    std::vector<bool> viscous{true, false};
};

[[noreturn]] void usage(const std::string& why) {
    std::fprintf(stderr,
                 "element_parts: %s\nusage: element_parts [--rounds 7] [--passes 20] [--laws svk,snh] "
                 "[--modes viscous,elastic]\n",
                 why.c_str());
    std::exit(2);
}

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) usage("option " + a + " needs a value");
        const std::string v = argv[++i];
        if (a == "--rounds") o.rounds = std::atoi(v.c_str());
        else if (a == "--passes") o.passes = std::atoi(v.c_str());
        else if (a == "--laws") o.laws = bench::lawsFrom(v, usage);
        else if (a == "--modes") o.viscous = bench::modesFrom(v, usage);
        else usage("unknown option " + a);
    }
    if (o.rounds < 1 || o.passes < 1) usage("--rounds and --passes must be at least 1");
    if (o.laws.empty() || o.viscous.empty()) usage("--laws and --modes need at least one value");
    return o;
}

struct Case {
    MaterialLaw law;
    bool viscous;
    Stats cpu[2][kNVariants], wall[2][kNVariants];  // [mesh, L1][variant]
};

template <class Law>
void runCase(const Law& law, const Scene& s, Forces& buf, Case& c, int passes) {
    for (int where = 0; where < 2; ++where) {
        const Blocks& blocks = where == 0 ? s.blocks : s.l1;
        // The L1 walk does as many blocks as the mesh walk.
        const std::size_t n = s.blocks.size();
        for (int v = 0; v < kNVariants; ++v) {
            double bestCpu = 1e300, bestWall = 1e300;
            for (int r = 0; r < passes; ++r) {
                double cn, wn;
                if (c.viscous) pass<Law, true>(law, s, blocks, n, static_cast<Variant>(v), buf, cn, wn);
                else pass<Law, false>(law, s, blocks, n, static_cast<Variant>(v), buf, cn, wn);
                bestCpu = std::min(bestCpu, cn), bestWall = std::min(bestWall, wn);
            }
            c.cpu[where][v].v.push_back(bestCpu);
            c.wall[where][v].v.push_back(bestWall);
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    const Options o = parse(argc, argv);
    omp_set_num_threads(1);
    std::vector<Case> cases;
    std::vector<std::unique_ptr<Scene>> scenes;
    for (MaterialLaw l : o.laws) {
        scenes.push_back(makeScene(l));
        for (bool v : o.viscous) cases.push_back(Case{l, v, {}, {}});
    }
    const double load0 = bench::loadAverage1();
    for (int r = 0; r < o.rounds; ++r) {
        std::size_t si = 0;
        for (Case& c : cases) {
            while (scenes[si]->w.materials[0].law != c.law) ++si;
            Scene& s = *scenes[si];
            Forces& buf = s.buf;
            withLaw(s.w.materials[0], [&](const auto& law) { runCase(law, s, buf, c, o.passes); });
            si = 0;
        }
        std::fprintf(stderr, "element_parts: round %d/%d done (load %.2f)\n", r + 1, o.rounds, bench::loadAverage1());
    }
    const double load1 = bench::loadAverage1();
    const Scene& s0 = *scenes[0];
    std::printf("{\n  \"benchmark\": \"element_parts\",\n  \"date\": \"%s\",\n", bench::isoNow().c_str());
    std::printf("  \"tets\": %zu, \"nodes\": %zu, \"threads\": 1, \"rounds\": %d, \"passes_per_round\": %d,\n",
                s0.w.nTets(), s0.w.nNodes(), o.rounds, o.passes);
    std::printf("  \"load1_before\": %.2f, \"load1_after\": %.2f,\n", load0, load1);
    std::printf("  \"unit\": \"ns per tet, best of the passes in each round; min / median / max over the rounds\",\n");
    std::printf("  \"cases\": [\n");
    for (std::size_t ci = 0; ci < cases.size(); ++ci) {
        const Case& c = cases[ci];
        std::printf("    {\"law\": \"%s\", \"mode\": \"%s\",\n", c.law == MaterialLaw::SaintVenantKirchhoff ? "SVK" : "SNH", c.viscous ? "viscous" : "elastic");
        for (int where = 0; where < 2; ++where) {
            std::printf("     \"%s\": {", where == 0 ? "mesh" : "l1");
            for (int v = 0; v < kNVariants; ++v)
                std::printf("%s\n       \"%s\": {\"cpu\": %s, \"wall\": %s}", v ? "," : "", kVariantName[v],
                            c.cpu[where][v].json().c_str(), c.wall[where][v].json().c_str());
            std::printf("},\n");
        }
        const auto med = [&](int where, int v) { return c.cpu[where][v].median(); };
        std::printf("     \"derived_cpu_median\": {\"gather\": %.3f, \"scatter\": %.3f, \"arithmetic\": %.3f, "
                    "\"memory\": %.3f, \"whole_mesh\": %.3f}}%s\n",
                    med(1, kWhole) - med(1, kArithScatter), med(1, kWhole) - med(1, kGatherArith), med(1, kArith),
                    med(0, kWhole) - med(1, kWhole), med(0, kWhole), ci + 1 < cases.size() ? "," : "");
    }
    std::printf("  ],\n  \"sink\": %.6g\n}\n", sink);
    return 0;
}
