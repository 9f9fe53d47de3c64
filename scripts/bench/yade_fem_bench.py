# YADE tetrahedral-FEM cost benchmark (reference figure for the QDEM element).
#
#   yade -n -x scripts/bench/yade_fem_bench.py [--cells 8] [--cubes 1] [--steps N]
#        [--dt 1e-7] [--target-seconds 8] [--out out/bench/yade_fem.json]
#   (OpenMP threads are set by yade itself: `yade -j 2 -n -x ...`)
#
# Scene, as in YADE's FEMLIKE examples (examples/deformableelem, yade.deformableelementsutils):
# every node is a Body with a Node shape, every tetrahedron is its own Body whose shape is a
# Lin4NodeTetra (a DeformableElement) holding its 4 nodes via addNode(); engines are
# ForceResetter, FEInternalForceEngine([If2_Lin4NodeTetra_LinIsoRayleighDampElast()]) and
# NewtonIntegrator. Unlike the examples (one private node set per element, glued by
# Lin4NodeTetra_Lin4NodeTetra_InteractionElement) the nodes are shared between the tets of
# a cube: addNode only records the node's reference position and the functor accumulates its
# forces in O.forces, so a shared-node conforming mesh works and matches the QDEM benchmark.
import json, os, resource, sys, time, traceback
import numpy as np
import yade.config
from yade import O
from yade.minieigenHP import Vector3
try:  # FEM classes exist only in yade builds with the FEMLIKE feature
    from yade.wrapper import (Body, Node, Lin4NodeTetra, LinIsoRayleighDampElastMat, ForceResetter,
                              FEInternalForceEngine, If2_Lin4NodeTetra_LinIsoRayleighDampElast,
                              NewtonIntegrator)
    IMPORT_ERROR = None
except ImportError as exc:
    IMPORT_ERROR = 'yade %s lacks FEMLIKE classes: %s' % (yade.config.version, exc)


def parse_args(argv):
    opts = {'cells': 8, 'cubes': 1, 'steps': 0, 'dt': 1e-7, 'size': 1.0, 'warmup': 3,
            'target_seconds': 8.0, 'out': 'out/bench/yade_fem.json'}
    it = iter(argv)
    for a in it:
        key, _, val = a.lstrip('-').replace('-', '_').partition('=')
        if key not in opts:
            raise SystemExit('unknown argument %r; known: %s' % (a, ', '.join('--' + k for k in opts)))
        val = val or next(it)
        opts[key] = type(opts[key])(val)
    return opts


def box_mesh(n, L):
    """Structured n^3-cell cube of edge L centred at 0: 12 tets per cell around a body-centre
    node; each cell face is cut along the diagonal through its smallest global node id (so
    neighbouring cells agree) and each triangle is coned to the centre. Output is identical
    (nodes, tet order, orientation) to pkg/mesh/BoxMesh.cpp boxMesh(n,n,n,L,L,L,12)."""
    g = n + 1
    k, j, i = np.meshgrid(np.arange(g), np.arange(g), np.arange(g), indexing='ij')
    grid = np.stack([i, j, k], -1).reshape(-1, 3) * (L / n) - 0.5 * L
    k, j, i = [a.ravel() for a in np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing='ij')]
    centres = np.stack([i, j, k], -1) * (L / n) + (0.5 * L / n - 0.5 * L)
    cid = g ** 3 + np.arange(n ** 3)
    v = lambda a, b, c: ((k + c) * g + (j + b)) * g + (i + a)
    faces = np.stack([np.stack([v(*p) for p in quad], -1) for quad in (
        ((0, 0, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1)), ((1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)),
        ((0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)), ((0, 1, 0), (1, 1, 0), (1, 1, 1), (0, 1, 1)),
        ((0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)), ((0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)))], 1)
    rot = (np.argmin(faces, 2)[..., None] + np.arange(4)) % 4          # smallest id first
    q = np.take_along_axis(faces, rot, 2)                                # (cells, 6, 4)
    c = np.broadcast_to(cid[:, None], q.shape[:2])
    tets = np.stack([np.stack([q[..., 0], q[..., 1], q[..., 2], c], -1),   # cell, face, triangle
                     np.stack([q[..., 0], q[..., 2], q[..., 3], c], -1)], 2).reshape(-1, 4)
    nodes = np.concatenate([grid, centres])
    neg = signed_volumes(nodes, tets) < 0                                # make all positive
    tets[neg] = tets[neg][:, [0, 1, 3, 2]]                              # as orientPositive()
    return nodes, tets


def signed_volumes(x, t):
    a, b, c, d = (x[t[:, m]] for m in range(4))
    return np.einsum('ij,ij->i', np.cross(b - a, c - a), d - a) / 6.0


def build_mesh(cells, cubes, L):
    """`cubes` disjoint copies of the cube on a m x m x m lattice (m = ceil(cubes^(1/3)))."""
    x0, t0 = box_mesh(cells, L)
    m = int(np.ceil(round(cubes ** (1.0 / 3.0), 9)))
    xs, ts = [], []
    for c in range(cubes):
        xs.append(x0 + 1.5 * L * np.array([c % m, (c // m) % m, c // (m * m)]))
        ts.append(t0 + c * len(x0))
    return np.concatenate(xs), np.concatenate(ts)


def build_scene(x, tets, dt, L):
    """Nodes (lumped mass, bottom face of each cube clamped) + one Lin4NodeTetra body per tet."""
    O.reset()
    mat = LinIsoRayleighDampElastMat(youngmodulus=5e8, poissonratio=0.4, density=700.0,
                                     alpha=0.0, beta=0.0, label='fem')
    O.materials.append(mat)
    vol = signed_volumes(x, tets)
    assert vol.min() > 0, 'non-positive tet volume'
    mass = np.zeros(len(x))
    np.add.at(mass, tets.ravel(), np.repeat(mat.density * vol / 4.0, 4))
    zmin = x[:, 2].min()    # bottom z of each cube (cube layers are 1.5 L apart)
    zcube = np.floor((x[:, 2] - zmin) / (1.5 * L) + 1e-9) * 1.5 * L + zmin
    clamped = np.abs(x[:, 2] - zcube) < 1e-9 * L
    radius = 0.1 * (0.75 * vol.mean()) ** (1 / 3.0)   # display only, as in YADE's examples
    nodes = []
    for p, mm, fix in zip(x, mass, clamped):
        b = Body(shape=Node(radius=radius), material=mat)
        b.state.pos = b.state.refPos = Vector3(*p)
        b.state.mass, b.state.inertia = mm, Vector3(1, 1, 1)
        b.state.blockedDOFs = 'xyzXYZ' if fix else 'XYZ'   # nodes carry no rotations
        b.bounded = False
        nodes.append(b)
    O.bodies.append(nodes)                    # nodes need ids before addNode
    elems = []
    for t in tets.tolist():
        e = Body(shape=Lin4NodeTetra(), material=mat)
        for nid in t:
            e.shape.addNode(nodes[nid])
        e.state.blockedDOFs = 'xyzXYZ'      # element body is only a container
        e.state.mass = 1.0
        e.bounded = False
        elems.append(e)
    O.bodies.append(elems)
    fem = FEInternalForceEngine([If2_Lin4NodeTetra_LinIsoRayleighDampElast()])
    O.engines = [ForceResetter(), fem, NewtonIntegrator(damping=0.0, gravity=(0, 0, -9.81))]
    O.dt = dt
    return fem, np.flatnonzero(~clamped)


def main(opts):
    res = {'tets': None, 'nodes': None, 'steps': 0, 'threads': O.numThreads, 'cells': opts['cells'],
           'cubes': opts['cubes'], 'dt': opts['dt'], 'yade_fem_ns_per_tet_step': None,
           'yade_fem_engine_ns_per_tet_step': None}
    try:
        if IMPORT_ERROR:
            raise RuntimeError(IMPORT_ERROR)
        if opts['cells'] < 1 or opts['cubes'] < 1:
            raise ValueError('--cells and --cubes must be >= 1')
        t0 = time.perf_counter()
        x, tets = build_mesh(opts['cells'], opts['cubes'], opts['size'])
        res.update(tets=len(tets), nodes=len(x))
        fem, free = build_scene(x, tets, opts['dt'], opts['size'])
        res['build_s'] = time.perf_counter() - t0
        O.timingEnabled = True
        # warm-up: the first step builds every element's 12x12 M^-1 K matrix
        t1 = time.perf_counter()
        O.run(1, True)
        res['first_step_s'] = time.perf_counter() - t1
        O.run(opts['warmup'], True)
        n = opts['steps']
        if not n:  # calibrate: double the run length until it takes >= 0.3 s
            k = 1
            while True:
                t1 = time.perf_counter()
                O.run(k, True)
                el = time.perf_counter() - t1
                if el >= 0.3:
                    break
                k *= 2
            n = max(3, int(opts['target_seconds'] * k / el))
        res['loadavg_1min_before'] = os.getloadavg()[0]   # other jobs on the box skew timings
        # O.run(n, True) polls for completion (~40 ms granularity): keep the timed run long
        e0, w0, c0 = fem.execTime, time.perf_counter(), time.process_time()
        O.run(n, True)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        eng = fem.execTime - e0   # ns, FEInternalForceEngine only
        res.update(steps=n, wall_s=wall,
                   yade_fem_ns_per_tet_step=wall * 1e9 / (n * len(tets)),
                   yade_fem_engine_ns_per_tet_step=eng / (n * len(tets)),
                   cpu_ns_per_tet_step=cpu * 1e9 / (n * len(tets)))   # all threads' CPU time
        # sanity: nodes moved and the FEM produced internal forces (gravity is not in O.forces)
        disp = np.array([(O.bodies[int(i)].state.pos - O.bodies[int(i)].state.refPos).norm() for i in free])
        fmax = max(O.forces.f(int(i)).norm() for i in free)
        res.update(max_node_disp=float(disp.max()), disp_spread=float(disp.max() - disp.min()),
                   max_internal_force=float(fmax), peak_rss_MB=resource.getrusage(
                       resource.RUSAGE_SELF).ru_maxrss / 1024.0)
        if not (disp.max() > 0 and fmax > 0):
            res['error'] = 'sanity check failed: no node moved or no internal force'
        res['note'] = ('YADE %s FEMLIKE: one Lin4NodeTetra body per tet, shared Node bodies, '
                       'If2_Lin4NodeTetra_LinIsoRayleighDampElast (small-strain linear, dense 12x12 '
                       'M^-1 K per element), bottom faces clamped, gravity on; %d cube(s) of %d^3 cells; '
                       'whole-step figure includes NewtonIntegrator over nodes+element bodies; engine '
                       'figure is FEInternalForceEngine.execTime (also loops over node bodies)'
                       % (yade.config.version, opts['cubes'], opts['cells']))
    except Exception as exc:  # report, never crash the driver
        traceback.print_exc()
        res.update(yade_fem_ns_per_tet_step=None, yade_fem_engine_ns_per_tet_step=None,
                   error='%s: %s' % (type(exc).__name__, exc))
    return res


opts = parse_args(sys.argv[1:])
res = main(opts)
print("\n" + json.dumps(res), flush=True)  # yade's C++ couts lack a newline
os.makedirs(os.path.dirname(os.path.abspath(opts['out'])), exist_ok=True)
with open(opts['out'], 'w') as f:
    json.dump(res, f, indent=2)
sys.stdout.flush()
os._exit(0)   # skip tearing down ~10^5 bodies (and yade's shell) at exit
