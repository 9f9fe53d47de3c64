// Element forces of the awake tets into per-thread buffers (the integration
// phase sums them), and the Cauchy stress output.
#pragma once
#include <cstdint>
#include <vector>

#include "../core/Aligned.hpp"
#include "../core/Column.hpp"
#include "../element/TetBlock.hpp"
#include "../material/Material.hpp"
#include "../step/Energy.hpp"
#include "../step/Phase.hpp"
#include "../mesh/PieceInfo.hpp"
#include "../step/Settings.hpp"
#include "../parallel/ThreadBlocks.hpp"
#include "../parallel/ThreadLayout.hpp"
#include "../step/AwakeSet.hpp"

namespace qdem {


class ElementPhase final : public Phase {
public:
    // What it reads and writes of the world.
    struct Data {
        const Column<double>& pos;
        const Column<double>& vel;
        const Column<int32_t>& tetNodes;
        const Column<int32_t>& tetPiece;
        const Column<double>& tetB;
        const Column<double>& tetVol0;
        const Column<int32_t>& tetMaterial;  // each element's material
        const std::vector<PieceInfo>& pieces;
        const std::vector<Material>& materials;
        const Settings& settings;
        const AwakeSet& sleeping;  // the awake tets
        Energy& energy;              // viscous dissipation
        std::vector<std::vector<double>>& threadPieceEnergy;  // strain energy per thread and piece
    };
    explicit ElementPhase(const Data& data) : w_(data) {}
    const char* name() const override { return "elements"; }
    void run(double dt) override;
    // Per-thread node force buffers of the last run (layout().stride doubles
    // per node) and the node range each covers.
    const ThreadLayout& layout() const { return layout_; }
    // Cauchy stress per tet (xx yy zz yz xz xy), elastic plus viscous.
    void stress(double* out) const;

private:
    // Rebuilds layout_ (force buffers padded to kForceStride doubles per
    // node) and blocks_ from it, when the awake set or thread count changed.
    void buildLayout(int threads);
    template <class Law, bool Viscous, bool Energy>
    void elementRange(const Law& law, const TetBlock* blocks, const BlockSegment& sg, const Material& m, double* buf,
                      int32_t lo, double& wEl, double& diss) const;
    Data w_;
    ThreadLayout layout_;
    std::vector<ThreadBlocks> blocks_;  // per thread
};

}  // namespace qdem
