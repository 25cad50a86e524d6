#!/usr/bin/env python3
"""Large tetrahedral meshes for the volume's trade (issue 16, items 5 and 7), generated, never
committed: writes VTK XML .vtu files into target/meshes/ that `scenes` can name.

    python3 benches/meshes.py            # needs numpy only

- `kuhn-200k.vtu`: the seed's Kuhn grid at 33^3 points (196,608 tetrahedra), the spherical
  field (`arbvis study --technique cellproj-volume --grids 33` makes the same one in memory).
- `bracket-like-1m.vtu`: about a million tetrahedra of a non-convex part, a box with a
  cylindrical and a spherical hole like the gmsh bracket in ../shared/data/tets (which was
  written by gmsh from a short geometry script: 40,710 tetrahedra), made here by cutting the
  holes out of a 56^3 Kuhn grid (a staircase boundary, which is what order errors need), with
  a "temperature" field falling off from one face.

Public CFD/FEM meshes of this size (e.g. in the pyvista/vtk-data repository, BSD-3) are not
reachable from this project's machines (only package registries are); this script is the
stand-in, and any .vtu / .vtk / .msh file a user has works the same way through a scene.
"""

import os
import sys

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


def main():
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "target", "meshes")
    os.makedirs(out, exist_ok=True)
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
