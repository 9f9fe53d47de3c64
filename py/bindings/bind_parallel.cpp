// MPI for the QDEM world (doc/parallel.md): the communicator comes from
// mpi4py (qdem/mpi/ranks.py hands over MPI.COMM_WORLD, or mpy's) and is
// duplicated in the core.  Without MPI at build time, setCommunicator
// refuses with the reason and everything else runs on one process.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "core/Errors.hpp"
#include "parallel/Domain.hpp"
#include "world/World.hpp"

#ifdef QDEM_HAVE_MPI
#include <mpi4py/mpi4py.h>

#include "parallel/MpiCommunicator.hpp"
#endif

namespace py = pybind11;
using namespace qdem;

void bindParallel(py::module_& m, py::class_<World>& world) {
#ifdef QDEM_HAVE_MPI
    m.attr("hasMPI") = true;
#else
    m.attr("hasMPI") = false;
#endif
    world.def(
        "setCommunicator",
        [](World& w, py::object comm, int firstRank) {
            w.partitionOptions.firstRank = 0;
            if (comm.is_none()) return w.setCommunicator(nullptr);
#ifdef QDEM_HAVE_MPI
            static bool imported = false;
            if (!imported) {
                if (import_mpi4py() < 0) throw py::error_already_set();
                imported = true;
            }
            MPI_Comm* c = PyMPIComm_Get(comm.ptr());
            if (!c) throw py::error_already_set();
            int size = 1;
            MPI_Comm_size(*c, &size);
            if (firstRank < 0 || (size > 1 && firstRank >= size))
                throw InputError("setCommunicator: firstRank = " + std::to_string(firstRank) + " must lie in [0, " +
                                 std::to_string(size - 1) + "] (the ranks below it own no QDEM node)");
            w.partitionOptions.firstRank = firstRank;
            w.setCommunicator(std::make_shared<MpiCommunicator>(*c));
#else
            throw InputError("this build of qdem has no MPI (Open MPI or mpi4py were missing when it was built): "
                             "install libopenmpi-dev openmpi-bin python3-mpi4py and build again");
#endif
        },
        py::arg("comm"), py::arg("firstRank") = 0,
        "Splits the world across the ranks of an mpi4py communicator (duplicated inside) from the next step on; "
        "None: back to one process.  Every rank must have built the same scene.  Ranks below firstRank own no "
        "node (yade.mpy's master: doc/parallel.md).");
    world.def_property(
        "partitionWholePieceFraction", [](const World& w) { return w.partitionOptions.wholePieceFraction; },
        [](World& w, double f) {
            if (!(f >= 0 && f <= 1))
                throw InputError("partitionWholePieceFraction = " + std::to_string(f) +
                                 " must lie in [0, 1] (0: every piece split along the curve)");
            w.partitionOptions.wholePieceFraction = f;
        },
        "Under MPI: a piece weighing at most this fraction of one rank's share is kept whole on one rank where "
        "balance allows (default 0.5; 0: every piece is split along the Hilbert curve).  Used by the next split "
        "(the first step, rebalance()).  doc/parallel.md.");
    world.def(
        "splitPreview",
        [](World& w, int nRanks, int firstRank) {
            // The split the next step would make over nRanks ranks, computed
            // here without MPI (before yade.mpy places its bodies).
            if (nRanks < 1) throw InputError("splitPreview: nRanks must be >= 1");
            std::vector<int32_t> pieceBegin;
            std::vector<double> extra;
            PartitionOptions opt = w.partitionOptions;
            opt.firstRank = firstRank;
            const Partition p = nRanks == 1 ? Partition{} : splitWorld(Domain::partitionInput(w, pieceBegin, extra), opt, nRanks);
            py::array_t<int32_t> a(static_cast<py::ssize_t>(w.nNodes()));
            int32_t* o = a.mutable_data();
            for (std::size_t i = 0; i < w.nNodes(); ++i) o[i] = nRanks == 1 ? 0 : p.nodeOwner[i];
            return a;
        },
        py::arg("nRanks"), py::arg("firstRank") = 0,
        "Per node, the rank that would own it if the world were split now over nRanks ranks, those below "
        "firstRank owning nothing (the split the first step makes; no MPI needed).");
    world.def_property_readonly(
        "surfaceNodeIds",
        [](const World& w) {
            py::array_t<int32_t> a(static_cast<py::ssize_t>(w.surfNodes.size()));
            for (std::size_t i = 0; i < w.surfNodes.size(); ++i) a.mutable_data()[i] = w.surfNodes[i];
            return a;
        },
        "Global ids of the surface nodes (every piece), ascending.");
    world.def(
        "gatherAll",
        [](World& w) {
            py::gil_scoped_release nogil;
            w.gatherAll();
        },
        "Under MPI: every rank learns every node's position and velocity (collective: call it on every rank). "
        "A no-op on one process.");
    world.def(
        "rebalance",
        [](World& w) {
            py::gil_scoped_release nogil;
            w.rebalance();
        },
        "Under MPI: splits the world again along the Hilbert curve from the current positions and contact work, "
        "moving every node's state and contact history to its new owner (collective: every rank calls it; the "
        "step does so by itself when the load drifts past rebalanceThreshold).  A no-op on one process.");
    world.def(
        "agreeOnScriptEnd",
        [](const World& w) {
            py::gil_scoped_release nogil;
            w.agreeOnScriptEnd();
        },
        "Under MPI: every rank has reached the end of the script (collective; qdem calls it at exit).  A rank "
        "still stepping or saving raises, naming both calls.  A no-op on one process.");
    world.def(
        "gatherState",
        [](World& w) {
            py::gil_scoped_release nogil;
            w.gatherState();
        },
        "Under MPI: every rank learns the whole state (node states and contact histories), as one process holds "
        "it; saveState needs it (collective).  A no-op on one process.");
    world.def_property_readonly("stateCurrent", &World::stateCurrent,
                                "Is every node's pos, vel and force current on this rank?  Always on one process; "
                                "under MPI right after gatherAll().");
    world.def_property_readonly(
        "mpiRank", [](const World& w) { return w.domain() ? w.domain()->rank() : 0; }, "This process's rank (0 alone).");
    world.def_property_readonly(
        "mpiSize", [](const World& w) { return w.domain() ? w.domain()->size() : 1; }, "Number of ranks (1 alone).");
    world.def_property_readonly(
        "nodeOwner",
        [](const World& w) {
            py::array_t<int32_t> a(static_cast<py::ssize_t>(w.nNodes()));
            int32_t* o = a.mutable_data();
            const Domain* d = w.domain();
            for (std::size_t i = 0; i < w.nNodes(); ++i)
                o[i] = d && d->built() ? d->partition().nodeOwner[i] : 0;
            return a;
        },
        "Per node, the rank that owns it (all 0 on one process or before the first step).");
    world.def_property_readonly(
        "partitionStats",
        [](const World& w) {
            py::dict s;
            const Domain* d = w.domain();
            if (!d || !d->built()) {
                s["ranks"] = 1;
                return s;
            }
            const Halo& h = d->halo();
            s["ranks"] = d->size();
            s["rank"] = d->rank();
            s["ownedNodes"] = h.ownedNodes.size();
            s["ownedTets"] = h.ownedTets.size();
            s["ghosts"] = h.nGhosts();
            s["neighbours"] = h.neighbours;
            s["imbalance"] = d->partition().imbalance();
            s["stepBytes"] = d->stepBytes;
            s["stepMessages"] = d->stepMessages;
            s["exchangeSeconds"] = d->seconds;
            s["loadImbalance"] = d->loadImbalance;
            s["rebalances"] = d->rebalances;
            return s;
        },
        "This rank's share (dict: ranks, rank, ownedNodes, ownedTets, ghosts, neighbours, imbalance = max/mean "
        "weight of the split, loadImbalance = max/mean load in the last step, rebalances so far) and its halo's "
        "cost in the last step (stepBytes, stepMessages sent, exchangeSeconds).");
}
