// YADE spheres near QDEM pieces: their properties and states in, forces out.
// readSphereStates and applySphereForces talk to YADE's Python objects with
// the CPython API directly: they run every step for every sphere near a
// piece, where a Python loop would cost several microseconds per sphere.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <string>

#include "core/Errors.hpp"
#include "world/World.hpp"

namespace py = pybind11;
using namespace qdem;

namespace {

using Ints = py::array_t<int32_t, py::array::c_style | py::array::forcecast>;
using Reals = py::array_t<double, py::array::c_style | py::array::forcecast>;

void need(const py::array& a, py::ssize_t n, const char* what) {
    if (a.ndim() != 1 || a.shape(0) != n)
        throw InputError(std::string("setSpheres: ") + what + " must be a 1-d array of length " + std::to_string(n));
}

// x, y, z of a YADE Vector3 attribute of obj into out[0..3).  minieigen's
// __getinitargs__ hands the three numbers over in one tuple: a third of the
// cost of three item lookups.  Any other sequence of 3 numbers works too.
void readVector(PyObject* obj, PyObject* name, double* out) {
    static PyObject* initArgs = PyUnicode_InternFromString("__getinitargs__");
    static PyTypeObject* lastType = nullptr;  // the unbound method, looked up once per type
    static PyObject* lastFunc = nullptr;
    PyObject* v = PyObject_GetAttr(obj, name);
    if (!v) throw py::error_already_set();
    if (Py_TYPE(v) != lastType) {
        Py_XDECREF(lastFunc);
        lastType = Py_TYPE(v);
        lastFunc = PyObject_GetAttr(reinterpret_cast<PyObject*>(lastType), initArgs);
        if (!lastFunc) PyErr_Clear();
    }
    PyObject* t = lastFunc ? PyObject_CallOneArg(lastFunc, v) : nullptr;
    if (t && PyTuple_Check(t) && PyTuple_GET_SIZE(t) == 3) {
        for (Py_ssize_t k = 0; k < 3; ++k) out[k] = PyFloat_AsDouble(PyTuple_GET_ITEM(t, k));
    } else {
        PyErr_Clear();
        for (Py_ssize_t k = 0; k < 3; ++k) {
            PyObject* x = PySequence_GetItem(v, k);
            out[k] = x ? PyFloat_AsDouble(x) : 0.0;
            Py_XDECREF(x);
        }
    }
    Py_XDECREF(t);
    Py_DECREF(v);
    if (PyErr_Occurred()) throw py::error_already_set();
}

// Box (lo, hi) of each piece's surface nodes, grown by its particle radius.
// The pieces' boxes now (World::pieceBoxes: under MPI a reduction over
// the ranks, once per step, collective).
const std::vector<double>& pieceBoxes(World& w) { return w.pieceBoxes(); }

}  // namespace

void bindSpheres(py::module_& m) {
    auto W = py::reinterpret_borrow<py::class_<World>>(m.attr("World"));
    W.def(
         "setSpheres",
         [](World& w, const Ints& id, const Reals& radius, const Reals& young, const Reals& ktRatio,
            const Reals& friction, const Reals& restitution, const Reals& mass, const Ints& pairStart,
            const Ints& pairPiece) {
             const py::ssize_t n = id.ndim() == 1 ? id.shape(0) : -1;
             need(id, n, "id");
             need(radius, n, "radius");
             need(young, n, "young");
             need(ktRatio, n, "ktRatio");
             need(friction, n, "friction");
             need(restitution, n, "restitution");
             need(mass, n, "mass");
             need(pairStart, n + 1, "pairStart");
             need(pairPiece, pairStart.data()[n], "pairPiece");
             w.setSpheres(static_cast<int32_t>(n), id.data(), radius.data(), young.data(), ktRatio.data(),
                          friction.data(), restitution.data(), mass.data(), pairStart.data(), pairPiece.data());
         },
         py::arg("id"), py::arg("radius"), py::arg("young"), py::arg("ktRatio"), py::arg("friction"),
         py::arg("restitution"), py::arg("mass"), py::arg("pairStart"), py::arg("pairPiece"),
         "Sets the YADE spheres that may touch pieces (see pkg/contact/SphereSet.hpp); keeps the contact "
         "history of (id, piece) pairs already there.")
        .def_static(
            "otherIds",
            [](const py::list& interactions, int32_t self) {
                // The body at the other end of each interaction (YADE's
                // O.interactions.withBodyAll(self)), without a Python loop.
                static PyObject* id1 = PyUnicode_InternFromString("id1");
                static PyObject* id2 = PyUnicode_InternFromString("id2");
                const py::ssize_t n = static_cast<py::ssize_t>(py::len(interactions));
                py::array_t<int32_t> out(n);
                int32_t* o = out.mutable_data();
                for (py::ssize_t k = 0; k < n; ++k) {
                    PyObject* it = PyList_GET_ITEM(interactions.ptr(), k);
                    PyObject* a = PyObject_GetAttr(it, id1);
                    if (!a) throw py::error_already_set();
                    long v = PyLong_AsLong(a);
                    Py_DECREF(a);
                    if (v == self) {
                        PyObject* b = PyObject_GetAttr(it, id2);
                        if (!b) throw py::error_already_set();
                        v = PyLong_AsLong(b);
                        Py_DECREF(b);
                    }
                    o[k] = static_cast<int32_t>(v);
                }
                return out;
            },
            py::arg("interactions"), py::arg("self"))
        .def(
            "piecesInside",
            [](World& w, const Reals& lo, const Reals& hi) {
                // Are all pieces' boxes inside the given (pieces, 3) boxes?  The
                // per-step test of the sphere coupling, without temporaries.
                const std::size_t np = w.pieces.size();
                if (lo.size() != static_cast<py::ssize_t>(3 * np) || hi.size() != static_cast<py::ssize_t>(3 * np))
                    return false;
                const std::vector<double>& b = pieceBoxes(w);
                for (std::size_t p = 0; p < np; ++p)
                    for (int d = 0; d < 3; ++d)
                        if (b[6 * p + d] < lo.data()[3 * p + d] || b[6 * p + 3 + d] > hi.data()[3 * p + d]) return false;
                return true;
            },
            py::arg("lo"), py::arg("hi"))
        .def_property_readonly("sphereSeconds", [](const World& w) { return w.report().second("spheres"); },
                               "Wall time of the sphere-contact phase of the last step [s].")
        .def_property_readonly("nSpheres", [](const World& w) { return w.spheres.size(); })
        .def(
            "pieceBounds",
            [](World& w) {
                const std::vector<double>& b = pieceBoxes(w);
                py::array_t<double> a({static_cast<py::ssize_t>(w.pieces.size()), py::ssize_t(6)});
                std::copy(b.begin(), b.end(), a.mutable_data());
                return a;
            },
            "Box (lo, hi) of each piece's surface, grown by its particle radius: (pieces, 6).")
        .def(
            "setSphereStates",
            [](World& w, const Reals& pos, const Reals& vel, const Reals& angVel, const py::object& spinCentre) {
                const py::ssize_t n = w.spheres.size();
                const Reals centre = spinCentre.is_none() ? pos : spinCentre.cast<Reals>();
                for (const Reals* a : {&pos, &vel, &angVel, &centre})
                    if (a->size() != 3 * n)
                        throw InputError("setSphereStates: arrays must hold 3 numbers per sphere (" +
                                         std::to_string(n) + " spheres)");
                std::copy_n(pos.data(), 3 * n, w.spheres.pos.data());
                std::copy_n(vel.data(), 3 * n, w.spheres.vel.data());
                std::copy_n(angVel.data(), 3 * n, w.spheres.angVel.data());
                for (py::ssize_t j = 0; j < 3 * n; ++j) w.spheres.spinOffset[j] = centre.data()[j] - pos.data()[j];
            },
            py::arg("pos"), py::arg("vel"), py::arg("angVel"), py::arg("spinCentre") = py::none(),
            "Positions, velocities and angular velocities (n, 3) of the spheres, in setSpheres order; spinCentre "
            "(n, 3): a clump member's clump centre, whose velocity vel + angVel x (centre - pos) is (default pos).")
        .def(
            "readSphereStates",
            [](World& w, const py::list& states, const py::object& clumpStates) {
                const py::ssize_t n = w.spheres.size();
                if (py::len(states) != static_cast<std::size_t>(n))
                    throw InputError("readSphereStates: one YADE State per sphere expected");
                // (a list, one entry per sphere: its clump's State for a clump member, else None)
                const bool clumps = !clumpStates.is_none();
                if (clumps && (!py::isinstance<py::list>(clumpStates) ||
                               py::len(clumpStates) != static_cast<std::size_t>(n)))
                    throw InputError("readSphereStates: clumpStates must be a list with one entry per sphere");
                static PyObject* pos = PyUnicode_InternFromString("pos");
                static PyObject* vel = PyUnicode_InternFromString("vel");
                static PyObject* angVel = PyUnicode_InternFromString("angVel");
                // Velocities only matter for spheres that may touch a piece this
                // step (box test as in the contact phase): the rest skip them.
                const std::vector<double>& box = pieceBoxes(w);
                SphereSet& S = w.spheres;
                long full = 0;
                for (py::ssize_t i = 0; i < n; ++i) {
                    PyObject* s = PyList_GET_ITEM(states.ptr(), i);
                    double* x = &S.pos[3 * i];
                    readVector(s, pos, x);
                    PyObject* cs = clumps ? PyList_GET_ITEM(clumpStates.ptr(), i) : Py_None;
                    double c[3];  // the spin centre
                    if (cs == Py_None)
                        std::copy_n(x, 3, c);
                    else
                        readVector(cs, pos, c);
                    for (int d = 0; d < 3; ++d) S.spinOffset[3 * i + d] = c[d] - x[d];
                    bool near = false;
                    for (int32_t q = S.pairStart[i]; q < S.pairStart[i + 1] && !near; ++q) {
                        const double* b = &box[6 * S.pairPiece[q]];
                        near = true;
                        for (int d = 0; d < 3 && near; ++d)
                            near = x[d] - S.radius[i] <= b[3 + d] && b[d] <= x[d] + S.radius[i];
                    }
                    if (near && cs != Py_None) {
                        // A clump member: its clump's motion at the member's place
                        // (YADE sets a member's own vel only in NewtonIntegrator:
                        // zero before the first step).
                        double vc[3], *wv = &S.angVel[3 * i];
                        readVector(cs, vel, vc);
                        readVector(cs, angVel, wv);
                        const double r[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
                        S.vel[3 * i] = vc[0] + wv[1] * r[2] - wv[2] * r[1];
                        S.vel[3 * i + 1] = vc[1] + wv[2] * r[0] - wv[0] * r[2];
                        S.vel[3 * i + 2] = vc[2] + wv[0] * r[1] - wv[1] * r[0];
                        ++full;
                    } else if (near) {
                        readVector(s, vel, &S.vel[3 * i]);
                        readVector(s, angVel, &S.angVel[3 * i]);
                        ++full;
                    } else {
                        for (int d = 0; d < 3; ++d) S.vel[3 * i + d] = S.angVel[3 * i + d] = 0.0;
                    }
                }
                return full;
            },
            py::arg("states"), py::arg("clumpStates") = py::none(),
            "Reads pos from YADE State objects (one per sphere, setSpheres order), and vel, angVel for those "
            "near a piece; clumpStates: per sphere its clump's State (a clump member) or None, whose pos is the "
            "spin centre; returns how many were near.")
        .def(
            "sphereForceTorque",
            [](const World& w) {
                const py::ssize_t n = w.spheres.size();
                py::array_t<double> a({n, py::ssize_t(6)});
                std::copy_n(w.spheres.forceTorque.data(), 6 * n, a.mutable_data());
                return a;
            },
            "Force and torque (n, 6) on each sphere in the last step.")
        .def(
            "applySphereForces",
            [](const World& w, const py::object& forces) {
                // O.forces.addF(id, (x, y, z)) and addT for spheres in contact: a
                // tuple converts to Vector3 in YADE at half the cost of a Vector3.
                const int32_t n = w.spheres.size();
                py::object addF = forces.attr("addF"), addT = forces.attr("addT");
                long applied = 0;
                for (int32_t i = 0; i < n; ++i) {
                    const double* ft = &w.spheres.forceTorque[6 * i];
                    if (!(ft[0] || ft[1] || ft[2] || ft[3] || ft[4] || ft[5])) continue;
                    py::int_ id(w.spheres.id[i]);
                    addF(id, py::make_tuple(ft[0], ft[1], ft[2]));
                    addT(id, py::make_tuple(ft[3], ft[4], ft[5]));
                    ++applied;
                }
                return applied;
            },
            py::arg("forces"),
            "Adds each sphere's contact force and torque to YADE's O.forces; returns how many spheres.");
}
