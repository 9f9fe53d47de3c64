"""VTK output that ParaView reads right: unstructured-grid frames (.vtu,
zlib-compressed, written with VTK's own XML writer) and the .pvd collection
that strings them into a time series.  Every file is written to a temporary
name and renamed, so an interrupted run never leaves a truncated frame.

Symmetric tensors carry six components named in ParaView's order (XX, YY, ZZ,
XY, YZ, XZ), so its Tensor filters and component menus show the right ones."""
import os
from xml.sax.saxutils import quoteattr

import numpy as np

TENSOR6 = ("XX", "YY", "ZZ", "XY", "YZ", "XZ")


def _vtk():
    try:
        from vtkmodules.util import numpy_support
        from vtkmodules.vtkCommonCore import vtkPoints
        from vtkmodules.vtkCommonDataModel import VTK_TETRA, vtkCellArray, vtkUnstructuredGrid
        from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader, vtkXMLUnstructuredGridWriter
    except ImportError:
        raise RuntimeError("qdem: VTK output needs VTK's Python module: apt-get install python3-vtk9 "
                           "(make deps does it)") from None
    return dict(numpy_support=numpy_support, vtkPoints=vtkPoints, VTK_TETRA=VTK_TETRA, vtkCellArray=vtkCellArray,
                vtkUnstructuredGrid=vtkUnstructuredGrid, reader=vtkXMLUnstructuredGridReader,
                writer=vtkXMLUnstructuredGridWriter)


def _array(v, name, a, components=None):
    a = np.ascontiguousarray(a)
    if a.dtype not in (np.float64, np.float32, np.int32, np.int64, np.uint8):
        a = a.astype(np.float64)
    arr = v["numpy_support"].numpy_to_vtk(a, deep=True)
    arr.SetName(name)
    for k, c in enumerate(components or ()):
        arr.SetComponentName(k, c)
    return arr


def atomicWrite(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def writeVtu(path, points, tets, pointData=None, cellData=None, componentNames=None):
    """Write tetrahedra with named point and cell arrays to a compressed .vtu
    file.  componentNames maps an array name to its component names."""
    v = _vtk()
    points = np.ascontiguousarray(points, dtype=np.float64)
    tets = np.asarray(tets, dtype=np.int64)
    for name, a in list((pointData or {}).items()) + list((cellData or {}).items()):
        if not np.all(np.isfinite(a)):
            raise ValueError("writeVtu: array %r holds NaN or infinite values; not writing %s" % (name, path))
    grid = v["vtkUnstructuredGrid"]()
    pts = v["vtkPoints"]()
    pts.SetData(v["numpy_support"].numpy_to_vtk(points, deep=True))
    grid.SetPoints(pts)
    cells = v["vtkCellArray"]()
    offsets = np.arange(0, 4 * len(tets) + 1, 4, dtype=np.int64)
    cells.SetData(v["numpy_support"].numpy_to_vtkIdTypeArray(offsets, deep=True),
                  v["numpy_support"].numpy_to_vtkIdTypeArray(tets.reshape(-1).copy(), deep=True))
    grid.SetCells(v["VTK_TETRA"], cells)
    names = componentNames or {}
    for k, a in (pointData or {}).items():
        grid.GetPointData().AddArray(_array(v, k, a, names.get(k)))
    for k, a in (cellData or {}).items():
        grid.GetCellData().AddArray(_array(v, k, a, names.get(k)))
    w = v["writer"]()
    tmp = path + ".tmp.vtu"
    w.SetFileName(tmp)
    w.SetInputData(grid)
    w.SetDataModeToAppended()
    w.SetCompressorTypeToZLib()
    w.EncodeAppendedDataOff()
    if not w.Write():
        raise RuntimeError("writeVtu: VTK could not write %s" % path)
    os.replace(tmp, path)


def readVtu(path):
    """(points, {name: array}, {name: component names}) of a .vtu file, point and
    cell arrays together (for tests and post-processing)."""
    v = _vtk()
    r = v["reader"]()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    ns = v["numpy_support"]
    out, comps = {}, {}
    for data in (g.GetPointData(), g.GetCellData()):
        for i in range(data.GetNumberOfArrays()):
            a = data.GetArray(i)
            out[a.GetName()] = ns.vtk_to_numpy(a)
            comps[a.GetName()] = [a.GetComponentName(k) for k in range(a.GetNumberOfComponents())]
    return ns.vtk_to_numpy(g.GetPoints().GetData()), out, comps


def writePvd(path, frames):
    """Write a ParaView collection: frames = [(time, relative vtu path), ...]."""
    # quoteattr: a file name with &, <, " or ' would otherwise break the XML
    rows = "".join('<DataSet timestep="%.17g" part="0" file=%s/>\n' % (t, quoteattr(f)) for t, f in frames)
    atomicWrite(path, '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n<Collection>\n'
                      + rows + "</Collection>\n</VTKFile>\n")
