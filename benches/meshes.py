#!/usr/bin/env python3
"""Large tetrahedral meshes for the volume's trade (issue 16, items 5 and 7), never committed:
writes into target/meshes/ files that the scenes under scenes/meshes/ name.

    python3 benches/meshes.py                     # generated meshes; needs numpy only
    python3 benches/meshes.py nasa                # the NASA CFD meshes, downloaded
    python3 benches/meshes.py nasa --source DIR   # the same from a folder of the .bin files

Generated:
- `kuhn-200k.vtu`: the seed's Kuhn grid at 33^3 points (196,608 tetrahedra), the spherical
  field (`arbvis study --technique cellproj-volume --grids 33` makes the same one in memory).
- `bracket-like-1m.vtu`: about a million tetrahedra of a non-convex part, a box with a
  cylindrical and a spherical hole like the gmsh bracket in data/tets (which was
  written by gmsh from a short geometry script: 40,710 tetrahedra), made here by cutting the
  holes out of a 56^3 Kuhn grid (a staircase boundary, which is what order errors need), with
  a "temperature" field falling off from one face.

NASA CFD solutions (`nasa`): the structured PLOT3D grids behind the meshes that papers on
unstructured volume rendering have shown since the 1990s (Blunt Fin: 187,395 tetrahedra;
Oxygen Post: 513,375; Combustion Chamber: 215,040; e.g. Callahan et al. 2005, HAVS), taken
from the pyvista/vtk-data repository at a pinned commit (the files are VTK's test data,
distributed under VTK's BSD-3 notice, Copyright.txt there; the solutions are NASA's: blunt
fin by Hung and Buning, the liquid-oxygen post from NASA Ames), each checked against its
SHA-256, and split here into linear tetrahedra: 5 per hexahedron, the pattern alternating
with the parity of i + j + k so that neighbouring hexahedra cut their shared face along the
same diagonal (a conforming mesh, checked: no face is shared by more than two tetrahedra),
each tetrahedron turned to positive volume. Written as legacy VTK (binary) with the point
scalars Density, Pressure (gamma 1.4), VelocityMagnitude and StagnationEnergy.
"""

import hashlib
import os
import sys
import urllib.request

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))
from peer_common import kuhn_tets  # noqa: E402


def fix_orientation(pts, tets):
    p = pts[tets]
    det = np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))
    neg = det < 0
    tets[neg, 2], tets[neg, 3] = tets[neg, 3].copy(), tets[neg, 2].copy()
    return tets


def write_vtu(path, pts, tets, name, values):
    with open(path, "w") as f:
        f.write('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0">\n'
                f'<UnstructuredGrid><Piece NumberOfPoints="{len(pts)}" NumberOfCells="{len(tets)}">\n'
                f'<PointData Scalars="{name}"><DataArray type="Float64" Name="{name}" format="ascii">\n')
        np.savetxt(f, values, fmt="%.9g")
        f.write('</DataArray></PointData>\n<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">\n')
        np.savetxt(f, pts, fmt="%.9g")
        f.write('</DataArray></Points>\n<Cells><DataArray type="Int64" Name="connectivity" format="ascii">\n')
        np.savetxt(f, tets, fmt="%d")
        f.write('</DataArray><DataArray type="Int64" Name="offsets" format="ascii">\n')
        np.savetxt(f, np.arange(4, 4 * len(tets) + 1, 4), fmt="%d")
        f.write('</DataArray><DataArray type="UInt8" Name="types" format="ascii">\n')
        np.savetxt(f, np.full(len(tets), 10), fmt="%d")
        f.write("</DataArray></Cells></Piece></UnstructuredGrid></VTKFile>\n")


# pyvista/vtk-data at this commit: Data/<name>xyz.bin and Data/<name>q.bin.
NASA_COMMIT = "126ee906165a8b2f984f08259a4a2d32cf3b3409"
NASA_URL = f"https://raw.githubusercontent.com/pyvista/vtk-data/{NASA_COMMIT}/Data/"
NASA_FILES = {
    "bluntfinxyz.bin": "b0748b066152c7001d2979245e729da32b44eb6f171b0c49cf6ed0eb84fe0e6a",
    "bluntfinq.bin": "1fa8642d08f6bbbda6a7bc95571a06ec26afa8abac556a7330bfc74b60899397",
    "postxyz.bin": "578733b095c9a4776ad35c11c0e0f95a563bd7e9da0922045620c09991992da6",
    "postq.bin": "25ac2ed16d9df263541f3daa1ddda097210f31ca73b192cbac9d5182c042adfb",
    "combxyz.bin": "75e20a039c7bfc02d724ef18a411ef27cbf8977926d0f4b0208ca28817e1288f",
    "combq.bin": "a59dfe6faa76d4bc1b82a718636742e1a7220d06da17bb1ee5ab815432f9baea",
}
# (output, PLOT3D name)
NASA_MESHES = [("bluntfin.vtk", "bluntfin"), ("oxygen-post.vtk", "post"), ("combustion.vtk", "comb")]


def nasa_bytes(name, source):
    """A PLOT3D file's bytes from `source` (a folder) or downloaded, checked against its hash."""
    if source:
        try:
            with open(os.path.join(source, name), "rb") as f:
                data = f.read()
        except OSError as e:
            sys.exit(f"{os.path.join(source, name)}: {e.strerror}")
    else:
        try:
            with urllib.request.urlopen(NASA_URL + name, timeout=60) as r:
                data = r.read()
        except OSError as e:
            sys.exit(f"{NASA_URL + name}: {e} (without a network, fetch pyvista/vtk-data's "
                     f"Data/{name} at {NASA_COMMIT} some other way and pass --source DIR)")
    digest = hashlib.sha256(data).hexdigest()
    if digest != NASA_FILES[name]:
        sys.exit(f"{name}: SHA-256 {digest}, expected {NASA_FILES[name]} (a different file)")
    return data


def plot3d_grid(data, name):
    """A single-grid PLOT3D xyz file (big-endian, no Fortran record markers): (ni, nj, nk)
    and the points, i varying fastest (the Oxygen Post's IBLANK array after them unused)."""
    dims = tuple(int(v) for v in np.frombuffer(data, ">i4", 3, 0))
    n = dims[0] * dims[1] * dims[2]
    if len(data) < 12 + 12 * n:
        sys.exit(f"{name}: {len(data)} bytes, a {dims} grid needs {12 + 12 * n}")
    return dims, np.frombuffer(data, ">f4", 3 * n, 12).reshape(3, n).T.astype(np.float64)


def plot3d_solution(data, dims, name):
    """A PLOT3D q file: its dimensions (must be the grid's), four floats (Mach, alpha,
    Reynolds number, time), then density, the three momenta and the stagnation energy."""
    if tuple(int(v) for v in np.frombuffer(data, ">i4", 3, 0)) != dims:
        sys.exit(f"{name}: not the grid's dimensions {dims}")
    n = dims[0] * dims[1] * dims[2]
    if len(data) < 28 + 20 * n:
        sys.exit(f"{name}: {len(data)} bytes, a {dims} solution needs {28 + 20 * n}")
    return np.frombuffer(data, ">f4", 5 * n, 28).reshape(5, n).astype(np.float64)


def hex_tets(dims):
    """5 tetrahedra per cell of a structured grid, alternating with the parity of i + j + k."""
    ni, nj, nk = dims
    i, j, k = (a.ravel() for a in np.meshgrid(
        np.arange(ni - 1), np.arange(nj - 1), np.arange(nk - 1), indexing="ij"))
    corner = [(i + di) + ni * ((j + dj) + nj * (k + dk))
              for dk in (0, 1) for dj in (0, 1) for di in (0, 1)]
    # Corners numbered di + 2 dj + 4 dk: four corner tetrahedra and the one between them.
    even = [(0, 1, 2, 4), (3, 2, 1, 7), (5, 4, 7, 1), (6, 7, 4, 2), (1, 2, 4, 7)]
    odd = [(1, 0, 3, 5), (2, 3, 0, 6), (4, 5, 6, 0), (7, 6, 5, 3), (0, 3, 5, 6)]
    parity = ((i + j + k) % 2).astype(bool)
    return np.concatenate([
        np.stack([np.where(parity, corner[o[m]], corner[e[m]]) for m in range(4)], axis=1)
        for e, o in zip(even, odd)])


def check_conforming(tets, name):
    """No face shared by more than two tetrahedra (a face cut along two diagonals would
    leave four half-faces, each once: counted by the boundary faces' total)."""
    faces = np.sort(np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]],
                                    tets[:, [0, 1, 3]], tets[:, [0, 1, 2]]]), axis=1)
    _, counts = np.unique(faces, axis=0, return_counts=True)
    if counts.max() > 2:
        sys.exit(f"{name}: a face shared by {counts.max()} tetrahedra")
    return int((counts == 1).sum())


def write_legacy_vtk(path, title, pts, tets, arrays):
    with open(path + ".part", "wb") as f:
        f.write(f"# vtk DataFile Version 3.0\n{title}\nBINARY\nDATASET UNSTRUCTURED_GRID\n".encode())
        f.write(b"POINTS %d float\n" % len(pts) + pts.astype(">f4").tobytes() + b"\n")
        cells = np.hstack([np.full((len(tets), 1), 4), tets]).astype(">i4")
        f.write(b"CELLS %d %d\n" % (len(tets), 5 * len(tets)) + cells.tobytes() + b"\n")
        f.write(b"CELL_TYPES %d\n" % len(tets) + np.full(len(tets), 10, ">i4").tobytes() + b"\n")
        f.write(b"POINT_DATA %d\n" % len(pts))
        for name, values in arrays:
            f.write(b"SCALARS %s float 1\nLOOKUP_TABLE default\n" % name.encode())
            f.write(values.astype(">f4").tobytes() + b"\n")
    os.replace(path + ".part", path)


def nasa(out, source):
    for output, name in NASA_MESHES:
        dims, pts = plot3d_grid(nasa_bytes(name + "xyz.bin", source), name + "xyz.bin")
        q = plot3d_solution(nasa_bytes(name + "q.bin", source), dims, name + "q.bin")
        tets = hex_tets(dims)
        a, b, c, d = (pts[tets[:, m]] for m in range(4))
        negative = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) < 0
        tets[negative, 0], tets[negative, 1] = tets[negative, 1].copy(), tets[negative, 0].copy()
        boundary = check_conforming(tets, output)
        rho, energy = q[0], q[4]
        with np.errstate(divide="ignore", invalid="ignore"):
            speed2 = np.where(rho != 0, (q[1:4] ** 2).sum(axis=0) / rho ** 2, 0.0)
        pressure = 0.4 * (energy - 0.5 * rho * speed2)
        arrays = [("Density", rho), ("Pressure", pressure),
                  ("VelocityMagnitude", np.sqrt(speed2)), ("StagnationEnergy", energy)]
        title = f"NASA {name} (PLOT3D, pyvista/vtk-data {NASA_COMMIT[:10]}), 5 tetrahedra per cell"
        write_legacy_vtk(os.path.join(out, output), title, pts, tets, arrays)
        print(f"{output}: grid {dims}, {len(pts)} points, {len(tets)} tetrahedra, "
              f"{boundary} boundary faces", file=sys.stderr)


def main():
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "target", "meshes")
    os.makedirs(out, exist_ok=True)
    args = sys.argv[1:]
    if args[:1] == ["nasa"]:
        source = args[2] if args[1:2] == ["--source"] and len(args) == 3 else None
        if len(args) not in (1, 3) or (len(args) == 3 and source is None):
            sys.exit("usage: meshes.py [nasa [--source DIR]]")
        return nasa(out, source)
    if args:
        sys.exit("usage: meshes.py [nasa [--source DIR]]")
    pts, tets = kuhn_tets(33)
    field = np.linalg.norm(pts - 0.5, axis=1)
    write_vtu(os.path.join(out, "kuhn-200k.vtu"), pts, fix_orientation(pts, tets), "spherical", field)
    print(f"kuhn-200k.vtu: {len(tets)} tetrahedra", file=sys.stderr)
    pts, tets = kuhn_tets(56)
    c = pts[tets].mean(axis=1)
    hole_cyl = (c[:, 0] - 0.3) ** 2 + (c[:, 2] - 0.5) ** 2 < 0.15 ** 2
    hole_sph = np.linalg.norm(c - [0.7, 0.5, 0.5], axis=1) < 0.2
    keep = ~(hole_cyl | hole_sph)
    tets = fix_orientation(pts, tets[keep])
    used = np.unique(tets)
    remap = np.full(len(pts), -1)
    remap[used] = np.arange(len(used))
    pts, tets = pts[used], remap[tets]
    temperature = np.exp(-2.0 * pts[:, 0]) * (1.0 + 0.3 * np.sin(6.0 * pts[:, 1]))
    write_vtu(os.path.join(out, "bracket-like-1m.vtu"), pts, tets, "temperature", temperature)
    print(f"bracket-like-1m.vtu: {len(tets)} tetrahedra", file=sys.stderr)


if __name__ == "__main__":
    main()
