// The partition half of the MPI scaling model (doc/parallel_scaling.md): the real
// partitioner (pkg/parallel/Partition.hpp) run for P ranks on one core, on
// synthetic scenes of about `nodesPerRank` nodes per rank, for the Hilbert
// split and, for comparison, slabs along the longest axis.  Per P and method:
// weight imbalance (max / mean), halo size over owned nodes (mean, max over
// ranks), neighbours, bytes each rank sends and receives per step (forward:
// position and velocity, 6 doubles per ghost; reverse: the ghost's partial
// force, 3 doubles) and the pieces split.  No MPI and no World: raw arrays,
// nodes replicated as every rank will hold them at set-up.
//
// Scenes (mpi_scenes.hpp): pieces (a heap of shogi-size boxes), body (one
// block), mixed (a block, the pieces on top).
// The contact halo reaches `reach` (default 1 mm: one contact cell plus the
// skin), so neighbouring pieces of other ranks are ghosts.
//
// At more than `sample` ranks the halos are computed for `sample` ranks
// spread evenly (each of them exact: haloOf); the JSON says which.  The
// partition itself always covers every rank.  Default: P = 1, 2, 4, ..., 128
// (6.4 million nodes at 128): about a minute and 2 GB on the development
// machine, most of it building the scenes and partitioning 6 million nodes.
//
//   mpi_partition_model [--quick] [--out PATH] [--max-ranks P] [--nodes-per-rank N]
//                       [--reach M] [--sample S]
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "mpi_scenes.hpp"

using namespace qdem;
using namespace mpibench;

namespace {

struct Row {
    std::string scene, method;
    int P;
    int64_t nodes, tets, pieces;
    double imbalance;
    int32_t split;
    int sampled;
    double haloMean, haloMax, nbrMean;
    int nbrMax;
    double sendMean, sendMax, recvMax;  // bytes per step per rank
    double partSeconds, haloSeconds;
};

std::vector<int> sampleRanks(int P, int sample) {
    std::vector<int> r;
    if (P <= sample) {
        for (int i = 0; i < P; ++i) r.push_back(i);
        return r;
    }
    for (int i = 0; i < sample; ++i) r.push_back(int((int64_t(i) * (P - 1)) / (sample - 1)));
    r.erase(std::unique(r.begin(), r.end()), r.end());
    return r;
}

Row measure(const RawScene& s, const std::string& scene, const std::string& method, int P, double reach, int sample) {
    const PartitionInput in = s.input();
    PartitionOptions opt;
    opt.nRanks = P;
    double t0 = omp_get_wtime();
    const Partition p = method == "hilbert" ? partitionHilbert(in, opt) : partitionSlabs(in, opt);
    const double tPart = omp_get_wtime() - t0;
    t0 = omp_get_wtime();
    const std::vector<int> ranks = sampleRanks(P, sample);
    const std::vector<Halo> hs = haloOf(p, in, s.surf.data(), static_cast<int32_t>(s.surf.size()), reach, ranks);
    const double tHalo = omp_get_wtime() - t0;

    Row row{scene, method, P, in.nNodes, in.nTets, in.nPieces, p.imbalance(), countSplitPieces(p, in),
            static_cast<int>(ranks.size()), 0, 0, 0, 0, 0, 0, 0, tPart, tHalo};
    const HaloFigures f = haloFigures(hs);
    row.haloMean = f.haloMean, row.haloMax = f.haloMax, row.nbrMean = f.nbrMean, row.nbrMax = f.nbrMax;
    row.sendMean = f.sendMean, row.sendMax = f.sendMax, row.recvMax = f.recvMax;
    return row;
}

}  // namespace

int main(int argc, char** argv) {
    std::string out = "out/bench/mpi_partition.json";
    bool quick = false;
    int maxRanks = 128, sample = 32;
    int64_t nodesPerRank = 50000;
    double reach = 0.001;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> const char* {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "%s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--quick") quick = true;
        else if (a == "--out") out = next();
        else if (a == "--max-ranks") maxRanks = std::atoi(next());
        else if (a == "--nodes-per-rank") nodesPerRank = std::atoll(next());
        else if (a == "--reach") reach = std::atof(next());
        else if (a == "--sample") sample = std::max(2, std::atoi(next()));
        else {
            std::fprintf(stderr, "unknown argument %s\n", a.c_str());
            return 2;
        }
    }
    if (quick) maxRanks = std::min(maxRanks, 4), nodesPerRank = std::min<int64_t>(nodesPerRank, 5000);

    std::vector<Row> rows;
    const double t0 = omp_get_wtime();
    std::printf("%-7s %-8s %5s %9s %6s %8s %6s %8s %8s %6s %6s %10s %10s %6s %6s\n", "scene", "method", "P", "nodes",
                "pieces", "imbal", "split", "haloAvg", "haloMax", "nbrAvg", "nbrMax", "sendAvgB", "sendMaxB", "tPart",
                "tHalo");
    for (const char* scene : {"pieces", "body", "mixed"}) {
        for (int P = 1; P <= maxRanks; P *= 2) {
            const double tb = omp_get_wtime();
            const RawScene s = makeScene(scene, P, nodesPerRank);
            std::printf("%-7s (scene of %d ranks built in %.2f s)\n", scene, P, omp_get_wtime() - tb);
            for (const char* method : {"hilbert", "slabs"}) {
                const Row r = measure(s, scene, method, P, reach, sample);
                rows.push_back(r);
                std::printf("%-7s %-8s %5d %9lld %6lld %8.4f %6d %8.4f %8.4f %6.1f %6d %10.0f %10.0f %6.2f %6.2f\n",
                            r.scene.c_str(), r.method.c_str(), r.P, (long long)r.nodes, (long long)r.pieces,
                            r.imbalance, r.split, r.haloMean, r.haloMax, r.nbrMean, r.nbrMax, r.sendMean, r.sendMax,
                            r.partSeconds, r.haloSeconds);
                std::fflush(stdout);
            }
        }
    }
    const double total = omp_get_wtime() - t0;
    std::printf("total %.1f s\n", total);

    const std::filesystem::path path(out);
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    FILE* f = std::fopen(out.c_str(), "w");
    if (!f) {
        std::fprintf(stderr, "cannot write %s\n", out.c_str());
        return 1;
    }
    std::fprintf(f,
                 "{\"nodes_per_rank\": %lld, \"contact_reach_m\": %g, \"quick\": %s, \"halo_sample_ranks\": %d,\n"
                 " \"notes\": \"halo figures over all ranks when P <= halo_sample_ranks, else over that many ranks "
                 "spread evenly (each halo exact); halo = ghosts / owned nodes; bytes per step per rank: forward 6 "
                 "doubles per ghost (position, velocity), reverse 3 (partial force); send = 48 * sent nodes + 24 * "
                 "ghosts\",\n \"seconds\": %.2f,\n \"rows\": [\n",
                 (long long)nodesPerRank, reach, quick ? "true" : "false", sample, total);
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const Row& r = rows[i];
        std::fprintf(f,
                     "  {\"scene\": \"%s\", \"method\": \"%s\", \"ranks\": %d, \"nodes\": %lld, \"tets\": %lld, "
                     "\"pieces\": %lld, \"imbalance\": %.5f, \"pieces_split\": %d, \"halo_ranks\": %d, "
                     "\"halo_over_owned_mean\": %.5f, \"halo_over_owned_max\": %.5f, \"neighbours_mean\": %.2f, "
                     "\"neighbours_max\": %d, \"bytes_sent_per_step_mean\": %.0f, \"bytes_sent_per_step_max\": %.0f, "
                     "\"bytes_received_per_step_max\": %.0f, \"partition_seconds\": %.3f, \"halo_seconds\": %.3f}%s\n",
                     r.scene.c_str(), r.method.c_str(), r.P, (long long)r.nodes, (long long)r.tets,
                     (long long)r.pieces, r.imbalance, r.split, r.sampled, r.haloMean, r.haloMax, r.nbrMean, r.nbrMax,
                     r.sendMean, r.sendMax, r.recvMax, r.partSeconds, r.haloSeconds, i + 1 < rows.size() ? "," : "");
    }
    std::fprintf(f, " ]}\n");
    std::fclose(f);
    std::printf("wrote %s\n", out.c_str());
    return 0;
}
