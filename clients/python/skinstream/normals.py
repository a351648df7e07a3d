"""Unit area-weighted vertex normals of a triangle mesh whose triangles stay the same from frame
to frame (the body's): the corners are sorted by vertex once, so that a frame is one cross
product per face and one sum per vertex, in float32 as the daemon computes them."""
import numpy as np


class VertexNormals:
    """normals = VertexNormals(faces, vertex_count)(positions): faces F x 3 (counter-clockwise
    from outside), positions V x 3; V x 3 float32 unit vectors (zero for a vertex of no face or
    of faces of no area)."""

    def __init__(self, faces, vertex_count):
        faces = np.asarray(faces, np.int64).reshape(-1, 3)
        self.vertex_count = vertex_count
        self._corners = [np.ascontiguousarray(faces[:, c]) for c in range(3)]
        corners = faces.ravel()
        self._corner_faces = np.argsort(corners, kind='stable') // 3  # each vertex's faces, vertex after vertex
        counts = np.bincount(corners, minlength=vertex_count)
        # Sums over the vertices of some face only: reduceat's segments run from one start to
        # the next, so a vertex of no face (an empty segment) would take its neighbour's corners.
        self._used = np.flatnonzero(counts)
        self._starts = np.concatenate(([0], np.cumsum(counts)[:-1]))[self._used]

    def __call__(self, positions):
        count = self.vertex_count
        if not len(self._corner_faces):
            return np.zeros((count, 3), np.float32)
        p = np.asarray(positions, np.float32)
        a, b, c = self._corners
        x, y, z = (np.ascontiguousarray(p[:, axis]) for axis in range(3))  # gathers run faster on contiguous columns
        ax, ay, az = x[a], y[a], z[a]
        bx, by, bz = x[b] - ax, y[b] - ay, z[b] - az
        cx, cy, cz = x[c] - ax, y[c] - ay, z[c] - az
        summed = np.zeros((count, 3), np.float32)
        # Each face's (b - a) x (c - a): twice its area, outwards.
        for axis, face in enumerate((by * cz - bz * cy, bz * cx - bx * cz, bx * cy - by * cx)):
            summed[self._used, axis] = np.add.reduceat(face[self._corner_faces], self._starts)
        length = np.sqrt((summed * summed).sum(axis=1))
        with np.errstate(invalid='ignore', divide='ignore'):
            return np.where(length[:, None] > 0, summed / length[:, None], np.float32(0)).astype(np.float32, copy=False)


def vertex_normals(positions, faces):
    """Unit area-weighted vertex normals (float32, V x 3) of the faces (F x 3, counter-clockwise)."""
    return VertexNormals(faces, len(positions))(positions)
