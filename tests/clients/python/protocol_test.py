"""The package's message codec against the protocol's golden fixtures
(tests/protocol/fixtures/subscriber/, written from the spec by make_v2_fixtures.py), and the
refusals of bytes that break the protocol."""
import os
import struct
import sys
import unittest
import zlib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support.python_clients import fixture  # noqa: E402
import numpy as np  # noqa: E402
from skinstream import protocol as wire  # noqa: E402
from skinstream.evaluation import Evaluator  # noqa: E402


def payload(name):
    data = fixture(name)
    version, kind, size = wire.decode_header(data)
    assert len(data) == wire.HEADER_BYTES + size
    return version, kind, data[wire.HEADER_BYTES:]


class Messages(unittest.TestCase):
    def test_hello_and_ack_are_the_fixtures_bytes(self):
        hello = wire.encode_hello(2, wire.WANT_NORMALS | wire.WANT_MARKERS | wire.WANT_PACED, wire.PARAMETERS, 'Actor2', 'stage-token')
        self.assertEqual(hello, fixture('hello_v2.bin'))
        self.assertEqual(wire.encode_hello(1, 1 | 4), fixture('hello.bin'))
        self.assertEqual(wire.encode_ack(1, struct.unpack_from('<I', fixture('ack.bin'), 12)[0]), fixture('ack.bin'))

    def test_mesh_info(self):
        version, kind, data = payload('mesh_info_v2.bin')
        self.assertEqual((version, kind), (2, wire.MESH_INFO))
        info = wire.MeshInfo(data, version)
        self.assertEqual((info.vertex_count, info.part_count, info.source_rate_hz), (4, 2, 120.0))
        np.testing.assert_array_equal(info.faces, [[0, 1, 2], [0, 2, 3]])
        np.testing.assert_array_equal(info.dominant_part, [0, 1, 255, 1])
        np.testing.assert_array_equal(info.marker_triangles, [[0, 1, 2]])
        self.assertEqual(info.marker_names, ['LSHO', 'RSHO', 'C7'])
        self.assertEqual((info.subject, info.encoding), ('Actor2', wire.COMPRESSED))
        np.testing.assert_array_equal(info.compressed_order, [2, 0, 3, 1])
        version, _, data = payload('mesh_info.bin')
        self.assertEqual(wire.MeshInfo(data, version).marker_names, ['LSHO', 'RSHO', 'C7'])

    def test_status(self):
        version, _, data = payload('status_v2.bin')
        status = wire.Status(data, version)
        self.assertTrue(status.refused)
        self.assertEqual((status.state, status.subject, status.subject_present), ('refused', 'Actor3', False))
        self.assertEqual(status.detail, 'no subject "Actor3" (subjects: Actor1, Actor2)')

    def test_float_frame_with_markers_and_timecode(self):
        version, _, data = payload('frame_v2_float.bin')
        frame = wire.FrameView(data, version)
        self.assertEqual((frame.frame_number, frame.markers_filled, frame.markers_relabelled), (1234, 3, 1))
        self.assertEqual((frame.pipeline_dropped, frame.subscriber_dropped), (7, 2))
        np.testing.assert_array_equal(wire.float_block(frame.positions, 3), [[0, 100, 5], [65535, 131170, 5], [0, 2100, 5]])
        np.testing.assert_array_equal(frame.markers, [[1.5, 2.5, 3.5], [-4, 5, 6.25]])
        np.testing.assert_array_equal(frame.marker_status, [0, 2])
        self.assertEqual(str(frame.timecode), '10:20:30;12')
        self.assertEqual((frame.timecode.subframe, frame.timecode.subframes_per_frame), (1, 5))
        self.assertAlmostEqual(frame.timecode.rate_hz, 29.97, places=5)

    def test_model_and_parameters(self):
        _, kind, data = payload('model.bin')
        self.assertEqual(kind, wire.MODEL)
        model = wire.Model(data)
        self.assertEqual((model.vertex_count, model.part_count, model.member_count, model.influence_count), (3, 2, 3, 4))
        np.testing.assert_array_equal(model.influences_per_vertex, [2, 1, 1])
        np.testing.assert_array_equal(model.influence_parts, [0, 1, 0, 1])
        np.testing.assert_array_equal(model.influence_weights, [0.75, 0.25, 1.0, 1.0])
        np.testing.assert_array_equal(model.part_members, [2, 1])
        self.assertEqual(model.sigma.tolist(), [20.0, 0.0])
        # The reference pose's parameters (A = [I 0 0], R = R0, d = d0, no RBF) give back the
        # reference vertices: the evaluation undoes the reference frames exactly.
        evaluator = Evaluator(model)
        block = struct.pack('<II', 2, 3)
        for p in range(2):
            a = np.zeros((3, 9), np.float32)
            a[:, :3] = np.eye(3)
            block += a.tobytes() + model.rotation[p].tobytes() + model.translation[p].tobytes() + struct.pack('<I', 0)
        block += np.zeros(9, np.float32).tobytes()
        vertices, _ = evaluator.evaluate(block)
        np.testing.assert_allclose(vertices, model.reference, atol=1e-4)

    def test_parameter_frame(self):
        version, _, data = payload('frame_v2_parameters.bin')
        frame = wire.FrameView(data, version)
        self.assertTrue(frame.flags & wire.FRAME_PARAMETERS)
        self.assertEqual(len(frame.positions), 8 + 160 + 24)


class BrokenBytes(unittest.TestCase):
    def assert_one_line(self, what, call, *args):
        with self.assertRaisesRegex(wire.ProtocolError, what) as raised:
            call(*args)
        self.assertNotIn('\n', str(raised.exception))

    def test_headers(self):
        good = fixture('frame_v2_float.bin')
        self.assert_one_line('bad magic', wire.decode_header, b'X' + good[1:])
        self.assert_one_line('unsupported protocol version 3', wire.decode_header, good[:4] + struct.pack('<H', 3) + good[6:])
        self.assert_one_line('unknown message type 9', wire.decode_header, good[:6] + struct.pack('<H', 9) + good[8:])
        self.assert_one_line('exceeds the limit', wire.decode_header, good[:8] + struct.pack('<I', (64 << 20) + 1))
        self.assert_one_line('truncated', wire.decode_header, good[:7])
        self.assert_one_line('unknown message type 6 in version 1', wire.decode_header, fixture('model.bin')[:4] + b'\1\0' + fixture('model.bin')[6:])

    def test_sizes_and_counts(self):
        _, _, frame = payload('frame_v2_float.bin')
        self.assert_one_line('counts say', wire.FrameView, frame[:-4], 2)
        self.assert_one_line('counts say', wire.FrameView, frame + b'\0\0\0\0', 2)
        self.assert_one_line('reserved flag bits', wire.FrameView, frame[:4] + struct.pack('<I', 0x100) + frame[8:], 2)
        _, _, model = payload('model.bin')
        self.assert_one_line('counts', wire.Model, model[:-4])
        _, _, info = payload('mesh_info_v2.bin')
        self.assert_one_line('truncated', wire.MeshInfo, info[:-3], 2)
        self.assert_one_line('left over', wire.MeshInfo, info + b'\0', 2)
        _, _, status = payload('status_v2.bin')
        self.assert_one_line('unknown source state 7', wire.Status, struct.pack('<I', 7) + status[4:], 2)


class Packed(unittest.TestCase):
    """The golden Packed messages (written from the spec by make_v2_fixtures.py) hold the golden
    plain ones byte for byte; forged fields are one-line ProtocolErrors."""

    def test_the_golden_packed_messages_hold_the_plain_ones(self):
        for plain, packed, kind in (('mesh_info_v2.bin', 'packed_mesh_info_v2.bin', wire.MESH_INFO),
                                    ('model.bin', 'packed_model.bin', wire.MODEL)):
            version, packed_kind, body = payload(packed)
            self.assertEqual((version, packed_kind), (2, wire.PACKED))
            self.assertEqual(wire.unpack(body), (kind, payload(plain)[2]))
        kind, mesh = wire.unpack(payload('packed_mesh_info_v2.bin')[2])
        self.assertEqual(wire.MeshInfo(mesh, 2).faces.tolist(), [[0, 1, 2], [0, 2, 3]])

    def test_a_packed_message_needs_version_2(self):
        data = fixture('packed_model.bin')
        with self.assertRaisesRegex(wire.ProtocolError, 'unknown message type 7 in version 1'):
            wire.decode_header(data[:4] + struct.pack('<H', 1) + data[6:])

    def test_forged_fields_are_refused_with_the_reason(self):
        good = payload('packed_mesh_info_v2.bin')[2]
        size = struct.unpack_from('<I', good, 4)[0]

        def forged(offset, fmt, value):
            return good[:offset] + struct.pack(fmt, value) + good[offset + struct.calcsize(fmt):]

        cases = {
            'type 3 (only MeshInfo and Model are packed)': forged(0, '<H', 3),
            'reserved field is 1': forged(2, '<H', 1),
            'over the limit': forged(4, '<I', 100 << 20),
            'shorter than its counts': forged(4, '<I', 5),
            'deflated bytes cannot make': forged(4, '<I', 60_000_000),
            'face count needs 12000000 bytes': forged(12, '<I', 1_000_000),
            'the unpacked size says': forged(4, '<I', size + 1),
            'makes more than the unpacked size': forged(4, '<I', size - 1),
            'bytes after the deflated stream': good + b'\0',
            'corrupt': good[:31] + bytes([good[31] ^ 0xFF]) + good[32:],
            'truncated': good[:6],
        }
        for what, body in cases.items():
            with self.subTest(what):
                with self.assertRaises(wire.ProtocolError) as raised:
                    wire.unpack(body)
                self.assertIn(what, str(raised.exception))
                self.assertNotIn('\n', str(raised.exception))
        for n in range(len(good)):
            with self.assertRaises(wire.ProtocolError, msg=f'cut at {n}'):
                wire.unpack(good[:n])
        # Counts alone unpacked, and a stream that would make 10 MB: refused without making them
        # (zlib reads a limit of 0 as none).
        bomb = struct.pack('<HHI', wire.MODEL, 0, 16) + bytes(16) + zlib.compress(bytes(10 << 20), 9)
        with self.assertRaisesRegex(wire.ProtocolError, 'makes more than the unpacked size 0'):
            wire.unpack(bomb)


if __name__ == '__main__':
    unittest.main(verbosity=2)
