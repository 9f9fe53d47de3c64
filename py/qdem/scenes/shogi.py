"""Shogi pieces: the seed paper's application (its section 5).

One pentagonal shape for all eight kinds -- interior angles 81, 81, 117, 117
and 144 degrees, thinner at the top than at the base -- scaled per kind after
real pieces.  The king (32 x 28.7 x 9.7 mm: height x base width x base
thickness) and the pawn (27 x 22.5 x 7.75 mm) are the sizes the design brief
gives; the kinds in between are interpolated linearly by rank.
"""
import math
import warnings

import numpy as np

from ..mesh import meshSurface
from ..world import World, defaultWorld

# Rank 0 = largest.  (height, base width, base thickness) in mm.
_KING = np.array([32.0, 28.7, 9.7])
_PAWN = np.array([27.0, 22.5, 7.75])
ORDER = ["king", "rook", "bishop", "gold", "silver", "knight", "lance", "pawn"]
KINDS = {k: tuple(_KING + (_PAWN - _KING) * i / (len(ORDER) - 1)) for i, k in enumerate(ORDER)}
# One player's set: 20 pieces.
SET = ["king", "rook", "bishop", "gold", "gold", "silver", "silver", "knight", "knight", "lance", "lance"] + \
    ["pawn"] * 9

BASE_ANGLE, SHOULDER_ANGLE = 81.0, 117.0    # apex = 540 - 2*81 - 2*117 = 144 degrees
TOP_THICKNESS_RATIO = 0.7                   # thickness at the apex / at the base


def outline(height, width):
    """Pentagon (5, 2) counter-clockwise from the left base corner, base on y = 0,
    apex at (0, height): base angles 81, shoulders 117, apex 144 degrees."""
    a1 = math.radians(180.0 - BASE_ANGLE)            # direction of the right side (99 deg)
    a2 = a1 + math.radians(180.0 - SHOULDER_ANGLE)   # upper right edge (162 deg)
    # Right side length s1 and upper edge s2 put the apex at (0, height).
    A = np.array([[math.cos(a1), math.cos(a2)], [math.sin(a1), math.sin(a2)]])
    s1, s2 = np.linalg.solve(A, [-width / 2, height])
    if s1 <= 0 or s2 <= 0:
        raise ValueError("shogi outline: height %g and width %g do not fit the angles" % (height, width))
    B = np.array([width / 2, 0.0])
    C = B + s1 * np.array([math.cos(a1), math.sin(a1)])
    D = np.array([0.0, height])
    return np.array([[-width / 2, 0.0], B, C, D, [-C[0], C[1]]])


def surface(kind, scale=1.0):
    """Closed triangle surface of one piece: (vertices (10,3), triangles (16,3)).
    x across, y up (base at y = 0), z through the thickness; metres = mm * scale / 1000."""
    if kind not in KINDS:
        raise ValueError("unknown shogi piece %r; kinds: %s" % (kind, ", ".join(ORDER)))
    h, w, t = (v * scale * 1e-3 for v in KINDS[kind])
    p = outline(h, w)
    half = 0.5 * t * (1 + (TOP_THICKNESS_RATIO - 1) * p[:, 1] / h)   # thinner towards the apex
    front = np.column_stack([p, half])
    back = np.column_stack([p, -half])
    verts = np.vstack([front, back])
    tris = [(0, 1, 2), (0, 2, 3), (0, 3, 4)]                 # front (+z), CCW seen from +z
    tris += [(5 + c, 5 + b, 5 + a) for a, b, c in tris]      # back, reversed
    for i in range(5):
        j = (i + 1) % 5
        tris += [(i, 5 + i, 5 + j), (i, 5 + j, j)]           # sides, outward
    return verts, np.array(tris, dtype=np.int32)


def mesh(kind, scale=1.0, nodes=797, tolerance=0.05, seed=0):
    """Tetrahedral mesh of a piece with CGAL.  The seed's pieces have 797 nodes
    and 2,566 tets: 3.2 tets per node, i.e. most nodes on the surface of these
    thin pieces.  Cells 1.45 times the surface triangle size give that ratio
    (measured: 3.1-3.3); the surface size is searched until the node count is
    within `tolerance`."""
    verts, tris = surface(kind, scale)
    h, w, t = (v * scale * 1e-3 for v in KINDS[kind])
    lo, hi = h / 60, h / 2
    best = None
    for _ in range(30):
        size = math.sqrt(lo * hi)
        m = meshSurface((verts, tris), cellSize=1.45 * size, surfaceSize=size, seed=seed)
        err = m.nNodes / nodes - 1
        if best is None or abs(err) < abs(best[0]):
            best = (err, m)
        if abs(err) <= tolerance:
            break
        if m.nNodes > nodes:
            lo = size
        else:
            hi = size
    return best[1]


def volume(kind, scale=1.0):
    """Exact volume of a piece [m^3]: pentagon area times the thickness at the
    area's centroid height (the thickness varies linearly with height)."""
    h, w, t = (v * scale * 1e-3 for v in KINDS[kind])
    p = outline(h, w)
    x, y = p[:, 0], p[:, 1]
    xs, ys = np.roll(x, -1), np.roll(y, -1)
    cross = x * ys - xs * y
    area = 0.5 * cross.sum()
    cy = ((y + ys) * cross).sum() / (6 * area)
    return area * t * (1 + (TOP_THICKNESS_RATIO - 1) * cy / h)


def stableScale(material, dt=6.4e-6, kinds=ORDER, margin=1.05):
    """Smallest length scale (times real size) at which `dt` is stable for
    every kind of piece meshed as by mesh(): the stable step of these meshes
    grows as scale^2 when viscosity limits it and as scale when elasticity
    does, so the scale is found from one mesh per kind at real size."""
    need = 1.0
    for k in kinds:
        w = World()
        # The probe's pieces are at real size with the material's radius as
        # given (the scale is what is sought): addPiece's advice on a radius
        # large against the piece is about this probe, not the user's scene.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            w.addPiece(mesh(k), material)
            w.addPiece(mesh(k), material, pos=(1.0, 0, 0))   # two pieces: the contact limit counts too
        d = w.stableDt()
        for limit, power in ((d["viscous"], 2), (d["elastic"], 1), (d["contact"], 1)):
            need = max(need, (margin * dt / limit) ** (1.0 / power))
    return need


# Standing pieces: local x (width) -> world y, local y (height) -> world z,
# local z (thickness) -> world x, the direction the line topples in.
STANDING = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def dominoLine(kinds, material, scale=1.0, spacing=0.5, push=1.0, offsets=None, xs=None, world=None):
    """Stand pieces of the given kinds in a line along +x on a floor at z = 0,
    `spacing` times the tallest height apart (centre to centre), and tip the
    first one towards the second with angular velocity `push` [rad/s] about
    its base.  offsets: optional sideways (y) shift of each piece [m], for
    eccentric hits; xs: optional positions along the line, in units of the
    spacing (default 0, 1, 2, ...).  Returns the list of Pieces (meshes are
    made once per kind)."""
    world = world or defaultWorld()
    meshes = {}
    hMax = max(KINDS[k][0] for k in kinds) * scale * 1e-3
    pieces = []
    for i, k in enumerate(kinds):
        if k not in meshes:
            meshes[k] = mesh(k).scaled(scale)
        y = 0.0 if offsets is None else offsets[i]
        x = (i if xs is None else xs[i]) * spacing * hMax
        pos = (x, y, material.radius)                          # base one particle radius above the floor
        angVel = (0.0, push, 0.0) if i == 0 else (0.0, 0.0, 0.0)
        pieces.append(world.addPiece(meshes[k], material, pos=pos, ori=STANDING, angVel=angVel))
    return pieces


SCENES = {
    # seed Figure 7: two rooks
    "two_rooks": dict(kinds=["rook", "rook"]),
    # seed Figure 8: a king hitting two pawns side by side, off centre
    "king_pawns": dict(kinds=["king", "pawn", "pawn"], xs=[0, 1, 1], offsets=[0.0, 0.47, -0.42]),
    # seed Figures 9 and 10: both players' 20 pieces in one line
    "forty": dict(kinds=SET + SET),
}


def scene(name, material, scale, spacing=0.8, push=None, world=None, count=None):
    """Build one of the seed's scenes (SCENES) with pieces `scale` times real
    size.  Sideways offsets are in units of the largest height.  The first
    piece is tipped with an angular velocity that takes it past its balance
    point.  Spacing 0.8 heights: at 0.5-0.6 a toppled piece comes to rest
    leaning on the next without tipping it (measured with three rooks).
    count: only the first `count` pieces of the line.  Returns the Pieces."""
    spec = dict(SCENES[name])
    if count:
        for k in ("kinds", "offsets", "xs"):
            if k in spec:
                spec[k] = spec[k][:count]
    hMax = max(KINDS[k][0] for k in SCENES[name]["kinds"]) * scale * 1e-3  # the whole line's: same spacing
    offsets = [o * hMax for o in spec["offsets"]] if "offsets" in spec else None
    if push is None:  # about 2.6x the angular velocity that just tips a piece over (0.38 sqrt(g/H))
        push = 1.0 * math.sqrt(9.81 / hMax)
    return dominoLine(spec["kinds"], material, scale=scale, spacing=spacing, push=push, offsets=offsets,
                      xs=spec.get("xs"), world=world)

__all__ = ["outline", "surface", "mesh", "volume", "stableScale", "dominoLine", "scene"]
