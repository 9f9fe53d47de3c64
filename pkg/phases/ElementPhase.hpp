// Element forces of the awake tets into per-thread buffers (the integration
// phase sums them), and the Cauchy stress output.
#pragma once
#include <cstdint>

#include "../world/Phase.hpp"
#include "../world/ThreadLayout.hpp"

namespace qdem {

struct Material;

class ElementPhase final : public Phase {
public:
    using Phase::Phase;
    const char* name() const override { return "elements"; }
    void run(double dt) override;
    // Per-thread node force buffers of the last run and the node range each covers.
    const ThreadLayout& layout() const { return layout_; }
    // Cauchy stress per tet (xx yy zz yz xz xy), elastic plus viscous.
    void stress(double* out) const;

private:
    template <class Law, bool Viscous, bool Energy>
    void elementRange(const Law& law, int32_t t0, int32_t t1, const Material& m, double* buf, int32_t lo,
                      double& wEl, double& diss) const;
    ThreadLayout layout_;
};

}  // namespace qdem
