// Semi-implicit Kelvin-Voigt viscosity (settings.viscousIntegration =
// Implicit; doc/formulation.md section 2.1).
//
// The leapfrog's velocity update becomes
//     (M + dt C(x_n)) v_{n+1/2} = M v_{n-1/2} + dt (f_elastic + f_contact + f_ext + m g)
// with C the viscous operator on the current shape (ViscousOperator.hpp):
// elasticity and contacts stay explicit.  Written for the increment
// D = v_{n+1/2} - v_{n-1/2} it reads (M + dt C) D = dt f, where f is the
// explicit force of the step *with* the viscous force at v_{n-1/2} (what the
// element phase computes anyway).  The iterations start from the last
// step's D (scaled by the ratio of the steps): the acceleration changes
// little from one step to the next, so the start is close; when it is not
// (the first step, a piece woke, the guess's residual larger than D = 0's)
// they start from D = 0.  Preconditioned conjugate gradients (Jacobi, or
// per piece the co-rotated Cholesky factor of its reference shape,
// CorotatedCholesky.hpp: settings.viscousPreconditioner) over the
// free DOFs of the awake nodes (blocked DOFs keep their velocity: D = 0
// there) return q = C D; the integrator then applies the force f - q, so
// the viscous forces applied are element forces, each summing to zero:
// momentum is conserved whatever the tolerance.  Under MPI each rank
// iterates on its owned nodes, C p is one pass over its owned tets with the
// ghosts' partial sums sent back to their owners (Domain.hpp), and the dot
// products are summed in rank order: every rank stops at the same count.
#pragma once
#include <cstdint>
#include <vector>

#include "../core/Column.hpp"
#include "../material/Material.hpp"
#include "../parallel/DomainRef.hpp"
#include "../mesh/PieceInfo.hpp"
#include "../step/Settings.hpp"
#include "../parallel/ThreadBlocks.hpp"
#include "../parallel/ThreadLayout.hpp"
#include "../step/AwakeSet.hpp"
#include "CorotatedCholesky.hpp"

namespace qdem {


class ViscousSolve {
public:
    // What it reads of the world (the integration phase declares it for it).
    struct Data {
        const Column<double>& pos;        // the current shape C(x) is built on
        const Column<double>& refPos;      // the reference shape (the Cholesky preconditioner's)
        const Column<double>& mass;
        const Column<uint8_t>& blocked;   // prescribed DOFs keep their velocity
        const Column<int32_t>& tetNodes;
        const Column<double>& tetB;
        const Column<double>& tetVol0;
        const Column<int32_t>& tetMaterial;  // each element's material
        const std::vector<PieceInfo>& pieces;
        const std::vector<Material>& materials;
        const Settings& settings;
        const long& iter;                 // named in its errors
        const AwakeSet& sleeping;         // the awake tets and nodes
        DomainRef domain;                 // under MPI: ghosts, partial sums, reductions
    };
    explicit ViscousSolve(const Data& data)
        : w_(data),
          precond_({.pos = data.pos, .refPos = data.refPos, .mass = data.mass, .tetNodes = data.tetNodes,
                    .tetB = data.tetB, .tetVol0 = data.tetVol0, .tetMaterial = data.tetMaterial, .pieces = data.pieces, .materials = data.materials,
                    .settings = data.settings, .sleeping = data.sleeping, .domain = data.domain}) {}
    // Implicit viscosity asked for, viscosity on, and an awake piece viscous
    // (the same answer on every MPI rank).
    bool active() const;
    // Solves for the step's viscous correction from the explicit forces f
    // (3 per node, read on the awake nodes); returns q = C D (3 per node,
    // valid on the awake nodes).  Throws StabilityError when the iterations
    // do not converge.
    const double* solve(double dt, const double* f);
    // With the energy tracked: the integrator writes v_{n+1/2} - v_{n-1/2}
    // here (3 per awake node), then dissipation() returns the work of the
    // viscous correction in the step (doc/formulation.md 2.1, "Energy").
    double* velocityChange() { return delta_.data(); }
    double dissipation(double dt, const double* vNew);

    // The warm start: the last solve's D, 3 per node (0 on blocked DOFs and on
    // nodes it did not solve for), the step it was solved at and its dt.  Part
    // of a run's state (a restart without it would start the next solve
    // elsewhere and end within the tolerance, not on the same bits):
    // IntegrationPhase saves it and migrates it between MPI ranks.
    std::vector<double>& warmStart() { return warm_; }
    const std::vector<double>& warmStart() const { return warm_; }
    long warmIter = -1;  // -1: none
    double warmDt = 0;

    // Factorizations of the Cholesky preconditioner since the world was built.
    long factorizations() const { return precond_.factorizations; }

    int iterations = 0;    // of the last solve
    bool startedWarm = false;  // the last solve started from the last step's change
    long totalIterations = 0;
    double seconds = 0;    // wall time of the last solve (and its energy term)

private:
    // The awake nodes: the i-th is awake[i] (every node when nothing sleeps).
    struct AwakeNodes {
        const int32_t* ids;  // nullptr: all nodes, in order
        int32_t count;
        int32_t operator[](int32_t i) const { return ids ? ids[i] : i; }
    };
    AwakeNodes awakeNodes() const;
    // y = C p over the awake tets (3 per node, written on the awake nodes).
    // Under MPI p is first sent to the ghosts (its entries there are
    // overwritten) and the ghosts' partial sums come back to their owners.
    void apply(double* p, double* y);
    void diagonal(double* d);
    // The iteration's vectors (sized by solve): masses, blocked flags, the
    // iterate X, residual R, preconditioned residual Z, direction P, C P, q = C X
    // and the preconditioner's diagonal D.
    struct Vectors {
        const double* M;
        const uint8_t* blk;
        double *X, *R, *Z, *P, *CP, *Q, *D;
    };
    Vectors vectors();
    // X = the warm start, or 0 when there is none; R, Z, P, Q and the sums
    // (r.z, r.M^-1 r, x.M x) to match.  Returns whether it started warm.
    bool start(double dt, const double* f, double* sums);
    // With the Cholesky preconditioner: Z = its z on the pieces it covers
    // (Jacobi's elsewhere, already in Z), 0 on blocked DOFs; returns r.z
    // (global); with setP also P = Z.
    double precondition(bool setP);
    bool cholesky() const { return w_.settings.viscousPreconditioner == ViscousPreconditioner::Cholesky; }
    // After the solve: the warm start of the next step.
    void keep(double dt);
    // Sums of a*b (and more) over the free DOFs of the awake nodes, per thread
    // then in thread order: the same bits for a given thread count.  Global:
    // under MPI then over the ranks in rank order (Domain::sumInRankOrder),
    // so every rank stops the iterations at the same count.
    enum class Sum { Local, Global };
    template <class Fn>
    void nodeLoop(Sum scope, int nSums, double* sums, Fn&& fn);

    Data w_;
    CorotatedCholesky precond_;  // settings.viscousPreconditioner = Cholesky
    ThreadLayout layout_;
    std::vector<ThreadBlocks> blocks_;  // the layout's shares as tet blocks (the operator's element pass)
    std::vector<double> x_, r_, z_, p_, y_, cp_, q_, diag_, delta_, partial_;
    std::vector<double> warm_;
};

}  // namespace qdem
