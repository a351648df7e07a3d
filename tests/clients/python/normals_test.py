"""The package's vertex normals (skinstream/normals.py) against the area-weighted normals
summed face by face in float64: on a closed mesh (an octahedron, whose normals are known), on
random triangles with vertices of no face and faces of no area, and on no faces at all."""
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support import python_clients  # noqa: E402,F401
import numpy as np  # noqa: E402
from skinstream.normals import VertexNormals, vertex_normals  # noqa: E402


def face_by_face(positions, faces):
    p = positions.astype(np.float64)
    summed = np.zeros_like(p)
    for a, b, c in faces:
        n = np.cross(p[b] - p[a], p[c] - p[a])
        for v in (a, b, c):
            summed[v] += n
    length = np.linalg.norm(summed, axis=1)
    return np.where(length[:, None] > 0, summed / np.where(length > 0, length, 1)[:, None], 0)


class VertexNormalsOfFaces(unittest.TestCase):
    def test_an_octahedron_has_its_vertices_as_normals(self):
        positions = np.float32([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]) * 10
        faces = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
        normals = vertex_normals(positions, faces)
        self.assertEqual(normals.dtype, np.float32)
        np.testing.assert_allclose(normals, positions / 10, atol=1e-6)

    def test_random_triangles_with_unused_vertices_and_flat_faces(self):
        rng = np.random.default_rng(2)
        positions = rng.uniform(-500, 500, (1000, 3)).astype(np.float32)
        faces = rng.integers(0, 900, (3000, 3))  # vertices 900-999 in no face
        faces[:10, 2] = faces[:10, 1]  # no area
        normals = VertexNormals(faces, len(positions))(positions)
        truth = face_by_face(positions, faces)
        np.testing.assert_allclose(normals, truth, atol=1e-5)
        self.assertTrue((normals[900:] == 0).all())
        lengths = np.linalg.norm(normals[:900], axis=1)
        np.testing.assert_allclose(lengths[lengths > 0], 1, atol=1e-6)

    def test_no_faces_gives_zero_normals(self):
        normals = VertexNormals(np.zeros((0, 3), np.int64), 5)(np.ones((5, 3), np.float32))
        np.testing.assert_array_equal(normals, np.zeros((5, 3), np.float32))


if __name__ == '__main__':
    unittest.main(verbosity=2)
