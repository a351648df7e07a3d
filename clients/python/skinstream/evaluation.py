"""The parameter encoding turned into vertices with numpy, as docs/subscriber-protocol.md writes
the evaluation out (Park & Hodgins 2006, eqs. 8 and 9):

    for each influence (part p, weight beta) of vertex j:
        u = R0_p v0_j + d0_p;  s = clamp(u, box_min_p, box_max_p);  l = A_p q(s)
        if the RBF term applies and sigma_p > 0:
            l += sum over members i of p: w_i phi(|l - A_p q(p0_i)| / sigma_p)
        v_j += beta R_p^T (l + (u - s) - d_p)

Everything that does not change from frame to frame (u, s, q(s)) is computed once from the
Model; phi(r) = ((2 - r)+³ - 4 (1 - r)+³) / 6 is the uniform cubic B-spline of support 2.

Most of a frame is the RBF sums, so they are culled as the daemon culls them
(core/deform/mesh_evaluator.cpp): each part's influences are cut into chunks of neighbours
(along a Morton curve of s), and a chunk sums only the centres within 2 sigma plus its deformed
bounding box's half diagonal of the box's middle; the others add exactly zero. In float32, as
the daemon evaluates: on the demo body within 0.001 mm of the daemon's float buffer (the
protocol promises 0.01 mm). Arrays are kept x, y, z in rows (3 x n): numpy's loops then run
along the long axis, and the weight sums are one (3 x m) @ (m x n) product."""
import numpy as np

from .normals import VertexNormals
from .protocol import PARAMETER_PART_BYTES, ProtocolError

_PART = np.dtype([('A', '<f4', (3, 9)), ('R', '<f4', (3, 3)), ('d', '<f4', 3), ('flags', '<u4')])
assert _PART.itemsize == PARAMETER_PART_BYTES
# Kernel terms a chunk aims at (its rows times its part's members): a chunk costs about twenty
# numpy calls whatever its size, a larger one culls fewer centres. On the demo body (2.4 million
# terms a frame from 3.8 million at 2^15) a frame took about the same from 2^15 to 2^17 and
# twice as long at 2^13, where the calls dominate.
_CHUNK_TERMS = 1 << 16
_MAX_CHUNK_ROWS = 2048


def quadratic_terms(x):
    """q(x, y, z) = (x, y, z, x², y², z², xy, yz, zx) of each row of an n x 3 array."""
    return np.concatenate([x, x * x, x * np.roll(x, -1, axis=1)], axis=1)


def _morton_codes(cells):
    """Interleaved bits of n x 3 integers below 1024: nearby cells get nearby codes."""
    codes = np.zeros(len(cells), np.int64)
    for axis in range(3):
        v = cells[:, axis].astype(np.int64) & 0x3FF
        v = (v | (v << 16)) & 0x30000FF
        v = (v | (v << 8)) & 0x300F00F
        v = (v | (v << 4)) & 0x30C30C3
        v = (v | (v << 2)) & 0x9249249
        codes |= v << axis
    return codes


def read_parameters(model, block):
    """(parts, weights) of a Frame's parameters block, checked against the Model: a structured
    array of the parts (A 3 x 9, R 3 x 3, d, flags) and the members' RBF weights (Y x 3)."""
    if len(block) < 8:
        raise ProtocolError(f'parameters: block of {len(block)} bytes is truncated')
    parts, members = np.frombuffer(block, '<u4', 2)
    if parts != model.part_count or members != model.member_count:
        raise ProtocolError(f'parameters: {parts} parts and {members} members, the model has {model.part_count} and '
                            f'{model.member_count}')
    expected = 8 + PARAMETER_PART_BYTES * parts + 12 * members
    if len(block) != expected:
        raise ProtocolError(f'parameters: block of {len(block)} bytes, the counts say {expected}')
    fits = np.frombuffer(block, _PART, parts, 8)
    weights = np.frombuffer(block, '<f4', 3 * members, 8 + PARAMETER_PART_BYTES * parts).reshape(members, 3)
    if not (np.isfinite(fits['A']).all() and np.isfinite(fits['R']).all() and np.isfinite(fits['d']).all()):
        raise ProtocolError('parameters: a part has a value that is not finite')
    if (fits['flags'] > 1).any():
        raise ProtocolError('parameters: a part has reserved flag bits set')
    if not np.isfinite(weights).all():
        raise ProtocolError('parameters: an RBF weight is not finite')
    return fits, weights


class _Part:
    """One part's influences (columns first to last of the evaluator's 3 x K arrays) and its
    members, with the chunks its RBF sums are culled by."""

    def __init__(self, first, last, members, sigma):
        self.columns = slice(first, last)
        self.members = members  # slice of the Model's members (and of a frame's weights)
        self.inverse_sigma = np.float32(1.0 / sigma) if sigma > 0 else None
        self.member_count = members.stop - members.start
        self.chunk_rows = max(1, min(_MAX_CHUNK_ROWS, _CHUNK_TERMS // self.member_count))
        self.chunk_starts = np.arange(0, last - first, self.chunk_rows)
        self.chunks = [slice(s, min(s + self.chunk_rows, last - first)) for s in self.chunk_starts.tolist()]


class Evaluator:
    """Evaluates one frame's parameters block against the Model it came after, in numpy."""

    name = 'numpy'

    def __init__(self, model, faces=None):
        self.model = model
        self.normals = None if faces is None else VertexNormals(faces, model.vertex_count)
        k_vertex = np.repeat(np.arange(model.vertex_count), model.influences_per_vertex)
        k_part = model.influence_parts.astype(np.int64)
        rotation = model.rotation.astype(np.float64)
        u = np.einsum('kij,kj->ki', rotation[k_part], model.reference.astype(np.float64)[k_vertex]) + model.translation[k_part]
        s = np.clip(u, model.box_min[k_part], model.box_max[k_part])
        # Influences part after part, each part's along a Morton curve of s in its box.
        extent = np.maximum(model.box_max - model.box_min, 1e-6)[k_part]
        cells = (np.clip((s - model.box_min[k_part]) / extent, 0, 1) * 1023).astype(np.int64)
        order = np.lexsort((_morton_codes(cells), k_part))
        self._vertex = k_vertex[order]
        self._beta = model.influence_weights[order].astype(np.float32)
        self._q = np.ascontiguousarray(quadratic_terms(s[order]).T, np.float32)  # 9 x K
        self._outside = np.ascontiguousarray((u - s)[order].T, np.float32)  # 3 x K
        part = k_part[order]
        bounds = np.searchsorted(part, np.arange(model.part_count + 1)).tolist()
        first = np.concatenate(([0], np.cumsum(model.part_members))).astype(np.int64).tolist()
        self._parts = [_Part(bounds[p], bounds[p + 1], slice(first[p], first[p + 1]), float(model.sigma[p]))
                       for p in range(model.part_count)]
        self._member_q = quadratic_terms(model.members.astype(np.float64)).T  # 9 x Y
        widest = max(part.chunk_rows * part.member_count for part in self._parts)
        self._scratch = [np.empty(widest, np.float32) for _ in range(3)]

    def parameters(self, block):
        """(parts, weights) of a Frame's parameters block, checked against the Model."""
        return read_parameters(self.model, block)

    def evaluate(self, block, normals=False):
        """(vertices, normals): V x 3 float32 (normals None unless asked for and the faces known)."""
        fits, weights = self.parameters(block)
        world = np.empty((3, len(self._vertex)), np.float32)
        for p, part in enumerate(self._parts):
            fit = fits[p]
            a = fit['A']
            local = a @ self._q[:, part.columns]
            if fit['flags'] & 1 and part.inverse_sigma is not None and part.chunks:
                self._add_rbf(local, part, a, weights[part.members])
            local += self._outside[:, part.columns]
            local -= fit['d'][:, None]
            world[:, part.columns] = fit['R'].T @ local
        world *= self._beta
        count = self.model.vertex_count
        vertices = np.empty((count, 3), np.float32)
        for axis in range(3):
            vertices[:, axis] = np.bincount(self._vertex, world[axis], minlength=count)
        return vertices, (self.normals(vertices) if normals and self.normals is not None else None)

    def _add_rbf(self, local, part, a, weights):
        """local += sum_i w_i phi(|l - c_i| / sigma) for each column l of `local` (3 x n), the
        centres c_i = A q(p0_i): chunk by chunk, over the centres each chunk can reach."""
        inverse_sigma = part.inverse_sigma
        centres = ((a.astype(np.float64) @ self._member_q[:, part.members]) * inverse_sigma).astype(np.float32)  # 3 x m
        weights_t = np.ascontiguousarray(weights.T) * np.float32(1.0 / 6.0)  # 3 x m: phi's 1/6 in the weights
        scaled = local * inverse_sigma  # in units of sigma, as the centres
        low = np.minimum.reduceat(scaled, part.chunk_starts, axis=1)
        high = np.maximum.reduceat(scaled, part.chunk_starts, axis=1)
        middle, half = (low + high) * np.float32(0.5), (high - low) * np.float32(0.5)
        # Support 2 plus the box's half diagonal, and a hair for rounding (as the daemon).
        reach = (np.float32(2) + np.sqrt((half * half).sum(axis=0))) * np.float32(1.0001) + np.float32(1e-3)
        offset = centres[:, None, :] - middle[:, :, None]  # 3 x chunks x m
        reached = (offset * offset).sum(axis=0) < (reach * reach)[:, None]
        every = reached.all(axis=1)
        for c, columns in enumerate(part.chunks):
            if every[c]:
                chunk_centres, chunk_weights = centres, weights_t
            else:
                listed = np.flatnonzero(reached[c])
                if not len(listed):
                    continue
                chunk_centres, chunk_weights = centres[:, listed], weights_t[:, listed]
            local[:, columns] += chunk_weights @ self._kernel(scaled[:, columns], chunk_centres)

    def _kernel(self, points, centres):
        """6 phi(|p - c|) (m x n, in scratch) of n points and m centres (3 x n, 3 x m), in sigma."""
        n, m = points.shape[1], centres.shape[1]
        r, t, cube = (s[:m * n].reshape(m, n) for s in self._scratch)
        np.subtract(centres[0, :, None], points[0], out=r)
        np.square(r, out=r)
        for axis in (1, 2):
            np.subtract(centres[axis, :, None], points[axis], out=t)
            np.square(t, out=t)
            r += t
        np.sqrt(r, out=r)
        np.subtract(np.float32(2), r, out=r)  # (2 - r)+
        np.maximum(r, np.float32(0), out=r)
        np.subtract(r, np.float32(1), out=t)  # (1 - r)+
        np.maximum(t, np.float32(0), out=t)
        np.multiply(r, r, out=cube)
        cube *= r
        np.multiply(t, t, out=r)
        r *= t
        r *= np.float32(4)
        cube -= r
        return cube
