// Element + integration cost, and the whole step, on the seed paper's Figure 6
// mesh (27 cubes of 8x8x8 cells, 12 tets per cell: 165,888 tets, 33,507
// nodes) and on a larger stack of the same cubes (6x6x6 cubes: 1,327,104
// tets, out of L3), built as users get them: each cube is Hilbert-reordered
// before it is placed, exactly as qdem.addPiece does (py/qdem/world.py).
//
// For each mesh size, both material laws (Saint-Venant-Kirchhoff and the
// default Stable Neo-Hookean), elastic only and viscous (Table 1), on 1 and
// 2 threads; every combination is one run of `steps` steps, and the runs are
// interleaved (round after round) so that machine noise hits all alike.  With
// each run it records the 1-minute load average and the CPU other processes
// used meanwhile (MachineLoad.hpp); busy runs are flagged and left out of
// min / median / max ("clean"), which are printed beside those of all runs.
//
//   bench_elements [--steps 200] [--cubes 3,6] [--repeats 5] [--threads 1,2]
//                  [--laws svk,snh] [--modes viscous,elastic]
//                  [--max-others 0.2] [--label NAME]
//   bench_elements [steps] [cubesPerAxis] [repeats]      (the older form)
//
// --steps is for the 27-cube mesh; larger meshes run fewer steps so that each
// run does the same number of tet-steps (at least 10 steps).  JSON on stdout;
// one line per run on stderr as it goes.
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "BenchArgs.hpp"
#include "BenchStats.hpp"
#include "MachineLoad.hpp"
#include "mesh/BoxMesh.hpp"
#include "mesh/Hilbert.hpp"
#include "world/World.hpp"

using namespace qdem;

namespace {

struct Options {
    int steps = 200, repeats = 5;
    std::vector<int> cubes{3, 6}, threads{1, 2};
    std::vector<MaterialLaw> laws{MaterialLaw::SaintVenantKirchhoff, MaterialLaw::StableNeoHookean};
    std::vector<bool> viscous{true, false};
    bench::BusyRule rule;
    std::string label;
};

[[noreturn]] void usage(const std::string& why) {
    std::fprintf(stderr,
                 "bench_elements: %s\nusage: bench_elements [--steps N] [--cubes 3,6] [--repeats N] [--threads 1,2] "
                 "[--laws svk,snh] [--modes viscous,elastic] [--max-others C] [--label NAME]\n",
                 why.c_str());
    std::exit(2);
}

int positive(const std::string& s, const char* what) {
    char* end = nullptr;
    const long v = std::strtol(s.c_str(), &end, 10);
    if (end == s.c_str() || *end || v < 1 || v > 100000) usage(std::string(what) + " must be a positive integer, got '" + s + "'");
    return int(v);
}

Options parse(int argc, char** argv) {
    Options o;
    int positional = 0;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a.rfind("--", 0) != 0) {  // the older positional form: steps cubes repeats
            if (positional == 0) o.steps = positive(a, "steps");
            else if (positional == 1) o.cubes = {positive(a, "cubesPerAxis")};
            else if (positional == 2) o.repeats = positive(a, "repeats");
            else usage("too many arguments");
            ++positional;
            continue;
        }
        if (i + 1 >= argc) usage(a + " needs a value");
        const std::string v = argv[++i];
        if (a == "--steps") o.steps = positive(v, "--steps");
        else if (a == "--repeats") o.repeats = positive(v, "--repeats");
        else if (a == "--cubes" || a == "--threads") {
            std::vector<int> xs;
            for (const auto& s : bench::splitList(v)) xs.push_back(positive(s, a.c_str()));
            if (xs.empty()) usage(a + " needs at least one value");
            (a == "--cubes" ? o.cubes : o.threads) = xs;
        } else if (a == "--laws") o.laws = bench::lawsFrom(v, usage);
        else if (a == "--modes") o.viscous = bench::modesFrom(v, usage);
        else if (a == "--max-others") o.rule.maxOthers = std::atof(v.c_str());
        else if (a == "--label") o.label = v;
        else usage("unknown option " + a);
    }
    if (o.laws.empty() || o.viscous.empty()) usage("--laws and --modes need at least one value");
    if (o.laws.size() > 2 || o.viscous.size() > 2 || o.threads.size() > 8) usage("at most 2 laws, 2 modes, 8 thread counts");
    return o;
}

// As qdem.addPiece(boxMesh((1,1,1), (8,8,8), 12), mat, pos=...) places each
// cube: the mesh is Hilbert-reordered in its own frame, then translated (all
// cubes alike, so the reordering is done once).
std::unique_ptr<World> makeScene(int cubesPerAxis, MaterialLaw law) {
    auto wp = std::make_unique<World>();  // by pointer: a World is neither copied nor moved
    World& w = *wp;
    Material m;  // seed Table 1
    m.law = law;
    const int mat = w.addMaterial(m);
    const double size = 1.0, gap = 0.1;  // 0.1 > 2 r: no contacts, the element phase alone
    TetMesh cube = boxMesh(8, 8, 8, size, size, size, 12);
    hilbertReorder(cube);
    for (int i = 0; i < cubesPerAxis; ++i)
        for (int j = 0; j < cubesPerAxis; ++j)
            for (int k = 0; k < cubesPerAxis; ++k) {
                TetMesh c = cube;
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

struct Run {
    double stepNs, elementNs, integrateNs, load1, ownLoad, others, cpuStepNs;
    bool busy;
};

Run run(World& w, int threads, int steps, bool viscous, const bench::BusyRule& rule) {
    omp_set_num_threads(threads);
    w.settings.viscosityOn = viscous;
    const double dt = 0.5 * w.stableDt().combined;
    for (int i = 0; i < 3; ++i) w.step(dt);  // warm-up: the thread layout, the caches
    double el = 0, in = 0;
    const bench::LoadProbe probe;
    const double t0 = omp_get_wtime();
    for (int i = 0; i < steps; ++i) {
        w.step(dt);
        const PhaseReport r = w.report();
        el += r.second("elements");
        in += r.second("integrate");
    }
    const double wall = omp_get_wtime() - t0;
    const double others = probe.othersCores(wall);
    // The step on CPU: this process's CPU time over the threads (waiting
    // threads sleep: OMP_WAIT_POLICY=passive), what the step costs while its
    // threads hold cores; on a time-shared machine the wall time is longer.
    const double cpu = (bench::ownCpuSeconds() - probe.own0) / threads;
    const double perTetStep = 1e9 / (double(steps) * double(w.nTets()));
    return {wall * perTetStep, el * perTetStep, in * perTetStep, probe.load1, probe.own, others, cpu * perTetStep,
            rule.busy(probe, others)};
}

const char* shortName(MaterialLaw l) { return l == MaterialLaw::SaintVenantKirchhoff ? "svk" : "snh"; }

}  // namespace

int main(int argc, char** argv) {
    const Options o = parse(argc, argv);
    const std::string date = bench::isoNow();
    std::printf("{\"benchmark\": \"bench_elements\", \"label\": \"%s\", \"date\": \"%s\", \"cpus\": %d, "
                "\"repeats\": %d, \"busy_rule\": {\"max_other_cores\": %g}, "
                "\"units\": \"ns per tet per step\", \"meshes\": [",
                o.label.c_str(), date.c_str(), omp_get_num_procs(), o.repeats, o.rule.maxOthers);
    const std::size_t smallTets = 27 * 6144;
    for (std::size_t mi = 0; mi < o.cubes.size(); ++mi) {
        const int cubes = o.cubes[mi];
        std::vector<std::unique_ptr<World>> worlds;
        for (MaterialLaw l : o.laws) worlds.push_back(makeScene(cubes, l));
        const std::size_t tets = worlds[0]->nTets();
        const int steps = std::max(10, int(double(o.steps) * double(smallTets) / double(tets) + 0.5));
        // cases[law][mode][thread]: one entry per run
        const std::size_t nl = o.laws.size(), nm = o.viscous.size(), nt = o.threads.size();
        std::vector<Run> runs[2][2][8];
        for (int r = 0; r < o.repeats; ++r)
            for (std::size_t t = 0; t < nt; ++t)
                for (std::size_t l = 0; l < nl; ++l)
                    for (std::size_t m = 0; m < nm; ++m) {
                        const Run x = run(*worlds[l], o.threads[t], steps, o.viscous[m], o.rule);
                        runs[l][m][t].push_back(x);
                        std::fprintf(stderr,
                                     "bench_elements %zu tets, %s %s, %d thread(s), round %d: step %.2f, element "
                                     "%.2f, integrate %.2f ns/tet (step on CPU %.2f); load %.2f (own %.2f), others %.2f cores%s\n",
                                     tets, shortName(o.laws[l]), o.viscous[m] ? "viscous" : "elastic", o.threads[t],
                                     r, x.stepNs, x.elementNs, x.integrateNs, x.cpuStepNs, x.load1, x.ownLoad, x.others,
                                     x.busy ? " BUSY (excluded)" : "");
                    }
        std::printf("%s{\"cubes_per_axis\": %d, \"tets\": %zu, \"nodes\": %zu, \"steps\": %d, \"cases\": [",
                    mi ? ", " : "", cubes, tets, worlds[0]->nNodes(), steps);
        bool first = true;
        for (std::size_t l = 0; l < nl; ++l)
            for (std::size_t m = 0; m < nm; ++m)
                for (std::size_t t = 0; t < nt; ++t) {
                    const std::vector<Run>& rs = runs[l][m][t];
                    Stats step, elInt, el, stepAll, elIntAll, elAll, cpu, cpuAll;
                    std::string list;
                    for (const Run& x : rs) {
                        char b[256];
                        std::snprintf(b, sizeof b,
                                      "%s{\"step\": %.3f, \"step_on_cpu\": %.3f, \"element\": %.3f, \"integrate\": %.3f, \"load1\": %.2f, "
                                      "\"own_load\": %.2f, \"other_cores\": %.2f, \"busy\": %s}",
                                      list.empty() ? "" : ", ", x.stepNs, x.cpuStepNs, x.elementNs, x.integrateNs, x.load1,
                                      x.ownLoad, x.others, x.busy ? "true" : "false");
                        list += b;
                        stepAll.v.push_back(x.stepNs);
                        elIntAll.v.push_back(x.elementNs + x.integrateNs);
                        elAll.v.push_back(x.elementNs);
                        cpuAll.v.push_back(x.cpuStepNs);
                        if (x.busy) continue;
                        cpu.v.push_back(x.cpuStepNs);
                        step.v.push_back(x.stepNs);
                        elInt.v.push_back(x.elementNs + x.integrateNs);
                        el.v.push_back(x.elementNs);
                    }
                    std::printf("%s{\"law\": \"%s\", \"mode\": \"%s\", \"threads\": %d, "
                                "\"clean\": {\"whole_step\": %s, \"element_integrate\": %s, \"element\": %s, "
                                "\"whole_step_on_cpu\": %s}, "
                                "\"all\": {\"whole_step\": %s, \"element_integrate\": %s, \"element\": %s, "
                                "\"whole_step_on_cpu\": %s}, "
                                "\"runs\": [%s]}",
                                first ? "" : ", ", lawName(o.laws[l]), o.viscous[m] ? "viscous" : "elastic",
                                o.threads[t], step.json().c_str(), elInt.json().c_str(), el.json().c_str(), cpu.json().c_str(),
                                stepAll.json().c_str(), elIntAll.json().c_str(), elAll.json().c_str(),
                                cpuAll.json().c_str(), list.c_str());
                    first = false;
                }
        std::printf("]}");
        std::fflush(stdout);
    }
    std::printf("]}\n");
    return 0;
}
