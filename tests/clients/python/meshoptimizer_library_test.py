"""The compressed encoding decoded by the system's libmeshoptimizer through ctypes
(skinstream/meshoptimizer_library.py) against the package's numpy decoder: the same bytes from
the vertex codec, the same one-line refusals of broken streams, normals within one 8-bit step,
and whole body-sized key and delta frames in MeshInfo's compressed order: the same positions bit
for bit. (Against the daemon: subscriber_test.py.)"""
import os
import struct
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support import python_clients  # noqa: E402,F401
from support.meshoptimizer_encoder import MISSING, encode, encode_octahedral, library  # noqa: E402
import numpy as np  # noqa: E402
from skinstream import protocol as wire  # noqa: E402
from skinstream.compressed import CompressedDecoder  # noqa: E402
from skinstream.meshoptimizer_library import find_meshoptimizer  # noqa: E402
from skinstream.vertex_codec import CodecError, decode_octahedral, decode_vertex_buffer  # noqa: E402

BODY = 53514


def positions_block(key_frame_number, origin, step, q):
    """A compressed positions block (docs/subscriber-protocol.md) of n x 3 uint16 grid positions."""
    padded = np.zeros((len(q), 4), np.uint16)
    padded[:, :3] = q
    coded = encode(padded.view(np.uint8).reshape(len(q), 8))
    return struct.pack('<I3f3fI', key_frame_number, *origin, *step, len(coded)) + coded + bytes(wire.padding_to_4(len(coded)))


def normals_block(unit):
    coded = encode(encode_octahedral(unit).view(np.uint8))
    return struct.pack('<I', len(coded)) + coded + bytes(wire.padding_to_4(len(coded)))


def random_unit(rng, n):
    v = rng.normal(size=(n, 3)).astype(np.float32)
    return v / np.linalg.norm(v, axis=1)[:, None]


@unittest.skipIf(library is None, MISSING)
class MeshoptimizerLibrary(unittest.TestCase):
    def setUp(self):
        self.library, line = find_meshoptimizer()
        self.assertIsNotNone(self.library, line)

    def test_decodes_the_bytes_the_numpy_decoder_decodes(self):
        rng = np.random.default_rng(1)
        for n in (1, 16, 17, 257, BODY):
            for size in (4, 8):
                v = (np.cumsum(rng.integers(-40, 41, (n, size)), axis=0) % 256).astype(np.uint8)
                coded = encode(v)
                with self.subTest(n=n, size=size):
                    decoded = self.library.decode_vertex_buffer(coded, n, size)
                    np.testing.assert_array_equal(decoded, v)
                    np.testing.assert_array_equal(decoded, decode_vertex_buffer(coded, n, size))

    def test_broken_streams_are_the_numpy_decoders_one_line_errors(self):
        rng = np.random.default_rng(2)
        good = encode((np.cumsum(rng.integers(-5, 6, (300, 8)), axis=0) % 256).astype(np.uint8))
        for what, data in {'truncated': good[:len(good) // 2], 'version 1': bytes([0xA1]) + good[1:], 'empty': b''}.items():
            with self.subTest(what):
                with self.assertRaises(CodecError) as numpy_error:
                    decode_vertex_buffer(data, 300, 8)
                with self.assertRaises(CodecError) as library_error:
                    self.library.decode_vertex_buffer(data, 300, 8)
                self.assertEqual(str(library_error.exception), str(numpy_error.exception))
                self.assertNotIn('\n', str(library_error.exception))
        with self.assertRaisesRegex(ValueError, 'vertex size 6'):
            self.library.decode_vertex_buffer(good, 300, 6)  # the library would abort on it

    def test_octahedral_normals_within_one_step_of_the_numpy_decoders(self):
        octahedral = encode_octahedral(random_unit(np.random.default_rng(3), 5000))
        ours, theirs = decode_octahedral(octahedral), self.library.decode_octahedral(octahedral.copy())
        self.assertEqual((theirs.shape, theirs.dtype), ((5000, 3), np.float32))
        np.testing.assert_allclose(np.linalg.norm(theirs, axis=1), 1, atol=1e-6)
        # The library scales by the CPU's approximate reciprocal square root (vertex_codec_test.py).
        self.assertLessEqual(np.abs(np.round(ours * 127) - np.round(theirs * 127)).max(), 1)

    def test_key_and_delta_frames_of_a_body_as_the_numpy_decoder(self):
        rng = np.random.default_rng(4)
        order = rng.permutation(BODY)  # the vertex of each coded vertex
        origin, step = np.float32([-1200, -300, -50]), np.float32([0.04, 0.035, 0.03])
        key_q = (np.cumsum(rng.integers(-60, 61, (BODY, 3)), axis=0) % 65536).astype(np.uint16)
        delta_q = rng.integers(-30, 31, (BODY, 3)).astype(np.uint16)  # mod 2^16, as the daemon sends it
        frames = [(positions_block(7, origin, step, key_q), normals_block(random_unit(rng, BODY)), True),
                  (positions_block(7, origin, step, delta_q), normals_block(random_unit(rng, BODY)), False)]
        by_numpy, by_library = CompressedDecoder(BODY, order), CompressedDecoder(BODY, order, self.library)
        self.assertEqual((by_numpy.name, by_library.name), ('numpy', 'libmeshoptimizer'))
        for (positions, normals, key), q in zip(frames, (key_q, key_q + delta_q)):
            with self.subTest(key=key):
                p_numpy, n_numpy = by_numpy.decode(positions, normals, key)
                p_library, n_library = by_library.decode(positions, normals, key)
                np.testing.assert_array_equal(p_library, p_numpy)
                expected = np.empty((BODY, 3), np.float32)
                expected[order] = origin + q * step
                np.testing.assert_array_equal(p_library, expected)
                self.assertLessEqual(np.abs(np.round(n_numpy * 127) - np.round(n_library * 127)).max(), 1)
        # A key whose coded bytes end early: the codec's error, said of the positions.
        header = struct.Struct('<I3f3fI')
        cut = frames[0][0][header.size:header.size + 1000]
        broken = header.pack(8, *origin, *step, len(cut)) + cut
        with self.assertRaisesRegex(wire.ProtocolError, '^compressed positions: ') as raised:
            by_library.decode(broken, None, True)
        self.assertNotIn('\n', str(raised.exception))


if __name__ == '__main__':
    unittest.main(verbosity=2)
