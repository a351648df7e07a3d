"""The package's numpy evaluation of the parameter encoding (skinstream/evaluation.py) against
the spec's evaluation written out plainly in float64 (tests/support/subscriber_models.py): on
random bodies whose first part has 150 RBF centres spread far wider than the kernel's support,
so that chunks sum only some of their part's centres; on a centre placed just within the
support of one corner of a chunk, which a cull short of the support would drop; and the
Model's reference pose, normals and bad blocks."""
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support import python_clients  # noqa: E402,F401
from support.subscriber_models import Body, random_body, random_parameters  # noqa: E402
import numpy as np  # noqa: E402
from skinstream import protocol as wire  # noqa: E402
from skinstream.evaluation import Evaluator  # noqa: E402


def identity_parameters(body, weights=None):
    """Every part at its reference frame, A = [I 0 0]; the RBF term on with `weights`."""
    a = np.zeros((body.part_count, 3, 9), np.float32)
    a[:, :, :3] = np.eye(3)
    flags = np.full(body.part_count, 0 if weights is None else 1, np.uint32)
    weights = np.zeros((len(body.members), 3), np.float32) if weights is None else weights
    return a, body.rotation, body.translation, flags, weights


class NumpyEvaluation(unittest.TestCase):
    def test_equals_the_spec_evaluated_in_float64(self):
        for seed in (1, 2):
            # 20,000 vertices: the first part's chunks are a few sigma across, and its centres
            # spread over nine.
            body = random_body(seed, vertices=20000, sigma=150.0)
            evaluator = Evaluator(wire.Model(body.model_payload()))
            for rbf in (True, False):
                parameters = random_parameters(body, seed, rbf=rbf)
                with self.subTest(seed=seed, rbf=rbf):
                    vertices, normals = evaluator.evaluate(Body.parameter_block(*parameters))
                    self.assertIsNone(normals)
                    self.assertEqual((vertices.shape, vertices.dtype), ((body.vertex_count, 3), np.float32))
                    truth = body.evaluate(*parameters)
                    # float32 of coordinates up to about 1000 mm: a few 1e-4 mm.
                    self.assertLess(np.abs(vertices - truth).max(), 2e-3)
                    if rbf:
                        without = body.evaluate(*parameters[:3], np.zeros(body.part_count, np.uint32), parameters[4])
                        self.assertGreater(np.abs(truth - without).max(), 10)  # the RBF term moves vertices by cm

    def test_a_centre_within_reach_of_one_corner_is_summed(self):
        # One part: a 10 x 10 x 10 grid of vertices filling a 100 mm cube (one chunk), sigma 50
        # mm; one centre 1.9 sigma beyond the cube's corner along its diagonal, where only that
        # corner's vertex feels it (phi(1.9) = 1/6000), and others far beyond reach.
        grid = np.stack(np.meshgrid(*[np.linspace(0, 100, 10)] * 3, indexing='ij'), axis=-1).reshape(-1, 3).astype(np.float32)
        diagonal = np.float32([1, 1, 1]) / np.sqrt(np.float32(3))
        members = np.vstack([[100, 100, 100] + 95 * diagonal, [-1000, 0, 0], [0, -1000, 0], [1200, 1200, 1200]]).astype(np.float32)
        v = len(grid)
        body = Body(reference=grid, rotation=np.eye(3, dtype=np.float32)[None], translation=np.zeros((1, 3), np.float32),
                    box_min=np.full((1, 3), -2000, np.float32), box_max=np.full((1, 3), 2000, np.float32),
                    sigma=np.float32([50]), part_members=np.uint32([len(members)]), members=members,
                    influences_per_vertex=np.ones(v, np.uint8), influence_parts=np.zeros(v, np.uint8),
                    influence_weights=np.ones(v, np.float32), faces=np.zeros((0, 3), np.uint32))
        weights = np.float32([[6000, 0, 0], [5000, 0, 0], [0, 5000, 0], [0, 0, 5000]])
        parameters = identity_parameters(body, weights)
        evaluator = Evaluator(wire.Model(body.model_payload()))
        self.assertEqual(len(evaluator._parts[0].chunks), 1)
        vertices, _ = evaluator.evaluate(Body.parameter_block(*parameters))
        moved = vertices - grid
        corner = int(np.argmax(grid.sum(axis=1)))
        self.assertAlmostEqual(float(moved[corner, 0]), 1.0, delta=0.05)  # 6000 phi(1.9) = 1 mm
        others = np.delete(moved, corner, axis=0)
        self.assertLess(np.abs(others).max(), 1e-3)
        np.testing.assert_allclose(vertices, body.evaluate(*parameters), atol=2e-3)

    def test_the_reference_pose_gives_the_reference_vertices(self):
        body = random_body(4, vertices=500)
        vertices, _ = Evaluator(wire.Model(body.model_payload())).evaluate(Body.parameter_block(*identity_parameters(body)))
        np.testing.assert_allclose(vertices, body.reference, atol=2e-3)

    def test_normals_of_the_faces_when_asked_for(self):
        body = random_body(5, vertices=400, faces=600)
        evaluator = Evaluator(wire.Model(body.model_payload()), body.faces)
        block = Body.parameter_block(*random_parameters(body, 5))
        vertices, normals = evaluator.evaluate(block, normals=True)
        self.assertEqual(normals.shape, vertices.shape)
        used = np.isin(np.arange(body.vertex_count), body.faces)
        np.testing.assert_allclose(np.linalg.norm(normals[used], axis=1), 1, atol=1e-5)
        self.assertIsNone(evaluator.evaluate(block, normals=False)[1])

    def test_bad_blocks_are_one_line_errors(self):
        body = random_body(6, vertices=200)
        evaluator = Evaluator(wire.Model(body.model_payload()))
        a, rotation, translation, flags, weights = random_parameters(body, 6)
        good = Body.parameter_block(a, rotation, translation, flags, weights)
        nan = a.copy()
        nan[1, 2, 3] = np.nan
        cases = {
            'truncated': good[:6],
            'the counts say': good[:-4],
            '3 parts and 173 members, the model has 3 and 174': Body.parameter_block(a, rotation, translation, flags, weights[:-1]),
            'not finite': Body.parameter_block(nan, rotation, translation, flags, weights),
            'reserved flag bits': Body.parameter_block(a, rotation, translation, flags | 4, weights),
        }
        for what, block in cases.items():
            with self.subTest(what):
                with self.assertRaisesRegex(wire.ProtocolError, what) as raised:
                    evaluator.evaluate(block)
                self.assertNotIn('\n', str(raised.exception))


if __name__ == '__main__':
    unittest.main(verbosity=2)
