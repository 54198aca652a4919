"""A world's particles written to a VTK file and read back with VTK's own reader: the drop
scene after some frames, its positions, velocities, stresses, masses and materials in a VTK
XML unstructured grid (`.vtu`, a vertex per particle, binary arrays in the world's precision),
which `vtkXMLUnstructuredGridReader` reads back; every array is checked against the world's
views bit for bit. ParaView opens the file.

    python python/examples/vtk_roundtrip.py                 # writes drop.vtu (needs vtk)
    python python/examples/vtk_roundtrip.py --out /tmp/drop.vtu --frames 10 --precision f64

The writer is plain numpy (no VTK needed to write); reading back needs `pip install vtk`.
"""

import argparse
import base64

import numpy as np

import mpm_gimp

# The view's stress rows (2D: xx, yy, xy, zz; 3D: xx, yy, zz, xy, xz, yz) in the order VTK and
# ParaView give a symmetric tensor's 6 components (xx, yy, zz, xy, yz, xz); None: 0.
SYMMETRIC = {4: [0, 1, 3, 2, None, None], 6: [0, 1, 2, 3, 5, 4]}
VTK_VERTEX = 1


def per_point(column, components):
    """A (D, n) view as an (n, components) little-endian array, zeros past D (a copy)."""
    column = np.asarray(column)
    out = np.zeros((column.shape[-1], components), dtype=column.dtype.newbyteorder("<"))
    out[:, : column.shape[0]] = column.T
    return out


def symmetric(stress):
    stress = np.asarray(stress)
    out = np.zeros((stress.shape[-1], 6), dtype=stress.dtype.newbyteorder("<"))
    for k, row in enumerate(SYMMETRIC[stress.shape[0]]):
        if row is not None:
            out[:, k] = stress[row]
    return out


def data_array(array, name=None, components=1):
    """A binary `<DataArray>`: base64 of the byte count (UInt64), then base64 of the bytes."""
    kind = {"f4": "Float32", "f8": "Float64", "u4": "UInt32", "i8": "Int64", "u1": "UInt8"}
    array = np.ascontiguousarray(array, dtype=array.dtype.newbyteorder("<"))
    data = array.tobytes()
    encoded = base64.b64encode(np.uint64(len(data)).tobytes()) + base64.b64encode(data)
    named = f' Name="{name}"' if name else ""
    return (
        f'<DataArray type="{kind[array.dtype.str[1:]]}"{named} '
        f'NumberOfComponents="{components}" format="binary">\n{encoded.decode()}\n</DataArray>\n'
    )


def write_vtu(path, p):
    """Writes the particles `p` (`World.particles()`) as a `.vtu`: the positions as points, a
    vertex cell per particle, the velocity (3 components), stress (Kirchhoff over initial
    density, m^2/s^2, a symmetric tensor), mass and material as point data."""
    n = p.count
    text = [
        '<?xml version="1.0"?>\n'
        '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
        'header_type="UInt64">\n<UnstructuredGrid>\n'
        f'<Piece NumberOfPoints="{n}" NumberOfCells="{n}">\n<Points>\n',
        data_array(per_point(p.position, 3), components=3),
        "</Points>\n<Cells>\n",
        data_array(np.arange(n, dtype=np.int64), "connectivity"),
        data_array(np.arange(1, n + 1, dtype=np.int64), "offsets"),
        data_array(np.full(n, VTK_VERTEX, dtype=np.uint8), "types"),
        "</Cells>\n<PointData>\n",
        data_array(per_point(p.velocity, 3), "velocity", 3),
        data_array(symmetric(p.stress), "stress", 6),
        data_array(np.asarray(p.mass), "mass"),
        data_array(np.asarray(p.material), "material"),
        "</PointData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n",
    ]
    with open(path, "w") as f:
        f.write("".join(text))


def read_vtu(path):
    """The points and point data of a `.vtu`, as numpy arrays, by VTK's own reader."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader

    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()
    data = grid.GetPointData()
    out = {"position": vtk_to_numpy(grid.GetPoints().GetData())}
    for i in range(data.GetNumberOfArrays()):
        out[data.GetArrayName(i)] = vtk_to_numpy(data.GetArray(i))
    out["cells"] = grid.GetNumberOfCells()
    return out


def same_bits(a, b):
    """Equal shapes, dtypes and bytes (so -0.0 is not 0.0, and a NaN equals itself)."""
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="drop.vtu")
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--precision", choices=["f32", "f64"], default="f32")
    args = parser.parse_args()
    mpm = mpm_gimp if args.precision == "f32" else mpm_gimp.f64

    d = mpm.WorldDef(cells=(40, 40, 1), cell_size=0.025)
    d.faces[mpm.Face.Y_MIN] = mpm.Boundary.STICK
    w = mpm.World(d)
    w.fill_box((0.3, 0.4), (0.7, 0.7), w.add_material(mpm.MaterialDef()))
    for _ in range(args.frames):
        w.step(1 / 60)
    p = w.particles()
    write_vtu(args.out, p)
    print(f"wrote {args.out}: {p.count} particles at t = {w.diagnostics().time:.3f} s")

    got = read_vtu(args.out)
    d_axes = np.asarray(p.position).shape[0]
    stress = np.asarray(p.stress)
    checks = {
        "position": same_bits(got["position"][:, :d_axes].T, p.position),
        "velocity": same_bits(got["velocity"][:, :d_axes].T, p.velocity),
        "stress": all(
            same_bits(got["stress"][:, k], stress[row])
            for k, row in enumerate(SYMMETRIC[stress.shape[0]])
            if row is not None
        ),
        "mass": same_bits(got["mass"], p.mass),
        "material": same_bits(got["material"], p.material),
        "cells": got["cells"] == p.count,
    }
    for name, ok in checks.items():
        print(f"{name:9} {'bit for bit' if ok else 'DIFFERS'}")
    if not all(checks.values()):
        raise SystemExit("read back differs from the world")
    print(f"read back by VTK's reader: every array is the world's, bit for bit ({args.precision})")


if __name__ == "__main__":
    main()
