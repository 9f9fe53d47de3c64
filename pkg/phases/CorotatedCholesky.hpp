// The co-rotated reference-shape Cholesky preconditioner of the implicit
// viscous solve (settings.viscousPreconditioner = Cholesky; ViscousSolve.hpp,
// doc/formulation.md 2.1 "Preconditioner").
//
// For a piece whose shape is its reference shape rotated by R, the viscous
// operator is exactly R C_ref R^T node-blockwise (ViscousOperator.hpp,
// viscousReferenceMatrix) and the lumped mass is unchanged, so
//     (M + dt C(x))^-1 = R (M + dt C_ref)^-1 R^T.
// Per piece, A_ref = M + dt C_ref is factored once (sparse Cholesky, AMD
// ordering) and applied with the piece's best-fit rotation (the polar factor
// of sum m (x - c)(X - C)^T), computed at each solve: z = R L^-T L^-1 R^T r.
// What separates it from the exact inverse is the piece's strain, not its
// rotation.  Refactored when the step changes by more than 1 %, or the
// material, the masses or the mesh change.
//
// Under MPI a piece split over ranks is preconditioned by the same factor:
// the ranks owning part of it gather its positions (once per solve) and its
// residual (once per iteration) with Domain::sumInRankOrder (each entry has
// one nonzero contribution: exact), each solves the whole piece and keeps its
// owned rows.  The preconditioner is then the serial one whatever the ranks,
// and so are the iteration counts.
#pragma once
#include <cstdint>
#include <vector>

#include "../core/Column.hpp"
#include "../material/Material.hpp"
#include "../parallel/DomainRef.hpp"
#include "../mesh/PieceInfo.hpp"
#include "../step/AwakeSet.hpp"
#include "../step/Settings.hpp"

namespace qdem {

class CorotatedCholesky {
public:
    struct Data {
        const Column<double>& pos;
        const Column<double>& refPos;
        const Column<double>& mass;
        const Column<int32_t>& tetNodes;
        const Column<double>& tetB;
        const Column<double>& tetVol0;
        const Column<int32_t>& tetMaterial;  // each element's material (the factor's C per element)
        const std::vector<PieceInfo>& pieces;
        const std::vector<Material>& materials;
        const Settings& settings;
        const AwakeSet& sleeping;
        DomainRef domain;
    };
    explicit CorotatedCholesky(const Data& data) : w_(data) {}
    // Before a solve: which pieces this rank preconditions, their factors
    // (refactored when their key changed) and their rotations.  Collective
    // under MPI when a piece is split.
    void prepare(double dt);
    // z = R A_ref^-1 R^T r on the nodes of every awake viscous piece this rank
    // owns nodes of (other entries of z untouched).  r must be 0 on blocked
    // DOFs; z is not zeroed there (the caller does).  Collective under MPI
    // when a piece is split.
    void apply(const double* r, double* z);

    long factorizations = 0;  // since the world was built
    double factorSeconds = 0;  // of the last prepare()

private:
    // A factor's key: what A_ref depends on.
    struct Key {
        double dt = 0, lambda = 0, mu = 0, beta = 0, massSum = 0, volSum = 0;
        int32_t nodeBegin = -1, nodeEnd = -1, tetBegin = -1, tetEnd = -1;
    };
    // L (lower, compressed columns, diagonal first in each column) of
    // P A_ref P^T = L L^T; perm: row i of A goes to row perm[i].
    struct Factor {
        Key key;
        bool valid = false;
        std::vector<int32_t> colStart, row, perm;
        std::vector<double> val;
    };
    // A piece this rank preconditions: its nodes' positions (this rank's pos,
    // or the gathered copy for a split piece) and the rotation at this solve.
    struct Task {
        int32_t piece;
        int32_t gatherOffset;  // -1: whole piece on this rank; else into gather_ (3 per node)
        double R[9];           // row-major
    };
    Key keyOf(const PieceInfo& pc, double dt) const;
    static bool sameKey(const Key& a, const Key& b);
    void factor(int32_t piece, const Key& key);
    void rotation(Task& t, const double* x) const;
    void solvePiece(const Task& t, const double* r, double* z, std::vector<double>& scratch) const;

    Data w_;
    std::vector<Factor> factors_;  // per piece
    std::vector<Task> tasks_;
    std::vector<int32_t> splitPieces_, splitOffset_;  // every split awake viscous piece (alike on every rank)
    std::vector<double> gather_;
    std::vector<std::vector<double>> scratch_;  // per thread, 2 x 3 x the largest piece's nodes
};

}  // namespace qdem
