// Our Hilbert split (pkg/parallel/Partition.hpp) against Zoltan's geometric
// partitioners, on the scenes of the partition model (mpi_scenes.hpp), for
// doc/parallel_scaling.md.  Zoltan runs on one MPI process and cuts the nodes into
// P parts (NUM_GLOBAL_PARTS); each method's node owners then go through the
// same code as ours: a tet is computed by the lowest owner of its nodes, and
// the halos come from haloAll, so every figure is measured the same way.
//
// Methods:
//   hilbert      ours (partitionHilbert, default options)
//   hilbert-split  ours with no piece kept whole (wholePieceFraction = 0):
//                like for like with zoltan-hsfc, which does not know pieces
//   zoltan-hsfc  Zoltan's Hilbert space-filling curve (LB_METHOD=HSFC) on
//                the nodes, each weighing a quarter of its tets
//   zoltan-rcb   Zoltan's recursive coordinate bisection (LB_METHOD=RCB),
//                the same objects
//   zoltan-hsfc-whole  HSFC where each piece that ours keeps whole (at most
//                half a rank's share) is one object at its centroid, weighing
//                its tets: what we would hand Zoltan if we switched
// Node weights are a quarter of the node's tets, not ours (each tet on its
// node first along our curve): that rule needs our curve's order, which
// Zoltan's curve does not share.  Partition time: weights, the Zoltan call
// (callbacks included) and the tet owners; Zoltan_Create and the parameters
// are outside it.
//
//   mpi_zoltan_compare [--quick] [--out PATH] [--max-ranks P] [--nodes-per-rank N]
//                      [--reach M] [--imbalance-tol T]
#include <mpi.h>
#include <omp.h>
#include <zoltan.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "mpi_scenes.hpp"

using namespace qdem;
using namespace mpibench;

namespace {

// What Zoltan partitions: points with a weight; each node is one of them.
struct Objects {
    std::vector<double> xyz;       // 3 per object
    std::vector<float> weight;     // 1 per object
    std::vector<int32_t> ofNode;   // per node: its object
};

std::vector<double> quarterTets(const PartitionInput& in) {
    std::vector<double> w(in.nNodes, 0.0);
    for (int64_t k = 0; k < 4 * int64_t(in.nTets); ++k) w[in.tetNodes[k]] += 0.25;
    return w;
}

// One object per node; or (wholeFraction > 0) one per piece of at most
// wholeFraction x a rank's share of tets, at its centroid, as ours keys it.
Objects makeObjects(const PartitionInput& in, int P, double wholeFraction) {
    const std::vector<double> w = quarterTets(in);
    Objects o;
    o.ofNode.assign(in.nNodes, -1);
    const double share = double(in.nTets) / P;
    for (int32_t q = 0; q < in.nPieces && wholeFraction > 0; ++q) {
        const int32_t b = in.pieceNodeBegin[q], e = in.pieceNodeBegin[q + 1];
        double pw = 0, c[3] = {0, 0, 0};
        for (int32_t n = b; n < e; ++n) {
            pw += w[n];
            for (int d = 0; d < 3; ++d) c[d] += in.pos[3 * n + d];
        }
        if (e <= b || pw > wholeFraction * share) continue;
        const int32_t id = static_cast<int32_t>(o.weight.size());
        for (int d = 0; d < 3; ++d) o.xyz.push_back(c[d] / (e - b));
        o.weight.push_back(static_cast<float>(pw));
        for (int32_t n = b; n < e; ++n) o.ofNode[n] = id;
    }
    for (int32_t n = 0; n < in.nNodes; ++n) {
        if (o.ofNode[n] >= 0) continue;
        o.ofNode[n] = static_cast<int32_t>(o.weight.size());
        for (int d = 0; d < 3; ++d) o.xyz.push_back(in.pos[3 * n + d]);
        o.weight.push_back(static_cast<float>(w[n]));
    }
    return o;
}

// Zoltan's query callbacks: all objects live on this one process; global
// and local id are both the object's index.
int numObjects(void* data, int* ierr) {
    *ierr = ZOLTAN_OK;
    return static_cast<int>(static_cast<const Objects*>(data)->weight.size());
}

void objectList(void* data, int, int, ZOLTAN_ID_PTR gids, ZOLTAN_ID_PTR lids, int wdim, float* wgts, int* ierr) {
    const Objects& o = *static_cast<const Objects*>(data);
    for (std::size_t i = 0; i < o.weight.size(); ++i) {
        gids[i] = lids[i] = static_cast<ZOLTAN_ID_TYPE>(i);
        if (wdim == 1) wgts[i] = o.weight[i];
    }
    *ierr = ZOLTAN_OK;
}

int numGeom(void*, int* ierr) {
    *ierr = ZOLTAN_OK;
    return 3;
}

void geomMulti(void* data, int, int, int nObj, ZOLTAN_ID_PTR gids, ZOLTAN_ID_PTR, int nDim, double* xyz, int* ierr) {
    const Objects& o = *static_cast<const Objects*>(data);
    for (int i = 0; i < nObj; ++i)
        for (int d = 0; d < nDim; ++d) xyz[i * nDim + d] = o.xyz[3 * gids[i] + d];
    *ierr = ZOLTAN_OK;
}

// Node owners from Zoltan: `method` is its LB_METHOD.  Objects not in the
// export list stay in part 0 (where this one process holds them all).
std::vector<int32_t> zoltanOwners(const PartitionInput& in, int P, const char* method, bool whole,
                                  const std::string& imbalanceTol) {
    const Objects o = makeObjects(in, P, whole ? PartitionOptions().wholePieceFraction : 0.0);
    Zoltan_Struct* zz = Zoltan_Create(MPI_COMM_WORLD);
    const std::string parts = std::to_string(P);
    Zoltan_Set_Param(zz, "DEBUG_LEVEL", "0");
    Zoltan_Set_Param(zz, "LB_METHOD", method);
    Zoltan_Set_Param(zz, "NUM_GID_ENTRIES", "1");
    Zoltan_Set_Param(zz, "NUM_LID_ENTRIES", "1");
    Zoltan_Set_Param(zz, "OBJ_WEIGHT_DIM", "1");
    Zoltan_Set_Param(zz, "NUM_GLOBAL_PARTS", parts.c_str());
    Zoltan_Set_Param(zz, "RETURN_LISTS", "PARTS");
    Zoltan_Set_Param(zz, "IMBALANCE_TOL", imbalanceTol.c_str());
    Zoltan_Set_Num_Obj_Fn(zz, numObjects, const_cast<Objects*>(&o));
    Zoltan_Set_Obj_List_Fn(zz, objectList, const_cast<Objects*>(&o));
    Zoltan_Set_Num_Geom_Fn(zz, numGeom, const_cast<Objects*>(&o));
    Zoltan_Set_Geom_Multi_Fn(zz, geomMulti, const_cast<Objects*>(&o));

    int changes = 0, nGid = 0, nLid = 0, nImport = 0, nExport = 0;
    ZOLTAN_ID_PTR impG = nullptr, impL = nullptr, expG = nullptr, expL = nullptr;
    int *impProc = nullptr, *impPart = nullptr, *expProc = nullptr, *expPart = nullptr;
    const int rc = Zoltan_LB_Partition(zz, &changes, &nGid, &nLid, &nImport, &impG, &impL, &impProc, &impPart,
                                       &nExport, &expG, &expL, &expProc, &expPart);
    if (rc != ZOLTAN_OK) {
        std::fprintf(stderr, "Zoltan %s failed (%d) at P = %d\n", method, rc, P);
        std::exit(1);
    }
    std::vector<int32_t> objPart(o.weight.size(), 0);
    for (int i = 0; i < nExport; ++i) objPart[expL[i]] = expPart[i];
    Zoltan_LB_Free_Part(&impG, &impL, &impProc, &impPart);
    Zoltan_LB_Free_Part(&expG, &expL, &expProc, &expPart);
    Zoltan_Destroy(&zz);

    std::vector<int32_t> owner(in.nNodes);
    for (int32_t n = 0; n < in.nNodes; ++n) owner[n] = objPart[o.ofNode[n]];
    return owner;
}

// A Partition from node owners, by the rule ours uses: a tet is computed by
// the lowest owner of its nodes, each rank weighs its tets.
Partition fromOwners(const PartitionInput& in, int P, std::vector<int32_t> owner) {
    Partition p;
    p.nRanks = P;
    p.nodeOwner = std::move(owner);
    p.tetOwner.resize(in.nTets);
    p.rankWeight.assign(P, 0.0);
    const int32_t* o = p.nodeOwner.data();
    for (int32_t t = 0; t < in.nTets; ++t) {
        const int32_t* tn = in.tetNodes + 4 * t;
        p.tetOwner[t] = std::min(std::min(o[tn[0]], o[tn[1]]), std::min(o[tn[2]], o[tn[3]]));
        p.rankWeight[p.tetOwner[t]] += 1;
    }
    p.keyStart.assign(P + 1, 0);  // no key ranges: diagnostics only
    return p;
}

// max / mean over ranks of the node weights (a quarter of each node's tets)
// they own: the balance Zoltan was asked for, before the tet-owner rule.
double quarterImbalance(const PartitionInput& in, const Partition& p) {
    const std::vector<double> w = quarterTets(in);
    std::vector<double> per(p.nRanks, 0.0);
    for (int32_t n = 0; n < in.nNodes; ++n) per[p.nodeOwner[n]] += w[n];
    double mx = 0, sum = 0;
    for (double v : per) mx = std::max(mx, v), sum += v;
    return sum > 0 ? mx / (sum / p.nRanks) : 1.0;
}

struct Row {
    std::string scene, method;
    int P = 0;
    int64_t nodes = 0, tets = 0, pieces = 0;
    double imbalance = 0, quarterImbalance = 0;
    int32_t split = 0;
    int emptyRanks = 0;
    HaloFigures halo;
    double partSeconds = 0, haloSeconds = 0;
};

Row measure(const RawScene& s, const std::string& scene, const std::string& method, int P, double reach,
            const std::string& imbalanceTol) {
    const PartitionInput in = s.input();
    double t0 = omp_get_wtime();
    Partition p;
    if (method == "hilbert" || method == "hilbert-split") {
        PartitionOptions opt;
        opt.nRanks = P;
        if (method == "hilbert-split") opt.wholePieceFraction = 0;
        p = partitionHilbert(in, opt);
    } else {
        const bool whole = method == "zoltan-hsfc-whole";
        const char* lb = method == "zoltan-rcb" ? "RCB" : "HSFC";
        p = fromOwners(in, P, zoltanOwners(in, P, lb, whole, imbalanceTol));
    }
    Row row;
    row.partSeconds = omp_get_wtime() - t0;
    t0 = omp_get_wtime();
    const std::vector<Halo> hs = haloAll(p, in, s.surf.data(), static_cast<int32_t>(s.surf.size()), reach);
    row.haloSeconds = omp_get_wtime() - t0;
    row.scene = scene, row.method = method, row.P = P;
    row.nodes = in.nNodes, row.tets = in.nTets, row.pieces = in.nPieces;
    row.imbalance = p.imbalance();
    row.quarterImbalance = quarterImbalance(in, p);
    row.split = countSplitPieces(p, in);
    for (double w : p.rankWeight) row.emptyRanks += w <= 0;
    row.halo = haloFigures(hs);
    return row;
}

void writeJson(const std::string& out, const std::vector<Row>& rows, long long nodesPerRank, double reach,
               bool quick, const std::string& imbalanceTol, double seconds) {
    const std::filesystem::path path(out);
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    FILE* f = std::fopen(out.c_str(), "w");
    if (!f) {
        std::fprintf(stderr, "cannot write %s\n", out.c_str());
        std::exit(1);
    }
    std::fprintf(f,
                 "{\"nodes_per_rank\": %lld, \"contact_reach_m\": %g, \"quick\": %s, \"zoltan_version\": %.2f, "
                 "\"zoltan_imbalance_tol\": %s,\n"
                 " \"notes\": \"node owners from each method; tets to the lowest owner of their nodes and halos from "
                 "haloAll for every method (all ranks); imbalance = max/mean tets per rank; quarter_imbalance = "
                 "max/mean of a quarter of each node's tets per rank (what Zoltan balances); halo = ghosts / owned "
                 "nodes; bytes per step per rank: send = 48 * sent nodes + 24 * ghosts\",\n \"seconds\": %.2f,\n"
                 " \"rows\": [\n",
                 nodesPerRank, reach, quick ? "true" : "false", double(ZOLTAN_VERSION_NUMBER), imbalanceTol.c_str(),
                 seconds);
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const Row& r = rows[i];
        const HaloFigures& h = r.halo;
        std::fprintf(f,
                     "  {\"scene\": \"%s\", \"method\": \"%s\", \"ranks\": %d, \"nodes\": %lld, \"tets\": %lld, "
                     "\"pieces\": %lld, \"imbalance\": %.5f, \"quarter_imbalance\": %.5f, \"empty_ranks\": %d, "
                     "\"pieces_split\": %d, \"halo_over_owned_mean\": %.5f, \"halo_over_owned_max\": %.5f, "
                     "\"neighbours_mean\": %.2f, \"neighbours_max\": %d, \"bytes_sent_per_step_mean\": %.0f, "
                     "\"bytes_sent_per_step_max\": %.0f, \"bytes_received_per_step_max\": %.0f, "
                     "\"partition_seconds\": %.3f, \"halo_seconds\": %.3f}%s\n",
                     r.scene.c_str(), r.method.c_str(), r.P, (long long)r.nodes, (long long)r.tets,
                     (long long)r.pieces, r.imbalance, r.quarterImbalance, r.emptyRanks, r.split, h.haloMean,
                     h.haloMax, h.nbrMean, h.nbrMax, h.sendMean, h.sendMax, h.recvMax, r.partSeconds, r.haloSeconds,
                     i + 1 < rows.size() ? "," : "");
    }
    std::fprintf(f, " ]}\n");
    std::fclose(f);
}

}  // namespace

int main(int argc, char** argv) {
    MPI_Init(&argc, &argv);
    float zoltanVersion = 0;
    if (Zoltan_Initialize(argc, argv, &zoltanVersion) != ZOLTAN_OK) {
        std::fprintf(stderr, "Zoltan_Initialize failed\n");
        MPI_Abort(MPI_COMM_WORLD, 1);
    }
    std::string out = "out/bench/mpi_zoltan.json", imbalanceTol = "1.01";
    bool quick = false;
    int maxRanks = 64;
    long long nodesPerRank = 50000;
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
        else if (a == "--imbalance-tol") imbalanceTol = next();
        else {
            std::fprintf(stderr, "unknown argument %s\n", a.c_str());
            return 2;
        }
    }
    if (quick) maxRanks = std::min(maxRanks, 4), nodesPerRank = std::min(nodesPerRank, 5000LL);

    std::vector<Row> rows;
    const double t0 = omp_get_wtime();
    std::printf("%-7s %-17s %3s %8s %7s %7s %5s %7s %7s %5s %4s %9s %9s %6s\n", "scene", "method", "P", "nodes",
                "imbal", "qImbal", "split", "haloAvg", "haloMax", "nbrAv", "nbrMx", "sendAvgB", "sendMaxB", "tPart");
    for (const char* scene : {"pieces", "body", "mixed"}) {
        for (int P = 2; P <= maxRanks; P *= 2) {
            const RawScene s = makeScene(scene, P, nodesPerRank);
            for (const char* method :
                 {"hilbert", "hilbert-split", "zoltan-hsfc", "zoltan-hsfc-whole", "zoltan-rcb"}) {
                const Row r = measure(s, scene, method, P, reach, imbalanceTol);
                rows.push_back(r);
                const HaloFigures& h = r.halo;
                std::printf("%-7s %-17s %3d %8lld %7.4f %7.4f %5d %7.4f %7.4f %5.1f %4d %9.0f %9.0f %6.3f\n",
                            r.scene.c_str(), r.method.c_str(), r.P, (long long)r.nodes, r.imbalance,
                            r.quarterImbalance, r.split, h.haloMean, h.haloMax, h.nbrMean, h.nbrMax, h.sendMean,
                            h.sendMax, r.partSeconds);
                std::fflush(stdout);
            }
        }
    }
    const double total = omp_get_wtime() - t0;
    std::printf("total %.1f s (Zoltan %.2f)\n", total, zoltanVersion);
    writeJson(out, rows, nodesPerRank, reach, quick, imbalanceTol, total);
    std::printf("wrote %s\n", out.c_str());
    MPI_Finalize();
    return 0;
}
