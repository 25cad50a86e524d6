"""Writes a tetrahedral mesh's boundary (the faces that belong to one tetrahedron only) as
an OBJ surface, outward-facing: how data/surfaces/bracket-boundary.obj was made from
data/tets/bracket-4.1.msh, for the layered scene scenes/data/bracket-layers.toml.

    python3 scripts/mesh_boundary.py data/tets/bracket-4.1.msh data/surfaces/bracket-boundary.obj

Needs meshio and numpy (scripts/python-tests.sh installs both into target/python-venv).
"""

import sys
from collections import Counter

import meshio
import numpy as np


def boundary(points, tets):
    """The faces of `tets` used once, each wound so its normal points out of its tet."""
    faces = [(0, 1, 2, 3), (0, 3, 1, 2), (0, 2, 3, 1), (1, 3, 2, 0)]
    counts = Counter()
    oriented = {}
    for t in tets:
        for a, b, c, opposite in faces:
            tri = (t[a], t[b], t[c])
            p = points[list(tri)]
            normal = np.cross(p[1] - p[0], p[2] - p[0])
            if np.dot(normal, points[t[opposite]] - p[0]) > 0:
                tri = (tri[0], tri[2], tri[1])
            key = tuple(sorted(tri))
            counts[key] += 1
            oriented[key] = tri
    return [oriented[k] for k, n in counts.items() if n == 1]


def main(source, target):
    mesh = meshio.read(source)
    tets = np.concatenate([c.data for c in mesh.cells if c.type == "tetra"])
    faces = boundary(mesh.points, tets)
    used = sorted({v for f in faces for v in f})
    index = {v: i + 1 for i, v in enumerate(used)}
    with open(target, "w") as out:
        out.write(f"# boundary of {source}: {len(faces)} triangles (scripts/mesh_boundary.py)\n")
        for v in used:
            x, y, z = mesh.points[v][:3]
            out.write(f"v {x:.9g} {y:.9g} {z:.9g}\n")
        for a, b, c in faces:
            out.write(f"f {index[a]} {index[b]} {index[c]}\n")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
