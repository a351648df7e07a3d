"""The parameter encoding turned into vertices with numpy, as docs/subscriber-protocol.md writes
the evaluation out (Park & Hodgins 2006, eqs. 8 and 9):

    for each influence (part p, weight beta) of vertex j:
        u = R0_p v0_j + d0_p;  s = clamp(u, box_min_p, box_max_p);  l = A_p q(s)
        if the RBF term applies and sigma_p > 0:
            l += sum over members i of p: w_i phi(|l - A_p q(p0_i)| / sigma_p)
        v_j += beta R_p^T (l + (u - s) - d_p)

Everything that does not change from frame to frame (u, s, q(s), the members' q) is computed
once from the Model; a frame is one matrix product per part, its RBF sum, and a weighted sum per
vertex, phi(r) = ((2 - r)+³ - 4 (1 - r)+³) / 6 being the uniform cubic B-spline of support 2.
In float64 but for the RBF sums (float32): on the demo body the daemon's float32 buffer is
within 0.0005 mm of the result (the protocol promises 0.01 mm)."""
import numpy as np

from .protocol import PARAMETER_PART_BYTES, ProtocolError

_PART = np.dtype([('A', '<f4', (3, 9)), ('R', '<f4', (3, 3)), ('d', '<f4', 3), ('flags', '<u4')])
assert _PART.itemsize == PARAMETER_PART_BYTES
_CHUNK = 2048  # rows of the RBF sums at a time: 2048 x 148 floats, three of them, stay in the cache


def quadratic_terms(x):
    """q(x, y, z) = (x, y, z, x², y², z², xy, yz, zx) of each row of an n x 3 array."""
    return np.concatenate([x, x * x, x * np.roll(x, -1, axis=1)], axis=1)


def vertex_normals(positions, faces):
    """Unit area-weighted vertex normals (float32, V x 3) of the faces (F x 3, counter-clockwise)."""
    p = positions.astype(np.float64, copy=False)
    a, b, c = p[faces[:, 0]], p[faces[:, 1]], p[faces[:, 2]]
    face = np.cross(b - a, c - a)  # twice the area, outwards
    v = len(positions)
    corners = faces.ravel()
    summed = np.stack([np.bincount(corners, np.repeat(face[:, axis], 3), minlength=v) for axis in range(3)], axis=1)
    length = np.sqrt((summed * summed).sum(axis=1))
    with np.errstate(invalid='ignore', divide='ignore'):
        unit = np.where(length[:, None] > 0, summed / length[:, None], 0.0)
    return unit.astype(np.float32)


class Evaluator:
    """Evaluates one frame's parameters block against the Model it came after."""

    def __init__(self, model, faces=None):
        self.model = model
        self.faces = None if faces is None else np.asarray(faces, np.int64)
        k_vertex = np.repeat(np.arange(model.vertex_count), model.influences_per_vertex)
        k_part = model.influence_parts.astype(np.int64)
        order = np.argsort(k_part, kind='stable')  # influences part after part
        self._vertex = k_vertex[order]
        part = k_part[order]
        self._beta = model.influence_weights[order].astype(np.float64)
        rotation = model.rotation.astype(np.float64)
        v0 = model.reference.astype(np.float64)[self._vertex]
        u = np.einsum('kij,kj->ki', rotation[part], v0) + model.translation[part]
        s = np.clip(u, model.box_min[part], model.box_max[part])
        self._outside = u - s
        self._q = quadratic_terms(s)
        bounds = np.searchsorted(part, np.arange(model.part_count + 1)).tolist()
        self._slices = [slice(bounds[p], bounds[p + 1]) for p in range(model.part_count)]
        first = np.concatenate(([0], np.cumsum(model.part_members))).astype(np.int64).tolist()
        self._member_slices = [slice(first[p], first[p + 1]) for p in range(model.part_count)]
        self._member_q = quadratic_terms(model.members.astype(np.float64))
        self._sigma = model.sigma.astype(np.float64)
        widest = int(model.part_members.max())
        self._scratch = [np.empty((_CHUNK, widest), np.float32) for _ in range(3)]

    def parameters(self, block):
        """(parts, weights) of a Frame's parameters block, checked against the Model."""
        m = self.model
        if len(block) < 8:
            raise ProtocolError(f'parameters: block of {len(block)} bytes is truncated')
        parts, members = np.frombuffer(block, '<u4', 2)
        if parts != m.part_count or members != m.member_count:
            raise ProtocolError(f'parameters: {parts} parts and {members} members, the model has {m.part_count} and {m.member_count}')
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

    def _rbf(self, local, centres, weights, inverse_sigma):
        """sum_i w_i phi(|l - c_i| / sigma) for each row l of `local`: in float32 (within 1e-4 mm
        of float64 here) and in chunks of rows whose scratch stays in the cache, in place."""
        centres = centres.astype(np.float32)
        out = np.empty((len(local), 3))
        r = self._scratch[0][:, :len(centres)]
        t = self._scratch[1][:, :len(centres)]
        u = self._scratch[2][:, :len(centres)]
        for start in range(0, len(local), _CHUNK):
            rows = local[start:start + _CHUNK].astype(np.float32)
            n = len(rows)
            rn, tn, un = r[:n], t[:n], u[:n]
            np.subtract(rows[:, 0, None], centres[None, :, 0], out=rn)
            np.square(rn, out=rn)
            for axis in (1, 2):
                np.subtract(rows[:, axis, None], centres[None, :, axis], out=tn)
                np.square(tn, out=tn)
                rn += tn
            np.sqrt(rn, out=rn)
            rn *= np.float32(inverse_sigma)
            # phi(r) = ((2 - r)+^3 - 4 (1 - r)+^3) / 6, the 1/6 applied to the sums
            np.subtract(np.float32(2), rn, out=tn)
            np.maximum(tn, 0, out=tn)
            np.multiply(tn, tn, out=un)
            un *= tn
            np.subtract(np.float32(1), rn, out=rn)
            np.maximum(rn, 0, out=rn)
            np.multiply(rn, rn, out=tn)
            tn *= rn
            tn *= np.float32(4)
            un -= tn
            out[start:start + n] = un @ weights
        return out * (1.0 / 6.0)

    def evaluate(self, block, normals=False):
        """(vertices, normals): V x 3 float32 (normals None unless asked for and the faces known)."""
        fits, weights = self.parameters(block)
        world = np.empty((len(self._vertex), 3))
        for p, rows in enumerate(self._slices):
            fit = fits[p]
            a = fit['A'].astype(np.float64)
            local = self._q[rows] @ a.T
            if fit['flags'] & 1 and self._sigma[p] > 0:
                members = self._member_slices[p]
                local += self._rbf(local, self._member_q[members] @ a.T, weights[members], 1.0 / self._sigma[p])
            local += self._outside[rows] - fit['d']
            world[rows] = local @ fit['R'].astype(np.float64)  # R^T x, row by row
        world *= self._beta[:, None]
        count = self.model.vertex_count
        vertices = np.stack([np.bincount(self._vertex, world[:, axis], minlength=count) for axis in range(3)], axis=1)
        vertices = vertices.astype(np.float32)
        return vertices, (vertex_normals(vertices, self.faces) if normals and self.faces is not None else None)
