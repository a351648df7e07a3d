"""Model payloads and parameter blocks of the subscriber protocol (docs/subscriber-protocol.md,
"6 Model" and "Parameters") written here from the spec, for the evaluators' tests: random
bodies whose parts spread their members much wider than their kernel's support, so that most
RBF centres are out of reach of most vertices, as on the demo body's trunk; and the spec's
evaluation in float64, written out as plainly as the document writes it."""
import struct

import numpy as np


def _padding(n):
    return (4 - n % 4) % 4


def _rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


class Body:
    """A body as the Model message carries it (the arrays of its fields, float32 and uint8/32),
    with the faces MeshInfo would carry; random_body() makes one."""

    def __init__(self, reference, rotation, translation, box_min, box_max, sigma, part_members, members,
                 influences_per_vertex, influence_parts, influence_weights, faces):
        self.reference, self.rotation, self.translation = reference, rotation, translation
        self.box_min, self.box_max, self.sigma, self.part_members, self.members = box_min, box_max, sigma, part_members, members
        self.influences_per_vertex, self.influence_parts = influences_per_vertex, influence_parts
        self.influence_weights, self.faces = influence_weights, faces
        self.vertex_count, self.part_count = len(reference), len(rotation)

    def model_payload(self):
        v, p, y, k = self.vertex_count, self.part_count, len(self.members), len(self.influence_parts)
        out = struct.pack('<IIII', v, p, y, k) + self.reference.tobytes()
        for i in range(p):
            floats = np.concatenate([self.rotation[i].ravel(), self.translation[i], self.box_min[i], self.box_max[i],
                                     [self.sigma[i]]]).astype('<f4')
            out += floats.tobytes() + struct.pack('<I', int(self.part_members[i]))
        out += self.members.astype('<f4').tobytes() + self.influences_per_vertex.tobytes() + self.influence_parts.tobytes()
        out += b'\0' * _padding(v + k) + self.influence_weights.astype('<f4').tobytes()
        return out

    @staticmethod
    def parameter_block(a, rotation, translation, flags, weights):
        out = struct.pack('<II', len(a), len(weights))
        for i in range(len(a)):
            out += a[i].astype('<f4').tobytes() + rotation[i].astype('<f4').tobytes() + translation[i].astype('<f4').tobytes()
            out += struct.pack('<I', int(flags[i]))
        return out + weights.astype('<f4').tobytes()

    def evaluate(self, a, rotation, translation, flags, weights):
        """The spec's evaluation in float64, every centre summed: V x 3."""
        def q(x):
            return np.concatenate([x, x * x, x * np.roll(x, -1, axis=1)], axis=1)

        def phi(r):
            return (np.maximum(2 - r, 0) ** 3 - 4 * np.maximum(1 - r, 0) ** 3) / 6

        first = np.concatenate(([0], np.cumsum(self.part_members))).astype(int).tolist()
        vertex_of = np.repeat(np.arange(self.vertex_count), self.influences_per_vertex)
        out = np.zeros((self.vertex_count, 3))
        for p in range(self.part_count):
            chosen = self.influence_parts == p
            v0 = self.reference[vertex_of[chosen]].astype(np.float64)
            u = v0 @ self.rotation[p].astype(np.float64).T + self.translation[p]
            s = np.clip(u, self.box_min[p], self.box_max[p])
            ap = a[p].astype(np.float64)
            local = q(s) @ ap.T
            if flags[p] & 1 and self.sigma[p] > 0:
                centres = q(self.members[first[p]:first[p + 1]].astype(np.float64)) @ ap.T
                r = np.linalg.norm(local[:, None, :] - centres[None], axis=2) / self.sigma[p]
                local = local + phi(r) @ weights[first[p]:first[p + 1]].astype(np.float64)
            world = (local + (u - s) - translation[p]) @ rotation[p].astype(np.float64)  # R^T x, row by row
            np.add.at(out, vertex_of[chosen], self.influence_weights[chosen][:, None] * world)
        return out


def random_body(seed, vertices=3000, parts=3, members=12, first_members=150, size=1500.0, sigma=60.0, faces=4000):
    """A random body of `parts` parts: vertices in a cube of `size` mm, each with 1 to 3
    influences, each part with `members` members (the first part `first_members`) spread over
    its box and a kernel of `sigma` mm (the last part none); some vertices lie outside their
    parts' boxes."""
    rng = np.random.default_rng(seed)
    box_min = np.full((parts, 3), -0.45 * size, np.float32) + rng.uniform(-50, 50, (parts, 3)).astype(np.float32)
    box_max = np.full((parts, 3), 0.45 * size, np.float32) + rng.uniform(-50, 50, (parts, 3)).astype(np.float32)
    part_members = np.array([first_members] + [members] * (parts - 1), np.uint32)
    sigmas = np.full(parts, sigma, np.float32)
    sigmas[-1] = 0.0
    counts = np.minimum(rng.integers(1, 4, vertices), parts).astype(np.uint8)
    influence_parts = np.concatenate([rng.choice(parts, n, replace=False) for n in counts]).astype(np.uint8)
    weights = rng.uniform(0.2, 1.0, len(influence_parts))
    vertex_of = np.repeat(np.arange(vertices), counts)
    return Body(reference=rng.uniform(-size / 2, size / 2, (vertices, 3)).astype(np.float32),
                rotation=np.stack([_rotation(rng) for _ in range(parts)]).astype(np.float32),
                translation=rng.uniform(-100, 100, (parts, 3)).astype(np.float32),
                box_min=box_min, box_max=box_max, sigma=sigmas, part_members=part_members,
                members=np.concatenate([rng.uniform(box_min[p], box_max[p], (int(part_members[p]), 3))
                                        for p in range(parts)]).astype(np.float32),
                influences_per_vertex=counts, influence_parts=influence_parts,
                influence_weights=(weights / np.bincount(vertex_of, weights)[vertex_of]).astype(np.float32),
                faces=rng.integers(0, vertices, (faces, 3)).astype(np.uint32))


def random_parameters(body, seed, rbf=True, weight_mm=40.0):
    """(A P x 3 x 9, R P x 3 x 3, d P x 3, flags P, weights Y x 3): each part moved and bent a
    little from its reference frame, with RBF weights of about weight_mm."""
    rng, p = np.random.default_rng(seed), body.part_count
    a = np.zeros((p, 3, 9), np.float32)
    a[:, :, :3] = np.eye(3) + rng.normal(0, 0.05, (p, 3, 3))
    a[:, :, 3:] = rng.normal(0, 2e-5, (p, 3, 6))  # a bend of some 10 mm across the body
    rotation = np.stack([_rotation(rng) for _ in range(p)]).astype(np.float32)
    translation = rng.uniform(-200, 200, (p, 3)).astype(np.float32)
    flags = np.full(p, 1 if rbf else 0, np.uint32)
    weights = rng.normal(0, weight_mm, (len(body.members), 3)).astype(np.float32)
    return a, rotation, translation, flags, weights
