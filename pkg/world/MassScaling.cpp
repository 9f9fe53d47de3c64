// Selective mass scaling: the least mass to add to the elements whose own
// stable step is below a target step (doc/meshes.md, "Selective mass
// scaling").
//
// An element of stiffness K_e (largest eigenvalue k_e) and lumped mass M_e/4
// per node has omega_e^2 = 4 k_e / M_e (Irons: the mesh's highest frequency is
// below the largest element one; the added mass is the element's own, so the
// element masses still sum to the node masses).  With its stiffness-
// proportional Kelvin-Voigt dashpot (C_e = beta K_e) the leapfrog energy
// condition M - dt/2 C - dt^2/4 K > 0 holds for that element iff
// omega_e^2 (dt^2/4 + beta dt/2) < 1 (leapfrogLimit), i.e. iff
//     M_e >= k_e dt (dt + 2 beta),
// so the added mass is max(0, k_e dt (dt + 2 beta) - rho V_e).  It is then
// checked with the very expressions stableDt() evaluates (elementNodeMass,
// leapfrogLimit) and raised by a few ulps while rounding leaves it short, so
// that stableDt() reports elastic and viscous steps >= the target exactly.
#include <algorithm>
#include <cmath>

#include "../contact/ContactModel.hpp"
#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../element/MaterialLaw.hpp"
#include "../element/Tetra.hpp"
#include "World.hpp"

namespace qdem {

double hookeStiffnessMax(const Mat3& B, double V, double lambda, double mu);  // StableDt.cpp

std::vector<double> World::massScaling(const TetMesh& mesh, int material, double targetDt) const {
    if (material < 0 || material >= static_cast<int>(materials.size()))
        throw InputError(cat("massScaling: unknown material index ", material));
    if (!(targetDt > 0) || !std::isfinite(targetDt))
        throw InputError(cat("addPiece: targetDt=", targetDt, " must be a positive number of seconds"));
    checkMesh(mesh);
    const Material& m = materials[material];
    const double lam = m.lambda(), mu = m.mu();
    double lam0 = lam, mu0 = mu;
    withLaw(m, [&](const auto& law) { law.lameAtRest(lam0, mu0); });
    // The viscous limit counts whatever the viscosity setting: the piece
    // keeps its step when viscosity is switched on later.
    const double beta = m.beta();
    const double dt = targetDt;
    const double need = dt * (dt + 2 * beta);  // element mass per unit k_e
    auto reaches = [&](double V, double k, double added) {
        const double w = std::sqrt(k / ((m.density * V + added) / 4.0));  // as elementNodeMass
        return leapfrogLimit(w, 0.0) >= dt && leapfrogLimit(w, 0.5 * beta * w) >= dt;
    };
    std::vector<double> added(mesh.nTets(), 0.0);
    for (std::size_t e = 0; e < mesh.nTets(); ++e) {
        const int32_t* c = &mesh.tets[4 * e];
        const Mat3 Dm =
            edgeMatrix(&mesh.nodes[3 * c[0]], &mesh.nodes[3 * c[1]], &mesh.nodes[3 * c[2]], &mesh.nodes[3 * c[3]]);
        const double V = Dm.determinant() / 6.0;  // as addPiece stores them
        const Mat3 B = Dm.inverse();
        // The cheap upper bound of omega_e^2 (elementOmegaMax) first: most
        // elements reach the step with room to spare.
        const double sumG2 = B.squaredNorm() + (B.row(0) + B.row(1) + B.row(2)).squaredNorm();
        const double bound = 4.0 * (std::max(lam, 0.0) + 2 * mu) * sumG2 / m.density;
        if (bound * (0.25 * dt * dt + 0.5 * beta * dt) < 1.0 - 1e-6) continue;
        const double k = hookeStiffnessMax(B, V, lam0, mu0);
        double a = std::max(0.0, k * need - m.density * V);
        for (int it = 0; !reaches(V, k, a); ++it) {
            if (it > 200) throw InputError(cat("addPiece: no mass reaches targetDt=", dt, " s for tetrahedron ", e));
            a += (m.density * V + a) * std::ldexp(1.0, it - 52);  // an ulp of the element mass, doubling
        }
        added[e] = a;
    }
    return added;
}

void World::rigidContactLimit(std::size_t i, double& contact, double& combined) const {
    if (i >= pieces.size()) throw InputError(cat("rigidContactLimit: no piece ", i));
    stableDt();  // the element frequencies (omegaCache_)
    const PieceInfo& p = pieces[i];
    const Material& m = materials[p.material];
    // As contactMode against a rigid wall: the stiffest w kn / m over the surface nodes.
    const PairConst pair = mix(materialSide(m, 0), rigidSide());
    const bool spring = tangentialSprings() && std::max(m.frictionWall, m.frictionPiece) > 0;
    const double wc = std::sqrt((spring ? std::max(pair.kn, pair.kt) : pair.kn) / p.minSurfaceMassPerWeight);
    contact = leapfrogLimit(wc, pair.xi);
    const double we = omegaCache_[i];
    const double beta = settings.viscosityOn ? pieceBeta(i) : 0.0;
    const double w = std::sqrt(we * we + wc * wc);
    combined = leapfrogLimit(w, w > 0 ? (beta * we * we + 2 * pair.xi * wc) / (2 * w) : 0.0);
}

}  // namespace qdem
