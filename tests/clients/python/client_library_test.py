"""The parameter encoding evaluated by the C++ client library through its C ABI and ctypes
(skinstream/client_library.py) against the spec's evaluation in float64 and the package's numpy
evaluator, on random bodies (tests/support/subscriber_models.py); its one-line errors; and how
the package finds the library or says why it does not. (Against the daemon, bit for bit:
subscriber_test.py.)"""
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support.python_clients import CLIENT_LIBRARY  # noqa: E402
from support.subscriber_models import Body, random_body, random_parameters  # noqa: E402
import numpy as np  # noqa: E402
from skinstream import client_library, protocol as wire  # noqa: E402
from skinstream.evaluation import Evaluator  # noqa: E402
from skinstream.meshoptimizer_library import find_meshoptimizer  # noqa: E402


def found_with(path):
    """find_client_library() with SKINSTREAM_CLIENT_LIBRARY set to `path` (None: unset)."""
    saved = os.environ.pop(client_library.ENVIRONMENT, None)
    try:
        if path is not None:
            os.environ[client_library.ENVIRONMENT] = path
        client_library.find_client_library.cache_clear()
        return client_library.find_client_library()
    finally:
        if saved is not None:
            os.environ[client_library.ENVIRONMENT] = saved
        client_library.find_client_library.cache_clear()


class LibraryEvaluation(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.library, line = found_with(CLIENT_LIBRARY)
        if cls.library is None:
            raise AssertionError(f'{line} (build the skinstream_client target)')

    def evaluator(self, body, faces=None):
        payload = body.model_payload()
        return client_library.LibraryEvaluator(self.library, wire.Model(payload), payload, faces)

    def test_equals_the_spec_and_the_numpy_evaluator(self):
        for seed in (1, 2):
            body = random_body(seed, vertices=20000, sigma=150.0)
            payload = body.model_payload()
            by_library, by_numpy = self.evaluator(body, body.faces), Evaluator(wire.Model(payload), body.faces)
            self.assertEqual(by_library.name, 'libskinstream_client')
            for rbf in (True, False):
                parameters = random_parameters(body, seed, rbf=rbf)
                block = Body.parameter_block(*parameters)
                with self.subTest(seed=seed, rbf=rbf):
                    vertices, normals = by_library.evaluate(block, normals=True)
                    self.assertEqual((vertices.shape, vertices.dtype), ((body.vertex_count, 3), np.float32))
                    self.assertLess(np.abs(vertices - body.evaluate(*parameters)).max(), 2e-3)
                    numpy_vertices, numpy_normals = by_numpy.evaluate(block, normals=True)
                    self.assertLess(np.abs(vertices - numpy_vertices).max(), 2e-3)
                    used = np.linalg.norm(numpy_normals, axis=1) > 0  # of some face with an area
                    np.testing.assert_allclose(np.linalg.norm(normals[used], axis=1), 1, atol=1e-5)
                    # Random triangles have slivers, whose normals swing with a 1e-4 mm move.
                    self.assertGreater(np.median((normals[used] * numpy_normals[used]).sum(axis=1)), 1 - 1e-6)
                    self.assertIsNone(by_library.evaluate(block, normals=False)[1])

    def test_no_faces_no_normals(self):
        body = random_body(3, vertices=300)
        self.assertIsNone(self.evaluator(body).evaluate(Body.parameter_block(*random_parameters(body, 3)), normals=True)[1])

    def test_bad_blocks_and_models_are_one_line_errors(self):
        body = random_body(6, vertices=200)
        evaluator = self.evaluator(body)
        a, rotation, translation, flags, weights = random_parameters(body, 6)
        good = Body.parameter_block(a, rotation, translation, flags, weights)
        nan = weights.copy()
        nan[5, 1] = np.inf
        for what, block in {'truncated': good[:6], 'the counts say': good[:-4],
                            'RBF weight is not finite': Body.parameter_block(a, rotation, translation, flags, nan)}.items():
            with self.subTest(what):
                with self.assertRaisesRegex(wire.ProtocolError, what) as raised:
                    evaluator.evaluate(block)
                self.assertNotIn('\n', str(raised.exception))
        faces = body.faces.copy()
        faces[3, 1] = body.vertex_count
        with self.assertRaisesRegex(wire.ProtocolError, f'^Model: .*face 3 refers to vertex {body.vertex_count}') as raised:
            self.evaluator(body, faces)
        self.assertNotIn('\n', str(raised.exception))


class FindingTheLibrary(unittest.TestCase):
    def test_by_the_environment_variable(self):
        library, line = found_with(CLIENT_LIBRARY)
        self.assertIsNotNone(library, line)
        self.assertEqual(line, CLIENT_LIBRARY)

    def test_a_path_that_does_not_load_says_why(self):
        library, line = found_with('/nonexistent/libskinstream_client.so.0')
        self.assertIsNone(library)
        self.assertRegex(line, '^/nonexistent/libskinstream_client.so.0 does not load: ')
        meshoptimizer = find_meshoptimizer()[0]
        if meshoptimizer is not None:  # a library, not the client's
            library, line = found_with(meshoptimizer.name)
            self.assertIsNone(library)
            self.assertIn('skinstream_evaluator_abi_version', line)

    def test_by_name_or_how_to_get_it(self):
        library, line = found_with(None)
        if library is None:
            self.assertIn('cmake --install', line)
            self.assertIn(client_library.ENVIRONMENT, line)
        else:
            self.assertIn('libskinstream_client', line)


if __name__ == '__main__':
    unittest.main(verbosity=2)
