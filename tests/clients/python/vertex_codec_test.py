"""The numpy decoder of meshoptimizer's vertex codec against the library itself (Debian's
libmeshoptimizer, loaded with ctypes): byte for byte on buffers of every shape the codec
treats differently, and the same refusals of broken streams."""
import ctypes
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support import python_clients  # noqa: E402,F401
from support.meshoptimizer_encoder import MISSING, encode, pointer as _pointer  # noqa: E402
from support.meshoptimizer_encoder import library as meshopt  # noqa: E402
import numpy as np  # noqa: E402
from skinstream.vertex_codec import CodecError, decode_octahedral, decode_vertex_buffer  # noqa: E402

def library_accepts(data, n, size):
    out = np.zeros((max(n, 1), size), np.uint8)
    buffer = np.frombuffer(data, np.uint8).copy()
    return meshopt.meshopt_decodeVertexBuffer(_pointer(out), ctypes.c_size_t(n), ctypes.c_size_t(size), _pointer(buffer),
                                              ctypes.c_size_t(len(data))) == 0


@unittest.skipIf(meshopt is None, MISSING)
class VertexCodec(unittest.TestCase):
    def test_decodes_what_the_library_encodes(self):
        rng = np.random.default_rng(7)
        # Counts around the 16-vertex groups and the 256-vertex blocks; sizes from 4 bytes (the
        # normals) past 32 (where the tail stops being padded); contents that choose each of
        # the four group codings, and 2- and 4-bit groups with escaped bytes.
        for n in (1, 15, 16, 17, 255, 256, 257, 1000):
            for size in (4, 8, 12, 16, 32, 36, 64):
                for kind in ('random', 'smooth', 'steps', 'zero'):
                    if kind == 'random':
                        v = rng.integers(0, 256, (n, size), dtype=np.uint8)
                    elif kind == 'smooth':
                        v = (np.cumsum(rng.integers(-2, 3, (n, size)), axis=0) % 256).astype(np.uint8)
                    elif kind == 'steps':
                        v = (np.cumsum(rng.integers(-9, 10, (n, size)) * (rng.random((n, size)) < 0.3), axis=0) % 256).astype(np.uint8)
                    else:
                        v = np.zeros((n, size), np.uint8)
                    with self.subTest(n=n, size=size, kind=kind):
                        np.testing.assert_array_equal(decode_vertex_buffer(encode(v), n, size), v)

    def test_decodes_a_body_sized_buffer_of_16_bit_positions(self):
        rng = np.random.default_rng(3)
        q = np.zeros((53514, 4), np.uint16)
        q[:, :3] = np.cumsum(rng.integers(-60, 61, (53514, 3)), axis=0) % 65536
        v = q.view(np.uint8).reshape(53514, 8)
        np.testing.assert_array_equal(decode_vertex_buffer(encode(v), 53514, 8), v)

    def test_refuses_what_the_library_refuses(self):
        rng = np.random.default_rng(5)
        v = (np.cumsum(rng.integers(-5, 6, (300, 8)), axis=0) % 256).astype(np.uint8)
        good = encode(v)
        broken = {
            'truncated': good[:len(good) // 2],
            'no tail': good[:-20],
            'a byte too many': good[:-32] + b'\0' + good[-32:],
            'version 1': bytes([0xA1]) + good[1:],
            'not the codec': bytes([0x42]) + good[1:],
            'empty': b'',
        }
        for what, data in broken.items():
            with self.subTest(what):
                self.assertFalse(library_accepts(data, 300, 8))
                with self.assertRaises(CodecError) as raised:
                    decode_vertex_buffer(data, 300, 8)
                self.assertNotIn('\n', str(raised.exception))
        with self.assertRaisesRegex(CodecError, 'version 1'):
            decode_vertex_buffer(broken['version 1'], 300, 8)

    def test_octahedral_normals_as_the_library_filters_them(self):
        rng = np.random.default_rng(11)
        normals = rng.normal(size=(5000, 4)).astype(np.float32)
        normals[:, :3] /= np.linalg.norm(normals[:, :3], axis=1)[:, None]
        normals[:, 3] = 0
        normals[:6, :3] = [[1, 0, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1], [0.6, 0.8, 0], [0, 0.6, -0.8]]
        octahedral = np.zeros((5000, 4), np.int8)
        meshopt.meshopt_encodeFilterOct(_pointer(octahedral), ctypes.c_size_t(5000), ctypes.c_size_t(4), 8, _pointer(normals))
        filtered = octahedral.copy()
        meshopt.meshopt_decodeFilterOct(_pointer(filtered), ctypes.c_size_t(5000), ctypes.c_size_t(4))
        library = filtered[:, :3].astype(np.float32)
        library /= np.linalg.norm(library, axis=1)[:, None]
        ours = decode_octahedral(octahedral)
        # The library's vector path scales by an approximate reciprocal square root (its
        # precision is the CPU's), so a component may round to the neighbouring 8-bit step: at
        # most one step (1/127 of the unit) in a component, and rarely: under 0.7 degrees with two.
        steps = np.abs(np.round(ours * 127) - np.round(library * 127))
        self.assertLessEqual(steps.max(), 1)
        self.assertLess(np.count_nonzero(steps) / steps.size, 0.02)
        angle = np.degrees(np.arctan2(np.linalg.norm(np.cross(ours, library), axis=1), (ours * library).sum(axis=1)))
        self.assertLess(angle.max(), 0.7)
        # And within the protocol's 1.5 degrees of the vectors coded.
        cosine = (ours * normals[:, :3]).sum(axis=1)
        self.assertGreater(cosine.min(), np.cos(np.radians(1.5)))


if __name__ == '__main__':
    unittest.main(verbosity=2)
