"""The Blender add-on (clients/blender), installed from its zip into a headless Blender
(blender -b --factory-startup --python addon_test.py -- ADDON_ZIP) and run against the real
skinstreamd on the demo subject. Background Blender runs no timers, so the test calls the
add-on's timer function itself, as Blender's would.

- the body mesh's vertices equal the daemon's (a float subscriber's frame of the same number)
  within 0.1 mm, for the parameter and compressed encodings (bit for bit when the C++ client
  library evaluates the parameters: the package carried finds it as outside Blender, and the
  system's libmeshoptimizer, and the panel says which decodes); markers as a point cloud;
- across a subject swapped at run time (POST /subjects/NAME/file) the same body object goes on
  taking the frames, of the new subject, with no error and no reconnection;
- a daemon that stalls never holds the timer up; one that goes away is shown in the panel's
  status and reconnected to when it comes back;
- a recording plays back through Blender's own Mesh Cache modifier, sample for sample;
- `skinstream deform --format pc2` plays through the Mesh Cache modifier as the file says."""
import os
import socket
import subprocess
import sys
import threading
import time
import unittest

import bpy
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support.python_clients import (CLIENT_LIBRARY, DEMO, SCRATCH, SKINSTREAM_CLI, demo_daemon, swap_daemon,  # noqa: E402
                                    swap_subject_file, swap_subjects)
import skinstream as source_package  # noqa: E402  (the source tree's, for the reference subscriber)

ADDON_ZIP = sys.argv[sys.argv.index('--') + 1]


class FloatFrames:
    """A float subscriber on a thread: the daemon's own vertex buffers, by frame number."""

    def __init__(self, port):
        self.frames = {}
        self._stop = threading.Event()
        self._subscriber = source_package.Subscriber(port=port, encoding='float', normals=False, markers=True)
        self._thread = threading.Thread(target=self._run)
        self._thread.start()

    def _run(self):
        while not self._stop.is_set():
            frame = self._subscriber.next_frame(0.2)
            if frame is not None:
                self.frames[frame.frame_number] = frame

    def mesh(self):
        return self._subscriber.mesh

    def stop(self):
        self._stop.set()
        self._thread.join()
        self._subscriber.close()


def vertices_of(mesh):
    co = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get('co', co)
    return co.reshape(-1, 3)


def read_pc2(path):
    """The samples of a PC2 file, read here from its bytes (not with the package)."""
    data = np.fromfile(path, np.uint8)
    assert data[:12].tobytes() == b'POINTCACHE2\0'
    points, samples = int(data[16:20].view('<i4')[0]), int(data[28:32].view('<i4')[0])
    return data[32:].view('<f4').reshape(samples, points, 3)


class Addon(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        bpy.ops.preferences.addon_install(filepath=ADDON_ZIP, overwrite=True)
        bpy.ops.preferences.addon_enable(module='skinstream_live')
        import skinstream_live.live
        cls.live = skinstream_live.live
        cls.scene = bpy.context.scene
        os.makedirs(SCRATCH, exist_ok=True)

    def tearDown(self):
        bpy.ops.skinstream.disconnect()

    def pump(self, until, seconds=90):
        """Runs the add-on's timer as Blender would, until `until()` or the time is up."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.assertEqual(self.live.apply_newest_frame(), self.live.TICK_SECONDS)
            if until():
                return True
            time.sleep(0.004)
        return False

    def connect(self, port, encoding):
        settings = self.scene.skinstream
        settings.port, settings.encoding = port, encoding
        bpy.ops.skinstream.connect()
        self.assertTrue(bpy.app.timers.is_registered(self.live.apply_newest_frame))

    def test_uses_the_package_it_carries(self):
        self.assertIn(os.path.join('skinstream_live', 'skinstream'), self.live.skinstream.__file__)

    def test_the_body_takes_the_daemons_vertices(self):
        for encoding in ('parameters', 'compressed'):
            with self.subTest(encoding), demo_daemon() as daemon:
                reference = FloatFrames(daemon.sub_port)
                try:
                    self.scene.skinstream.show_markers = True
                    self.connect(daemon.sub_port, encoding)
                    start = self.live.frames_applied()
                    self.assertTrue(self.pump(lambda: self.live.frames_applied() >= start + 10), self.live.status_lines())
                    body = self.live.body_object()
                    number = body['skinstream_frame']
                    decoder = self.live._connection.receiver.decoder
                    self.assertIn(f'(decoded by {decoder})', self.live.status_lines()[0])
                    shown = vertices_of(body.data)
                    markers = bpy.data.objects[self.live._connection.markers]
                    shown_markers = vertices_of(markers.data)  # of the same frame: pumping on applies later ones
                    self.assertTrue(self.pump(lambda: number in reference.frames, 30), f'frame {number} not seen by the float subscriber')
                finally:
                    reference.stop()
                truth = reference.frames[number]
                self.assertEqual(len(body.data.polygons), len(truth.mesh.faces))
                self.assertEqual(shown.shape, truth.vertices.shape)
                worst = np.abs(shown.astype(np.float64) - truth.vertices).max()
                print(f'{encoding} by {decoder}: frame {number}, largest difference from the daemon {worst:.4g} mm')
                self.assertLessEqual(worst, 0.1)
                if encoding == 'parameters' and os.path.exists(CLIENT_LIBRARY):
                    self.assertEqual((decoder, worst), ('libskinstream_client', 0.0))
                if encoding == 'compressed' and self.live.skinstream.meshoptimizer_library.find_meshoptimizer()[0]:
                    self.assertEqual(decoder, 'libmeshoptimizer')
                self.assertAlmostEqual(body.scale[0], 0.001)
                self.assertEqual(markers.instance_type, 'VERTS')
                self.assertEqual(len(markers.data.vertices), len(truth.mesh.marker_names))
                np.testing.assert_array_equal(shown_markers, truth.markers)
                bpy.ops.skinstream.disconnect()

    def test_the_body_carries_on_across_a_swapped_subject(self):
        first, second = swap_subjects()
        with swap_daemon(first) as daemon:
            reference = FloatFrames(daemon.sub_port)
            try:
                self.scene.skinstream.show_markers = True
                self.connect(daemon.sub_port, 'parameters')
                self.assertTrue(self.pump(lambda: self.live.frames_applied() >= 10), self.live.status_lines())
                connection = self.live._connection
                body, old_info, old_model = self.live.body_object(), connection.mesh_info, connection.receiver.model
                before = vertices_of(body.data)
                reference_before = reference.mesh()
                swapped = swap_subject_file(daemon.http_port, second, wait=lambda seconds: self.pump(lambda: False, seconds))
                self.assertEqual((swapped['change']['state'], swapped['file']), ('done', second), swapped)
                applied = self.live.frames_applied()
                # Built again from the new subject's MeshInfo, then its frames, 30 of them.
                self.assertTrue(self.pump(lambda: connection.mesh_info is not old_info and
                                          self.live.frames_applied() >= applied + 30), self.live.status_lines())
                body_after = self.live.body_object()
                number = body_after['skinstream_frame']
                shown = vertices_of(body_after.data)
                status = self.live.status_lines()
                self.assertTrue(self.pump(lambda: number in reference.frames and reference.frames[number].mesh is not reference_before,
                                          30), f'frame {number} of the new subject not seen by the float subscriber')
            finally:
                reference.stop()
            self.assertEqual(daemon.stop(), 0, daemon.log())
        new_info = connection.mesh_info
        self.assertIs(self.live._connection, connection)
        self.assertEqual((connection.receiver.connections, connection.receiver.meshes_received), (1, 2))  # never reconnected
        self.assertEqual(connection.problem, '')
        self.assertIn('streaming "body"', status[0])
        # The same object, its mesh built again for the new subject and still moving.
        self.assertEqual(body_after.name, body.name)
        self.assertEqual(body_after['skinstream_subject'], 'body')
        self.assertFalse(np.array_equal(new_info.marker_triangles, old_info.marker_triangles))
        self.assertIsNot(connection.receiver.model, old_model)
        self.assertEqual(shown.shape, before.shape)
        self.assertGreater(np.abs(shown - before).max(), 1.0)
        # What it shows is the daemon's: the new subject's vertices of that frame.
        truth = reference.frames[number]
        worst = np.abs(shown.astype(np.float64) - truth.vertices).max()
        print(f'across the swap: frame {number} within {worst:.4g} mm of the daemon\'s vertices')
        self.assertLessEqual(worst, 0.1)

    def test_a_stalled_or_vanished_daemon_is_shown_and_never_holds_blender_up(self):
        daemon = demo_daemon()
        port = daemon.sub_port
        try:
            self.connect(port, 'compressed')
            self.assertTrue(self.pump(lambda: self.live.frames_applied() >= 3))
            daemon.pause()  # the connection stays open, nothing comes
            time.sleep(0.3)
            self.live.apply_newest_frame()
            applied = self.live.frames_applied()
            for _ in range(200):  # each call returns at once: a blocking read would hang here
                self.live.apply_newest_frame()
            self.assertEqual(self.live.frames_applied(), applied)
            daemon.resume()
            daemon.stop()
            self.assertTrue(self.pump(lambda: 'retrying in' in self.live.status_lines()[0], 30), self.live.status_lines())
            self.assertIn(f'127.0.0.1:{port}', self.live.status_lines()[0])
            with demo_daemon(port=port):
                self.assertTrue(self.pump(lambda: self.live.frames_applied() > applied + 3), self.live.status_lines())
                self.assertIn('streaming', self.live.status_lines()[0])
        finally:
            daemon.stop()

    def test_bytes_that_break_the_protocol_are_shown_in_one_line(self):
        listener = socket.create_server(('127.0.0.1', 0))
        stop = threading.Event()

        def serve():  # every connection: a MeshInfo with another magic, then closed
            listener.settimeout(0.1)
            while not stop.is_set():
                try:
                    peer, _ = listener.accept()
                except socket.timeout:
                    continue
                with peer:
                    peer.recv(1024)
                    peer.sendall(b'XKSF' + bytes(8))

        thread = threading.Thread(target=serve)
        thread.start()
        try:
            self.connect(listener.getsockname()[1], 'compressed')
            self.assertTrue(self.pump(lambda: 'bad magic' in self.live.status_lines()[0], 30), self.live.status_lines())
            self.assertRegex(self.live.status_lines()[0], r'^127\.0\.0\.1:\d+: bad magic \(not a skinstream subscriber stream\); retrying in')
            self.assertEqual(self.live.frames_applied(), 0)
        finally:
            stop.set()
            thread.join()
            listener.close()

    def test_a_recording_plays_back_through_the_mesh_cache_modifier(self):
        path = os.path.join(SCRATCH, 'addon_recording.pc2')
        settings = self.scene.skinstream
        settings.record_path = path
        self.scene.frame_set(7)
        with demo_daemon() as daemon:
            reference = FloatFrames(daemon.sub_port)
            try:
                self.connect(daemon.sub_port, 'quantised')
                self.assertTrue(self.pump(lambda: self.live.can_record()))
                self.assertEqual(bpy.ops.skinstream.start_recording(), {'FINISHED'})
                self.assertTrue(self.pump(lambda: self.live.recording()[1] >= 12))
                self.assertEqual(bpy.ops.skinstream.stop_recording(), {'FINISHED'})
            finally:
                reference.stop()
        samples = read_pc2(path)
        self.assertGreaterEqual(len(samples), 12)
        # What was recorded is what the daemon sent (quantised: within half a step).
        for sample in samples[2:4]:
            closest = min(np.abs(sample - f.vertices).max() for f in reference.frames.values())
            self.assertLessEqual(closest, 0.02)
        playback = bpy.data.objects[self.live.RECORDING]
        cache = playback.modifiers[0]
        self.assertEqual((cache.type, cache.cache_format, bpy.path.abspath(cache.filepath)), ('MESH_CACHE', 'PC2', path))
        for k in (0, 5, len(samples) - 1):  # sample k at the scene frame where recording began, plus k
            self.scene.frame_set(7 + k)
            evaluated = playback.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
            np.testing.assert_allclose(vertices_of(evaluated), samples[k], atol=1e-4, err_msg=f'sample {k}')

    def test_skinstream_deform_pc2_plays_through_the_mesh_cache_modifier(self):
        out = os.path.join(SCRATCH, 'deform_pc2')
        subprocess.run([SKINSTREAM_CLI, 'deform', '--subject', os.path.join(DEMO, 'subject.sksubj'), '--capture',
                        os.path.join(DEMO, 'live.c3d'), '--fill', '--format', 'pc2', '--out', out], check=True,
                       stdout=subprocess.DEVNULL)
        samples = read_pc2(os.path.join(out, 'deformed.pc2'))
        vertices, faces = [], []
        with open(os.path.join(out, 'rest.obj')) as obj:
            for line in obj:
                if line.startswith('v '):
                    vertices.append(line.split()[1:4])
                elif line.startswith('f '):
                    faces.append([int(c.split('/')[0]) - 1 for c in line.split()[1:]])
        mesh = bpy.data.meshes.new('deformed')
        mesh.from_pydata(np.array(vertices, np.float32).tolist(), [], faces)
        self.assertEqual(len(mesh.vertices), samples.shape[1])
        body = bpy.data.objects.new('deformed', mesh)
        self.scene.collection.objects.link(body)
        cache = body.modifiers.new('deform', 'MESH_CACHE')
        cache.cache_format, cache.filepath, cache.frame_start = 'PC2', os.path.join(out, 'deformed.pc2'), 1
        self.assertGreater(np.abs(samples[-1] - samples[0]).max(), 100)  # the body moves
        for k in (0, 1, 120, len(samples) - 1):
            self.scene.frame_set(1 + k)
            evaluated = body.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
            np.testing.assert_allclose(vertices_of(evaluated), samples[k], atol=1e-4, err_msg=f'sample {k}')


if __name__ == '__main__':
    result = unittest.main(argv=[sys.argv[0]], exit=False, verbosity=2).result
    sys.exit(0 if result.wasSuccessful() else 1)
