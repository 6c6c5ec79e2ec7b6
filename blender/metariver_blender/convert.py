"""Between Blender and metariver: a grid mesh's heights, the axes, surface meshes, PLY files.

metariver's y is up and the terrain spans x in [0, (columns-1) a], z in [0, (rows-1) a];
Blender's Z is up. A metariver point (x, y, z) is Blender's (x + X0, Y0 - z, y + Z0): a
rotation (winding and normals stay right) plus the terrain object's offset.
"""
from __future__ import annotations

from dataclasses import dataclass

import bpy
import numpy as np


@dataclass
class Transform:
    """metariver -> Blender: (x, y, z) -> (x + origin[0], origin[1] - z, y + origin[2])."""
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def points(self, p: np.ndarray) -> np.ndarray:
        o = np.asarray(self.origin, np.float32)
        return np.stack([p[:, 0] + o[0], o[1] - p[:, 2], p[:, 1] + o[2]], axis=1).astype(np.float32)

    def directions(self, d: np.ndarray) -> np.ndarray:
        return np.stack([d[:, 0], -d[:, 2], d[:, 1]], axis=1).astype(np.float32)

    def quaternion(self, q) -> tuple[float, float, float, float]:
        """A metariver rotation (x, y, z, w, body to world) as Blender's (w, x, y, z): the
        same turn about the axis in Blender's axes."""
        return (float(q[3]), float(q[0]), -float(q[2]), float(q[1]))

    def to_metariver(self, p) -> np.ndarray:
        """A Blender point (X, Y, Z) in metariver's coordinates."""
        o = self.origin
        return np.array([p[0] - o[0], p[2] - o[2], o[1] - p[1]], np.float32)


def grid_heights(obj) -> tuple[np.ndarray, float, float, Transform]:
    """A grid mesh object's heights (rows x columns in [0, 1]), area_scale, height_scale and the
    transform that puts metariver's terrain on the object. Rows run along -Y, columns along +X
    (world space). ValueError naming the object when its vertices are not a regular grid."""
    mesh = obj.data
    n = len(mesh.vertices)
    co = np.empty(n * 3, np.float64)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(n, 3)
    m = np.array(obj.matrix_world, np.float64)
    co = co @ m[:3, :3].T + m[:3, 3]
    xs, ys = np.unique(np.round(co[:, 0], 4)), np.unique(np.round(co[:, 1], 4))
    columns, rows = len(xs), len(ys)
    if columns < 2 or rows < 2 or columns * rows != n:
        raise ValueError(f"terrain {obj.name!r}: {n} vertices on {columns} x {rows} distinct X/Y values: "
                         "not a regular grid mesh (use a subdivided plane, or a heightmap file)")
    dx, dy = (xs[-1] - xs[0]) / (columns - 1), (ys[-1] - ys[0]) / (rows - 1)
    if abs(dx - dy) > 1e-3 * max(dx, dy):
        raise ValueError(f"terrain {obj.name!r}: grid spacing {dx:g} along X and {dy:g} along Y; "
                         "metariver needs square cells")
    col = np.rint((co[:, 0] - xs[0]) / dx).astype(int)
    row = np.rint((ys[-1] - co[:, 1]) / dy).astype(int)
    z_min, z_max = co[:, 2].min(), co[:, 2].max()
    height_scale = max(z_max - z_min, 1e-3)
    heights = np.zeros((rows, columns), np.float64)
    heights[row, col] = (co[:, 2] - z_min) / height_scale
    return np.clip(heights, 0.0, 1.0), float(dx), float(height_scale), Transform((xs[0], ys[-1], z_min))


def surface_mesh(name: str, vertices: np.ndarray, normals: np.ndarray, indices: np.ndarray, normals_given=True):
    """A mesh datablock of triangles with smooth shading and the given vertex normals (or
    Blender's own, normals_given=False)."""
    mesh = bpy.data.meshes.new(name)
    nv, nt = len(vertices), len(indices)
    mesh.vertices.add(nv)
    mesh.vertices.foreach_set("co", vertices.ravel())
    mesh.loops.add(3 * nt)
    mesh.loops.foreach_set("vertex_index", indices.astype(np.int32).ravel())
    mesh.polygons.add(nt)
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * nt, 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(nt, 3, np.int32))
    mesh.polygons.foreach_set("use_smooth", np.ones(nt, bool))
    mesh.update()
    if nv and normals_given:
        mesh.use_auto_smooth = True
        mesh.normals_split_custom_set_from_vertices(normals.tolist())
    return mesh


def body_mesh(name: str, shape: str, size) -> "bpy.types.Mesh":
    """A body's shape in its own frame, in Blender's axes (metariver's local (x, y, z) is
    (x, -z, y)): a box of extents size, a sphere of radius size[0], a capsule of radius
    size[0] and cylinder length size[1] along x; a mesh shape (its OBJ is not read here)
    as a cube of side size[0]."""
    import bmesh

    bm = bmesh.new()
    if shape in ("sphere", "capsule"):
        bmesh.ops.create_uvsphere(bm, u_segments=24, v_segments=12, radius=float(size[0]))
        if shape == "capsule":  # the hemispheres apart by the cylinder's length
            half = 0.5 * float(size[1])
            for v in bm.verts:
                v.co.x += half if v.co.x > 0.0 else -half
    else:
        bmesh.ops.create_cube(bm, size=1.0)
        ext = (size[0], size[2], size[1]) if shape == "box" else (size[0],) * 3  # Blender X, Y, Z
        for v in bm.verts:
            v.co.x, v.co.y, v.co.z = v.co.x * ext[0], v.co.y * ext[1], v.co.z * ext[2]
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    return mesh


def write_ply(path: str, vertices: np.ndarray, normals: np.ndarray, indices: np.ndarray) -> None:
    """A binary little-endian PLY in metariver's coordinates (y up): x y z nx ny nz, triangles."""
    header = ("ply\nformat binary_little_endian 1.0\ncomment metariver water surface\n"
              f"element vertex {len(vertices)}\nproperty float x\nproperty float y\nproperty float z\n"
              "property float nx\nproperty float ny\nproperty float nz\n"
              f"element face {len(indices)}\nproperty list uchar uint vertex_indices\nend_header\n")
    vert = np.hstack([vertices, normals]).astype("<f4")
    face = np.zeros(len(indices), dtype=[("n", "u1"), ("i", "<u4", (3,))])
    face["n"] = 3
    face["i"] = indices
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(vert.tobytes())
        f.write(face.tobytes())


def read_ply_counts(path: str) -> tuple[int, int]:
    """(vertices, faces) a PLY header declares (the tests read the files back)."""
    counts = {}
    with open(path, "rb") as f:
        for line in f:
            if line.startswith(b"element"):
                _, name, count = line.split()
                counts[name.decode()] = int(count)
            if line.strip() == b"end_header":
                break
    return counts.get("vertex", 0), counts.get("face", 0)


__all__ = ["Transform", "grid_heights", "surface_mesh", "body_mesh", "write_ply", "read_ply_counts"]
