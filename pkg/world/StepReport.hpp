// What sets one piece's element step: its stiffest elements against its
// median one (World::pieceStepReport, StepReport.cpp), as an explicit FE
// code lists its smallest-step elements.  Reference shape and mass.
#pragma once
#include <cstdint>
#include <limits>
#include <vector>

namespace qdem {

struct PieceStepReport {
    static constexpr int kListed = 10;  // elements named, smallest step first
    // Largest exact element frequency omega_e = sqrt(lambda_max(K_e) / (rho V / 4))
    // [rad/s] (it sets the piece's element step), and the median element's.
    double omegaMax = 0, omegaMedian = 0;
    // Local tet indices (solver order) of the kListed smallest-step elements.
    std::vector<int32_t> worst;
    // Elements whose step is within 2x of the smallest (omega_e >= omegaMax / 2).
    int64_t nearLimit = 0;
    // Smallest shape quality over those: min height / longest edge (a regular
    // tetrahedron: sqrt(2/3) = 0.816; a sliver: near 0).
    double worstQuality = std::numeric_limits<double>::quiet_NaN();
};

// lambda_max(K_e) / (rho V / 4) of one element at rest (K_e Hooke's with
// (lambda, mu), B9 its inverse reference edge matrix, row-major): StableDt.cpp.
double restElementOmega2(const double* B9, double V, double lambda, double mu, double density);

}  // namespace qdem
