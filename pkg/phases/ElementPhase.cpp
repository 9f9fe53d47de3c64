// Element forces: every awake tet's elastic and viscous nodal forces
// (ElementKernel.hpp, compiled per material law), summed per thread into
// private buffers (ThreadLayout.hpp) that the integration phase adds up.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <type_traits>

#include <Eigen/Geometry>  // cross products, determinants

#include "../element/ElementKernel.hpp"
#include "../element/MaterialLaw.hpp"
#include "../core/ThreadPartials.hpp"
#include "../step/AwakeSet.hpp"
#include "ElementPhase.hpp"

namespace qdem {

template <class Law, bool Viscous, bool Energy>
void ElementPhase::elementRange(const Law& law, const TetBlock* blocks, const BlockSegment& sg, const Material& m,
                                double* buf, int32_t lo, double& wEl, double& diss) const {
    const ElementParams prm{m.lambda(), m.mu(), Viscous ? m.beta() : 0.0};
    const double* X = w_.pos.data();
    const double* V = w_.vel.data();
    const auto last = static_cast<int32_t>(std::min(w_.pos.size(), w_.vel.size()) / 3) - 1;
    double w = 0, d = 0;
    BatchOut out;
    const TetBlock* b = blocks + sg.first;
    for (int32_t e0 = sg.t0; e0 < sg.t1; e0 += kLanes, ++b) {
        const int count = sg.count(e0);
        elementBlock<Law, Viscous, Energy>(law, *b, X, V, last, prm, out);
        scatterForces(out.f, b->node, count, buf, lo);
        if constexpr (Energy)
            for (int l = 0; l < count; ++l) {
                w += out.wElastic[l];
                d += out.diss[l];
            }
    }
    wEl += w;
    diss += d;
}

void ElementPhase::buildLayout(int threads) {
    layout_.build(w_.tetNodes.data(), w_.sleeping.awakeTets(), threads, w_.sleeping.version(), kForceStride);
    buildThreadBlocks(layout_, w_.tetNodes.data(), w_.tetB.data(), w_.tetVol0.data(), w_.tetMaterial.data(), blocks_);
}

void ElementPhase::run(double dt) {
    const int nth = omp_get_max_threads();
    if (!layout_.matches(nth, w_.sleeping.version())) buildLayout(nth);
    const bool energyOn = w_.settings.trackEnergy;
    ThreadPartials<1> dissParts(layout_.nThreads);  // viscous power, added in thread order
#pragma omp parallel num_threads(layout_.nThreads)
    {
        const int th = omp_get_thread_num();
        double diss = 0;
        AlignedVector<double>& buf = layout_.buffers[th];
        std::fill(buf.begin(), buf.end(), 0.0);
        const int32_t lo = layout_.nodeLo[th];
        double* pe = energyOn ? w_.threadPieceEnergy[th].data() : nullptr;
        const TetBlock* blocks = blocks_[th].blocks.data();
        for (const BlockSegment& sg : blocks_[th].segments) {
            const Material& m = w_.materials[sg.material];
            const bool visc = w_.settings.viscosityOn && m.viscosity > 0;
            double w = 0;
            // The law is chosen once per segment (one material's tets): the
            // kernel below is compiled per law, with no call through a pointer.
            withLaw(m, [&](const auto& law) {
                using Law = std::decay_t<decltype(law)>;
                if (visc && energyOn) elementRange<Law, true, true>(law, blocks, sg, m, buf.data(), lo, w, diss);
                else if (visc) elementRange<Law, true, false>(law, blocks, sg, m, buf.data(), lo, w, diss);
                else if (energyOn) elementRange<Law, false, true>(law, blocks, sg, m, buf.data(), lo, w, diss);
                else elementRange<Law, false, false>(law, blocks, sg, m, buf.data(), lo, w, diss);
            });
            if (energyOn) pe[3 * sg.piece] += w;  // strain energy per piece (sleeping ones keep theirs)
        }
        dissParts.set(th, {diss});
    }
    if (energyOn) w_.energy.viscous += dissParts.sum()[0] * dt;
}

// ---------------------------------------------------------------------------
// Stress output

void ElementPhase::stress(double* out) const {
    const auto T = static_cast<int32_t>(w_.tetVol0.size());
#pragma omp parallel for schedule(static)
    for (int32_t e = 0; e < T; ++e) {
        const Material& m = w_.materials[w_.tetMaterial[e]];
        const ElementParams prm{m.lambda(), m.mu(), w_.settings.viscosityOn ? m.beta() : 0.0};
        const int32_t* c = w_.tetNodes.data() + 4 * e;
        const Mat3 B = loadRowMajor(w_.tetB.data() + 9 * e);
        const double* X = w_.pos.data();
        const double* V = w_.vel.data();
        const Mat3 F = edgeMatrix(X + 3 * c[0], X + 3 * c[1], X + 3 * c[2], X + 3 * c[3]) * B;
        const Mat3 Fd = edgeMatrix(V + 3 * c[0], V + 3 * c[1], V + 3 * c[2], V + 3 * c[3]) * B;
        const Mat3 P = withLaw(m, [&](const auto& law) {
            using Law = std::decay_t<decltype(law)>;
            return tetStress<Law, true, false>(law, F, Fd, prm).P;
        });
        // sigma = P F^T / J (for J <= 0 the element is inverted: the number
        // is the law's, signs and all)
        const Mat3 sigma = (P * F.transpose()) / F.determinant();
        double* o = out + 6 * e;
        o[0] = sigma(0, 0);
        o[1] = sigma(1, 1);
        o[2] = sigma(2, 2);
        o[3] = sigma(1, 2);
        o[4] = sigma(0, 2);
        o[5] = sigma(0, 1);
    }
}

}  // namespace qdem
