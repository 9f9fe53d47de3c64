"""Piece: the handle of one deformable body, with NumPy views of its nodes."""
import warnings

import numpy as np

from .attrs import boolean
from .stress import vonMises


class _HeldNodes(np.ndarray):
    """A read-only node array of a held piece (dynamic = False) whose writes
    say why they fail and the fix, not only NumPy's "assignment destination
    is read-only" (a YADE user moves fixed bodies by writing their state)."""

    def _refuse(self, *args, **kw):
        raise ValueError("piece %d is held (dynamic = False): its %s is read-only while it is held, since the "
                         "step leaves it where it is and a write would not take effect. Set piece.dynamic = True "
                         "first, then write (or keep it held and leave it)" % (self._pieceId, self._name))

    __setitem__ = __iadd__ = __isub__ = __imul__ = __itruediv__ = __ifloordiv__ = __ipow__ = __imod__ = _refuse
    __iand__ = __ior__ = __ixor__ = __ilshift__ = __irshift__ = _refuse

    def __array_finalize__(self, obj):
        self._pieceId = getattr(obj, "_pieceId", -1)
        self._name = getattr(obj, "_name", "array")


class Piece:
    """One QDEM piece in a world.  The array properties are NumPy *views* of the
    world's storage (writing ``piece.vel[:] = ...`` changes the simulation); take
    them again after adding pieces, since adding pieces moves the storage.
    Handing out a writable view wakes the piece if it sleeps (doc/sleeping.md):
    what is written to it then takes effect.

    The rule of its names: what the piece holds, and any sum or mean over its
    nodes that takes no argument (``totalMass``, ``volume``, ``centroid``,
    ``velocity``, ``momentum``, ``angularMomentum``), is a property; what the
    core computes per element on demand (``stress()``, ``vonMises()``,
    ``surface()``) or takes an argument (``angularMomentumAbout(point)``) is a
    method.  The former calls ``centroid()``, ``momentum()``, ``velocity()``
    and ``angularMomentum(about)`` still work, with a DeprecationWarning.

    Node order is the solver's (space-filling-curve) order; ``originalNodeIds[i]``
    is the index in the mesh you passed of solver node ``i``.  For a mesh read
    from a file (``qdem.loadMesh``, a path given to addPiece, or its
    ``splitMesh`` parts) it is the index of the point in the file, which
    differs from the Mesh's own index when the file has points no
    tetrahedron uses (loadMesh drops them; ``Mesh.nodeIds`` maps): nodes
    picked in the file (e.g. with meshio.read) are the solver nodes
    ``np.isin(piece.originalNodeIds, picked)``."""

    def __init__(self, world, pid, material, originalNodeIds):
        self.world, self.id, self._material = world, pid, material
        self._regionMaterials = None
        self.originalNodeIds = originalNodeIds
        n0, n1, t0, t1 = world.core.pieceRanges(pid)
        self.nodeSlice, self.tetSlice = slice(n0, n1), slice(t0, t1)

    @property
    def material(self):
        """The QdemMat the piece was added with (fixed: the world has compiled it in).
        For a bonded piece of several materials (addPiece's regionMaterials), its
        contact material: the softest of the materials on its surface."""
        return self._material

    @property
    def regionMaterials(self):
        """{region label: QdemMat} of a bonded piece of several materials
        (addPiece's regionMaterials; doc/meshes.md, "Regions and bimaterial
        parts"), None for a piece of one material."""
        return None if self._regionMaterials is None else dict(self._regionMaterials)

    @property
    def tetMaterial(self):
        """The QdemMat of each element, in solver order (a list as long as ``tets``)."""
        byIndex = {i: m for m, i in self.world._materialIndex.values()}
        return [byIndex[int(k)] for k in self.world.core.tetMaterial[self.tetSlice]]

    @material.setter
    def material(self, value):
        raise AttributeError("Piece.material is fixed when the piece is added (the assignment would be ignored). "
                             "Add the mesh again with the other material: qdem.addPiece(mesh, newMaterial, ...), "
                             "or start from a new QdemMat before addPiece.")

    # -- views -----------------------------------------------------------------
    def _live(self, name):
        """Refuses a handle of a scene that O.load replaced with other pieces:
        it would read the scene before the load, and what is written to it
        would go nowhere."""
        if getattr(self.world, "_replacedBy", None):
            raise RuntimeError("qdem: piece.%s of a piece of the scene before %s, which loaded a scene with other "
                               "pieces: this handle no longer steps. Take the loaded scene's pieces from "
                               "qdem.defaultWorld().pieces." % (name, self.world._replacedBy))

    def _nodes(self, name):
        """A node array of the world restricted to this piece (no waking)."""
        self._live(name)
        _requireCurrent(self.world.core, name)
        return getattr(self.world.core, name)[self.nodeSlice]

    def _writable(self, name):
        """A node array for writing: wakes the piece so that what is written
        takes effect; read-only while the piece is not dynamic (it is held
        where it is: set dynamic = True first)."""
        self._live(name)
        core = self.world.core
        _requireCurrent(core, name)
        # The script may change the state: the energy ledger check starts afresh
        # (QdemEngine._checkLedger), as energy put in by hand is no drift.
        self.world._stateEdited = True
        a = getattr(core, name)[self.nodeSlice]
        if not core.dynamic(self.id):
            a = a.view(_HeldNodes)
            a._pieceId, a._name = self.id, name
            a.flags.writeable = False
        elif core.nAsleep or core.nRigid:
            core.wake(self.id)  # (a rigid piece becomes deformable: its state is the nodes' again)
        return a

    @property
    def rigid(self):
        """Is the piece moving as a rigid body in its current shape (adaptive
        rigidity: QdemEngine.rigidify, doc/formulation.md)?"""
        return self.world.core.rigid(self.id)

    @property
    def asleep(self):
        """Is the piece asleep: at rest and left out of the step until something
        near it moves (QdemEngine.sleepVelocity, doc/sleeping.md)?"""
        return self.world.core.asleep(self.id)

    @property
    def dynamic(self):
        """Is the piece moved by the step (YADE's Body.dynamic)?  Set False, it
        stops where it is, as a sleeping piece that nothing wakes: awake pieces
        and spheres touch it as a fixed body, its push on the floor stays what
        it was, its kinetic energy goes to energy['sleep'].  Its pos, vel,
        extForce and blocked are read-only until it is set True again."""
        return self.world.core.dynamic(self.id)

    @dynamic.setter
    def dynamic(self, value):
        if boolean(value):  # ('no' would count as True, as it did)
            raise ValueError("Piece.dynamic=%r is invalid: must be True or False" % (value,))
        self.world.core.setDynamic(self.id, bool(value))

    @property
    def pos(self):
        """Node positions (n,3) [m], writable view (read-only while not dynamic)."""
        return self._writable("pos")

    @property
    def vel(self):
        """Node velocities (n,3) [m/s] at the last half step, writable view."""
        return self._writable("vel")

    @property
    def force(self):
        """Total force on each node in the last step (n,3) [N], read-only view."""
        _requireCurrent(self.world.core, "force")
        return self.world.core.force[self.nodeSlice]

    @property
    def extForce(self):
        """Persistent user force on each node (n,3) [N], writable view."""
        return self._writable("extForce")

    @property
    def refPos(self):
        """Reference (initial) node positions (n,3), read-only view."""
        return self.world.core.refPos[self.nodeSlice]

    @property
    def mass(self):
        """Lumped node masses (n,) [kg], read-only view (with the mass selective
        mass scaling added: addPiece(targetDt=...))."""
        return self.world.core.mass[self.nodeSlice]

    @property
    def contactWeight(self):
        """Per node (n,): the factor on its contact stiffness, its share of the
        surface area over the piece's mean share (0 for interior nodes;
        doc/contacts.md, "Area weights"); read-only view (set from the
        surface when the piece is added)."""
        a = self.world.core.contactWeight[self.nodeSlice].view()
        a.flags.writeable = False
        return a

    @property
    def blocked(self):
        """Per node bit mask of prescribed DOFs (1=x, 2=y, 4=z): those keep
        their velocity, like YADE's blockedDOFs.  Writable view."""
        return self._writable("blocked")

    @property
    def tets(self):
        """Tetrahedra (t,4) in piece-local node indices (a copy)."""
        return self.world.core.tets[self.tetSlice] - self.nodeSlice.start

    @property
    def displacement(self):
        """Node displacements from the reference shape (n,3) [m], rigid motion included (a copy)."""
        return self._nodes("pos") - self.refPos

    def stress(self):
        """Cauchy stress (t,6: xx yy zz yz xz xy) [Pa] of each tet, elastic + viscous."""
        self._live("stress")
        return self.world.core.stress()[self.tetSlice]

    def vonMises(self):
        """Von Mises stress of each tet [Pa]."""
        return vonMises(self.stress())

    def surface(self):
        """Surface triangles/edges/nodes/tets in piece-local indices."""
        s = self.world.core.pieceSurface(self.id)
        n0, t0 = self.nodeSlice.start, self.tetSlice.start
        return {"triangles": s["triangles"] - n0, "edges": s["edges"] - n0,
                "nodes": s["nodes"] - n0, "tets": s["tets"] - t0}

    # -- rigid-body summaries --------------------------------------------------
    # The rule (doc/reference/api.rst, "Piece"): a quantity of the piece --
    # what it holds, or a sum or mean over its nodes, taking no argument -- is
    # a property, read as a value like YADE's b.state.pos; per-element fields
    # the core computes on demand (stress(), vonMises()), the surface() lists
    # and anything taking an argument are methods.  centroid, momentum,
    # velocity and angularMomentum were methods: calling them still works,
    # with a DeprecationWarning (_Quantity).
    @property
    def totalMass(self):
        """Total mass of the piece [kg] (sum of the node masses)."""
        self._live("totalMass")
        return self.world.core.pieceMass(self.id)

    @property
    def volume(self):
        """Volume of the piece's reference (undeformed) mesh [m^3]."""
        return self.world.core.pieceVolume(self.id)

    # -- selective mass scaling (addPiece(targetDt=...), doc/meshes.md) ---------
    targetDt = None
    """The targetDt [s] the piece was added with (None: no mass scaling)."""

    @property
    def addedMass(self):
        """Mass added by selective mass scaling [kg] (0 without targetDt); part
        of totalMass, of the node masses and of the weight."""
        return self.world.core.pieceMassScaling(self.id)["addedMass"]

    @property
    def addedMassFraction(self):
        """addedMass over the piece's own mass rho V (what maxAddedMass bounds)."""
        d = self.world.core.pieceMassScaling(self.id)
        return d["addedMass"] / d["physicalMass"]

    @property
    def addedMassMaxNodeShare(self):
        """The largest share of added mass at one node: the mass added at that
        node over the node's own mass (rho V / 4 of its elements); at node
        ``addedMassMaxNode`` (piece-local, -1 without added mass)."""
        return self.world.core.pieceMassScaling(self.id)["maxNodeShare"]

    @property
    def addedMassMaxNode(self):
        """The node (piece-local index) with the largest addedMassMaxNodeShare, -1 if none."""
        return self.world.core.pieceMassScaling(self.id)["maxNode"]

    @property
    def addedMassPerTet(self):
        """Mass added to each tetrahedron [kg] (t,), read-only view; a quarter
        of it sits on each of the tet's nodes."""
        return self.world.core.tetAddedMass[self.tetSlice]

    @property
    def centroid(self):
        """Centre of mass (3,) [m]."""
        m = self.mass
        return _Quantity.of((self._nodes("pos") * m[:, None]).sum(axis=0) / m.sum(), "centroid")

    @property
    def momentum(self):
        """Linear momentum (3,), the sum of m v [kg m/s]."""
        return _Quantity.of((self._nodes("vel") * self.mass[:, None]).sum(axis=0), "momentum")

    @property
    def velocity(self):
        """Centre-of-mass velocity (3,) [m/s]."""
        return _Quantity.of(np.asarray(self.momentum) / self.mass.sum(), "velocity")

    @property
    def angularMomentum(self):
        """Angular momentum about the centre of mass (3,) [kg m^2/s]; about
        another point: angularMomentumAbout(point)."""
        return _Quantity.of(self.angularMomentumAbout(None), "angularMomentum",
                            call=lambda about=None: self.angularMomentumAbout(about),
                            instead="angularMomentumAbout(point)")

    def angularMomentumAbout(self, point=None):
        """Angular momentum (3,) [kg m^2/s] about a point (None: the centre of mass)."""
        c = np.asarray(self.centroid) if point is None else np.asarray(point, dtype=float)
        return (np.cross(self._nodes("pos") - c, self._nodes("vel")) * self.mass[:, None]).sum(axis=0)

    def __repr__(self):
        return "<qdem.Piece %d: %d nodes, %d tets>" % (
            self.id, self.nodeSlice.stop - self.nodeSlice.start, self.tetSlice.stop - self.tetSlice.start)


def _requireCurrent(core, name):
    """Under MPI a rank keeps only its own nodes and their halo current
    between gathers (QdemEngine.gatherPeriod, doc/parallel.md): reading a
    stale array would be a silently wrong answer."""
    if not core.stateCurrent:
        raise RuntimeError(
            "qdem: piece.%s on rank %d of %d is not current at step %d: under MPI every rank learns every node's "
            "state only every QdemEngine.gatherPeriod steps. Read it at those steps, set gatherPeriod=1, or call "
            "world.core.gatherAll() on every rank first." % (name, core.mpiRank, core.mpiSize, core.iter))


class _Quantity(np.ndarray):
    """The value of a Piece quantity that used to be a method (centroid(),
    momentum(), ...): an ordinary array that may still be called, as the old
    spelling did, with a DeprecationWarning.  Arithmetic on it gives plain
    arrays."""

    @classmethod
    def of(cls, value, name, call=None, instead=None):
        q = np.asarray(value).view(cls)
        q._name, q._call, q._instead = name, call, instead or name
        return q

    def __array_finalize__(self, obj):
        self._name = getattr(obj, "_name", "quantity")
        self._call = getattr(obj, "_call", None)
        self._instead = getattr(obj, "_instead", self._name)

    def __array_wrap__(self, arr, context=None, *args):
        arr = np.asarray(arr)
        return arr[()] if arr.ndim == 0 else arr

    def __call__(self, *args, **kw):
        warnings.warn("Piece.%s() is deprecated: Piece.%s is a property (read it without parentheses%s)"
                      % (self._name, self._name,
                         "" if self._instead == self._name else "; with an argument: Piece." + self._instead),
                      DeprecationWarning, stacklevel=2)
        if self._call is not None:
            return self._call(*args, **kw)
        if args or kw:
            raise TypeError("Piece.%s takes no arguments" % self._name)
        return np.asarray(self).copy()

    def __repr__(self):
        return repr(np.asarray(self))

    def __str__(self):
        return str(np.asarray(self))

    def __reduce__(self):
        return np.asarray(self).__reduce__()
