"""Minimal VTK XML writers (unstructured grid + PVD collection) for ParaView.
Binary (base64) arrays; every file is written to a temporary name and renamed,
so an interrupted run never leaves a truncated frame behind."""
import base64
import os
import struct

import numpy as np

_VTK_TETRA = 10
_TYPES = {np.dtype(np.float64): "Float64", np.dtype(np.float32): "Float32", np.dtype(np.int32): "Int32",
          np.dtype(np.int64): "Int64", np.dtype(np.uint8): "UInt8"}


def _dataArray(name, a, ncomp=None):
    a = np.ascontiguousarray(a)
    if a.dtype not in _TYPES:
        a = a.astype(np.float64)
    ncomp = ncomp or (a.shape[1] if a.ndim == 2 else 1)
    raw = a.tobytes()
    payload = base64.b64encode(struct.pack("<I", len(raw)) + raw).decode("ascii")
    return ('<DataArray type="%s" Name="%s" NumberOfComponents="%d" format="binary">%s</DataArray>\n'
            % (_TYPES[a.dtype], name, ncomp, payload))


def atomicWrite(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def writeVtu(path, points, tets, pointData=None, cellData=None):
    """Write tetrahedra with named point and cell arrays to a .vtu file."""
    points = np.asarray(points, dtype=np.float64)
    tets = np.asarray(tets, dtype=np.int64)
    for name, a in list((pointData or {}).items()) + list((cellData or {}).items()):
        if not np.all(np.isfinite(a)):
            raise ValueError("writeVtu: array %r holds NaN or infinite values; not writing %s" % (name, path))
    n, t = len(points), len(tets)
    out = ['<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian" '
           'header_type="UInt32">\n<UnstructuredGrid>\n<Piece NumberOfPoints="%d" NumberOfCells="%d">\n' % (n, t)]
    out.append("<PointData>\n")
    for k, a in (pointData or {}).items():
        out.append(_dataArray(k, a))
    out.append("</PointData>\n<CellData>\n")
    for k, a in (cellData or {}).items():
        out.append(_dataArray(k, a))
    out.append("</CellData>\n<Points>\n" + _dataArray("Points", points, 3) + "</Points>\n<Cells>\n")
    out.append(_dataArray("connectivity", tets.reshape(-1)))
    out.append(_dataArray("offsets", np.arange(4, 4 * t + 1, 4, dtype=np.int64)))
    out.append(_dataArray("types", np.full(t, _VTK_TETRA, dtype=np.uint8)))
    out.append("</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n")
    atomicWrite(path, "".join(out))


def writePvd(path, frames):
    """Write a ParaView collection: frames = [(time, relative vtu path), ...]."""
    rows = "".join('<DataSet timestep="%.10g" part="0" file="%s"/>\n' % (t, f) for t, f in frames)
    atomicWrite(path, '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n<Collection>\n'
                      + rows + "</Collection>\n</VTKFile>\n")
