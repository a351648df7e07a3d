"""The Python package against the real skinstreamd replaying the demo subject over loopback:
every encoding's vertices and normals, by each of its decoders (numpy, and the system's
libmeshoptimizer and the C++ client library, which ctest names in SKINSTREAM_CLIENT_LIBRARY),
against the daemon's own float buffer of the same frame number; and the bad paths (no daemon, a
refused Hello, bytes that break the protocol) as one-line errors."""
import os
import socket
import struct
import sys
import threading
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support.python_clients import CLIENT_LIBRARY, demo_daemon, fixture  # noqa: E402
import numpy as np  # noqa: E402
import skinstream  # noqa: E402
from skinstream.meshoptimizer_library import find_meshoptimizer  # noqa: E402
from skinstream.normals import vertex_normals  # noqa: E402

# (encoding, the system's libraries or numpy only, the decoder that must then decode it)
SUBSCRIBERS = [('float', True, 'numpy'), ('quantised', True, 'numpy'), ('compressed', False, 'numpy'),
               ('parameters', False, 'numpy')]
if os.path.exists(CLIENT_LIBRARY):  # built: then it must load
    SUBSCRIBERS.append(('parameters', True, 'libskinstream_client'))
if find_meshoptimizer()[0] is not None:
    SUBSCRIBERS.append(('compressed', True, 'libmeshoptimizer'))


def receive(port, encoding, libraries, count, results, until=None):
    """Keeps the first `count` frames the subscriber gets; with `until` (an event), goes on until
    it is set, keeping at most `count`."""
    frames = {}
    with skinstream.Subscriber(port=port, encoding=encoding, normals=True, markers=True, libraries=libraries) as sub:
        deadline = time.monotonic() + 120
        while len(frames) < count and time.monotonic() < deadline and not (until and until.is_set()):
            frame = sub.next_frame(1.0)
            if frame is not None:
                # A frame is its number and its receive time: the demo take loops every 10 s,
                # and under load the daemon drops input frames, after which the filler's output
                # for a number differs from the last loop's (seen: 2.8 mm).
                frames[frame.frame_number, frame.receive_time_ns] = frame
        results[encoding, libraries] = (frames, sub.encoding, sub.mesh, sub.model, sub.decoder)


def angles_degrees(a, b):
    """Angle between unit vectors row by row, as atan2(|a x b|, a . b): exact near 0."""
    a, b = a.astype(np.float64), b.astype(np.float64)
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), (a * b).sum(axis=1)))


class DemoSubject(unittest.TestCase):
    def test_every_encoding_gives_the_daemons_vertices(self):
        # Each subscriber keeps the first 60 frames it gets, and at least 10 of them are compared
        # with the float subscriber's frame of the same number. The daemon's newest-wins queues
        # drop a slow decoder's frames (numpy's on a loaded machine: one in several), so its 60
        # span seconds: the float subscriber, the reference, receives until the others are done
        # (at most 400 frames, about 0.5 GB). With 60 of its own it had 9 in common with a
        # compressed subscriber's 60 on a loaded machine.
        count, compared, reference_count = 60, 10, 400
        results = {}
        others_done = threading.Event()
        with demo_daemon() as daemon:
            reference_thread = threading.Thread(target=receive, args=(daemon.sub_port, 'float', True, reference_count,
                                                                      results, others_done))
            threads = [threading.Thread(target=receive, args=(daemon.sub_port, e, libraries, count, results))
                       for e, libraries, _ in SUBSCRIBERS if (e, libraries) != ('float', True)]
            for t in threads + [reference_thread]:
                t.start()
            for t in threads:
                t.join()
            others_done.set()
            reference_thread.join()
            self.assertEqual(daemon.stop(), 0, daemon.log())
        reference, _, mesh, _, _ = results['float', True]
        self.assertGreaterEqual(len(reference), count)
        first = next(iter(reference.values()))
        self.assertEqual(first.vertices.shape, (53514, 3))
        self.assertEqual(first.vertices.dtype, np.float32)
        self.assertEqual(first.markers.shape, (len(mesh.marker_names), 3))
        self.assertEqual(first.marker_status.shape, (len(mesh.marker_names),))
        self.assertLessEqual(int(first.marker_status.max()), 4)
        self.assertGreater(first.receive_time_ns, 0)
        self.assertGreaterEqual(first.publish_time_ns, first.receive_time_ns)
        self.assertEqual(mesh.faces.shape[1], 3)
        # The normals the package computes for the parameter encoding, from the daemon's own
        # positions: the daemon's normals.
        computed = vertex_normals(first.vertices, mesh.faces)
        self.assertLess(angles_degrees(computed, first.normals).max(), 0.001)
        # Position tolerance (mm) and normal tolerance (degrees) of each decoder: the client
        # library is the daemon's evaluator on the same floats, so its buffers are the daemon's
        # bit for bit; the numpy evaluation is float32 in another order (within 0.001 mm; the
        # demo body has triangles with 0.2 mm edges, whose normals that moves by up to 0.1
        # degree: from the same positions the normals agree to 0.0001 degree); quantised within
        # half a step of the frame's box; compressed within half a step of the key's grid and
        # 8-bit octahedral normals.
        tolerances = {'parameters': (0.01, 0.5), 'quantised': (0.02, 0.01), 'compressed': (0.025, 1.5)}
        for encoding, libraries, decoder in SUBSCRIBERS:
            if encoding == 'float':
                continue
            mm, degrees = (0, 0) if decoder == 'libskinstream_client' else tolerances[encoding]
            frames, served, _, model, decoded_by = results[encoding, libraries]
            self.assertEqual((served, decoded_by), (encoding, decoder))
            common = sorted(set(frames) & set(reference))
            self.assertGreaterEqual(len(common), compared, encoding)
            worst_mm = max(np.abs(frames[n].vertices.astype(np.float64) - reference[n].vertices).max() for n in common)
            worst_degrees = max(angles_degrees(frames[n].normals, reference[n].normals).max() for n in common)
            print(f'{encoding} by {decoder}: {len(common)} frames, largest differences {worst_mm:.4g} mm, {worst_degrees:.3g} degrees')
            self.assertLessEqual(worst_mm, mm, decoder)
            self.assertLessEqual(worst_degrees, degrees, decoder)
            for n in common:
                if decoder == 'libskinstream_client':
                    np.testing.assert_array_equal(frames[n].vertices, reference[n].vertices)
                    np.testing.assert_array_equal(frames[n].normals, reference[n].normals)
                np.testing.assert_array_equal(frames[n].markers, reference[n].markers)
                np.testing.assert_array_equal(frames[n].marker_status, reference[n].marker_status)
            if encoding == 'parameters':
                self.assertEqual(model.vertex_count, 53514)

    def test_an_unknown_subject_is_refused_with_the_reason(self):
        with demo_daemon() as daemon:
            with skinstream.Subscriber(port=daemon.sub_port, subject='Actor9') as sub:
                with self.assertRaisesRegex(skinstream.Refused, 'refused.*Actor9') as raised:
                    while True:
                        sub.next_frame(10)
        self.assertNotIn('\n', str(raised.exception))


class PackedJoiners(unittest.TestCase):
    def test_packed_and_plain_joiners_get_the_same_mesh_model_and_vertices(self):
        """MeshInfo and the Model asked for packed (the default) and plain: the same faces, Model
        and vertices, for under 1 / 2.5 of the bytes before the first frame."""
        results = {}

        def join(packed):
            frames, first_bytes = {}, None
            with skinstream.Subscriber(port=daemon.sub_port, encoding='parameters', normals=False, packed=packed) as sub:
                deadline = time.monotonic() + 120
                while len(frames) < 20 and time.monotonic() < deadline:
                    frame = sub.next_frame(1.0)
                    if frame is not None:
                        first_bytes = first_bytes or sub.bytes_received
                        frames[frame.frame_number, frame.receive_time_ns] = frame.vertices  # as in receive()
                results[packed] = (frames, sub.mesh, sub.model, first_bytes)

        with demo_daemon() as daemon:
            threads = [threading.Thread(target=join, args=(packed,)) for packed in (True, False)]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            self.assertEqual(daemon.stop(), 0, daemon.log())
        (packed_frames, packed_mesh, packed_model, packed_bytes) = results[True]
        (plain_frames, plain_mesh, plain_model, plain_bytes) = results[False]
        np.testing.assert_array_equal(packed_mesh.faces, plain_mesh.faces)
        self.assertEqual(packed_mesh.marker_names, plain_mesh.marker_names)
        for field in ('reference', 'rotation', 'translation', 'members', 'influences_per_vertex'):
            np.testing.assert_array_equal(getattr(packed_model, field), getattr(plain_model, field), field)
        common = sorted(set(packed_frames) & set(plain_frames))
        self.assertGreaterEqual(len(common), 5)
        for n in common:
            np.testing.assert_array_equal(packed_frames[n], plain_frames[n])
        print(f'bytes before the first frame: packed {packed_bytes}, plain {plain_bytes}')
        self.assertLess(packed_bytes * 2.5, plain_bytes)

    def test_a_packed_message_not_asked_for_is_an_error(self):
        fake = FakeDaemon(fixture('packed_mesh_info_v2.bin'))
        try:
            with skinstream.Subscriber(port=fake.port, encoding='parameters', packed=False) as sub:
                with self.assertRaisesRegex(skinstream.ProtocolError, 'did not ask for'):
                    sub.next_frame(5)
        finally:
            fake.thread.join()
            fake.listener.close()


class FakeDaemon:
    """Answers the Hello with the bytes given, then closes."""

    def __init__(self, reply):
        self.listener = socket.create_server(('127.0.0.1', 0))
        self.port = self.listener.getsockname()[1]
        self.thread = threading.Thread(target=self._serve, args=(reply,))
        self.thread.start()

    def _serve(self, reply):
        peer, _ = self.listener.accept()
        with peer:
            peer.recv(1024)
            peer.sendall(reply)
            time.sleep(0.2)

    def error(self, encoding='parameters'):
        try:
            with skinstream.Subscriber(port=self.port, encoding=encoding) as sub:
                while sub.next_frame(5) is None:
                    pass
            return 'no error'
        except skinstream.Error as e:
            return str(e)
        finally:
            self.thread.join()
            self.listener.close()


def error_for(reply):
    return FakeDaemon(reply).error()


class BadDaemons(unittest.TestCase):
    def test_no_daemon_is_a_one_line_error(self):
        with socket.create_server(('127.0.0.1', 0)) as s:
            port = s.getsockname()[1]
        with self.assertRaisesRegex(skinstream.ConnectionLost, f'127.0.0.1:{port}: .*refused') as raised:
            skinstream.Subscriber(port=port)
        self.assertNotIn('\n', str(raised.exception))
        with self.assertRaises(ValueError):
            skinstream.Subscriber(encoding='parameters', protocol_version=1)

    def test_bytes_that_break_the_protocol_are_one_line_errors(self):
        mesh_info = fixture('mesh_info_v2.bin')
        model = fixture('model.bin')  # 3 vertices; the MeshInfo has 4
        cases = [
            ('bad magic', b'X' + mesh_info[1:]),
            ('version 1, not 2', fixture('mesh_info.bin')),  # a version 1 answer to a version 2 Hello
            ('unsupported protocol version 7', mesh_info[:4] + struct.pack('<H', 7) + mesh_info[6:]),
            ('exceeds the limit', mesh_info[:8] + struct.pack('<I', 100 << 20)),
            ('Model message before MeshInfo', model),
            ('the Model has 3 vertices, MeshInfo 4', mesh_info + model),
            ('closed the connection', mesh_info + model[:-10]),  # truncated: the connection ends inside it
            ('before the Model', mesh_info + fixture('frame_v2_parameters.bin')),
            ('Packed: the deflated stream is corrupt', fixture('packed_mesh_info_v2.bin')[:43] + b'\xff' + fixture('packed_mesh_info_v2.bin')[44:]),
            ('the Model has 3 vertices, MeshInfo 4', fixture('packed_mesh_info_v2.bin') + fixture('packed_model.bin')),
        ]
        for what, reply in cases:
            with self.subTest(what):
                error = error_for(reply)
                self.assertIn(what, error)
                self.assertNotIn('\n', error)


def stream_with_a_broken_frame(frames, broken):
    """MeshInfo (version 2, float, 3 vertices, 2 markers), then `frames` float Frames numbered 1,
    2, ... (the golden frame_v2_float.bin's payload), the one numbered `broken` with a vertex
    coordinate that is not finite."""
    from skinstream import protocol as wire
    mesh = struct.pack('<IIIIf', 3, 1, 2, 1, 120.0) + struct.pack('<3I', 0, 1, 2) + bytes([0, 0, 0])
    mesh += struct.pack('<I', 0) + wire._short_string('A', 'marker') + wire._short_string('B', 'marker')
    mesh += wire._short_string('fake', 'subject') + struct.pack('<II', wire.FLOAT, 0)
    out = wire.message(wire.MESH_INFO, mesh, 2)
    template = fixture('frame_v2_float.bin')
    for n in range(1, frames + 1):
        frame = bytearray(template)
        frame[12:16] = struct.pack('<I', n)  # after the header: the frame number
        if n == broken:
            frame[80:84] = struct.pack('<f', float('inf'))  # the first coordinate, after the fixed part and the timecode
        out += bytes(frame)
    return out


class BrokenFrames(unittest.TestCase):
    def test_a_frame_that_is_not_finite_is_skipped_and_the_stream_goes_on(self):
        # It raised at the first (the package stopped after 12 frames of the real daemon's).
        listener = socket.create_server(('127.0.0.1', 0))

        def serve():
            peer, _ = listener.accept()
            with peer:
                peer.recv(1024)  # the Hello
                peer.sendall(stream_with_a_broken_frame(10, 4))
                while peer.recv(1024):
                    pass

        thread = threading.Thread(target=serve)
        thread.start()
        numbers = []
        with self.assertLogs('skinstream', 'WARNING') as logged:
            with skinstream.Subscriber(port=listener.getsockname()[1], encoding='float') as sub:
                while len(numbers) < 9:
                    frame = sub.next_frame(5)
                    self.assertIsNotNone(frame)
                    self.assertTrue(np.isfinite(frame.vertices).all())
                    numbers.append(frame.frame_number)
                self.assertEqual(sub.frames_rejected, 1)
                self.assertEqual(sub.last_rejection, 'frame skipped: a Frame whose vertices are not all finite')
        thread.join()
        listener.close()
        self.assertEqual(numbers, [1, 2, 3, 5, 6, 7, 8, 9, 10])
        self.assertEqual(len(logged.output), 1)
        self.assertIn('frame skipped: a Frame whose vertices are not all finite (1 frames skipped so far)', logged.output[0])


def mesh_info_of(vertices, markers):
    """A version 2 MeshInfo of `vertices` vertices (no faces, float) and `markers` empty names."""
    from skinstream import protocol as wire
    payload = struct.pack('<IIIIf', vertices, 0, markers, 1, 120.0) + bytes(vertices) + struct.pack('<I', 0)
    payload += bytes(2 * markers) + struct.pack('<HII', 0, wire.FLOAT, 0)
    return wire.message(wire.MESH_INFO, payload, 2)


class Limits(unittest.TestCase):
    def test_a_mesh_info_beyond_the_limits_is_an_error_before_anything_is_made(self):
        # 67 million vertices in a 64 MiB message, 8 million empty marker names: the package
        # peaked at 4.29 GB and 651 MB making arrays for them.
        error = error_for(mesh_info_of(67_000_000, 0))
        self.assertIn('MeshInfo: 67000000 vertices, more than this subscriber takes (4000000, its max_vertices)', error)
        error = error_for(mesh_info_of(3, 8_000_000))
        self.assertIn('MeshInfo: 8000000 markers, more than this subscriber takes (4096, its max_markers)', error)

    def test_the_daemons_words_in_an_error_are_printable(self):
        from skinstream import protocol as wire
        detail = 'no\n\x1b[31mskinstream-sub: error: forged'.encode()
        status = struct.pack('<IfQQ', 4, 0.0, 0, 0) + struct.pack('<H', len(detail)) + detail + struct.pack('<HII', 0, 0, 0)
        error = error_for(wire.message(wire.STATUS, status, 2))
        self.assertEqual(error, 'the daemon refused this subscriber: no\\x0a\\x1b[31mskinstream-sub: error: forged')


class Paced(unittest.TestCase):
    def test_skipped_compressed_deltas_are_acknowledged_too(self):
        # A delta of a key the subscriber never saw (it gave way in the daemon's queue) is
        # skipped, and acknowledged like the frames shown: the daemon waits while two are not.
        delta = bytearray(fixture('frame_v2_compressed.bin'))
        delta[16] &= ~0x40  # the flags after the header and the frame number: no longer a key
        delta[44:48] = struct.pack('<I', 4)  # the vertex count: the MeshInfo's 4 (the coded bytes are never read)
        listener = socket.create_server(('127.0.0.1', 0))
        received = bytearray()

        def serve():
            peer, _ = listener.accept()
            with peer:
                peer.recv(1024)  # the Hello
                peer.sendall(fixture('mesh_info_v2.bin') + bytes(delta) * 3)
                while chunk := peer.recv(1024):
                    received.extend(chunk)

        thread = threading.Thread(target=serve)
        thread.start()
        with skinstream.Subscriber(port=listener.getsockname()[1], encoding='compressed', paced=True) as sub:
            self.assertIsNone(sub.next_frame(1.5))
            self.assertEqual(sub.frames_skipped, 3)
        thread.join()
        listener.close()
        acks = [struct.unpack_from('<IHHII', received, 16 * i) for i in range(len(received) // 16)]
        self.assertEqual(len(received), 3 * 16)
        self.assertEqual(acks, [(0x46534B53, 2, 5, 4, 1234)] * 3)


if __name__ == '__main__':
    unittest.main(verbosity=2)
