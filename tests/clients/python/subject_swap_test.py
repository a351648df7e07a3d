"""The package's Subscriber and Receiver carry on across a subject swapped at run time: the real
skinstreamd serves one subject file, the control API (POST /subjects/NAME/file) swaps in another
(tests/support/make_swap_subjects.sh built both, from two CMU takes), and the subscribers that
were connected all along take the new MeshInfo (and, for the parameters, the new Model) and then
the new subject's frames, rejecting none and never reconnecting."""
import os
import sys
import threading
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support.python_clients import SWAP_SUBJECT, swap_daemon, swap_subject_file, swap_subjects, wait_until  # noqa: E402
import numpy as np  # noqa: E402
import skinstream  # noqa: E402

NAME = SWAP_SUBJECT


class Collector:
    """A Subscriber on a thread: every frame it returns, with the MeshInfo and Model it had then."""

    def __init__(self, port, encoding):
        self.frames = []  # (frame, model)
        self.error = None
        self._stop = threading.Event()
        self.subscriber = skinstream.Subscriber(port=port, encoding=encoding, normals=False, markers=True)
        self._thread = threading.Thread(target=self._run)
        self._thread.start()

    def _run(self):
        try:
            while not self._stop.is_set():
                frame = self.subscriber.next_frame(0.2)
                if frame is not None:
                    self.frames.append((frame, self.subscriber.model))
        except skinstream.Error as e:  # the test fails on it: a swap must not end the subscription
            self.error = e

    def count(self, mesh=None):
        return sum(1 for frame, _ in self.frames if mesh is None or frame.mesh is mesh)

    def stop(self):
        self._stop.set()
        self._thread.join()
        self.subscriber.close()


class SubjectSwap(unittest.TestCase):
    def test_subscribers_carry_on_across_a_swap_to_another_subject_file(self):
        first, second = swap_subjects()
        with swap_daemon(first) as daemon:
            collectors = {encoding: Collector(daemon.sub_port, encoding) for encoding in ('parameters', 'float')}
            receiver = skinstream.Receiver(port=daemon.sub_port, encoding='parameters', normals=False)
            receiver.start()
            try:
                for encoding, c in collectors.items():
                    self.assertTrue(wait_until(lambda: c.count() >= 10), f'{encoding}: {c.count()} frames, {c.error}')
                self.assertTrue(wait_until(lambda: receiver.frames_received >= 10), receiver.describe())
                before = {encoding: c.subscriber.mesh for encoding, c in collectors.items()}
                model_before = collectors['parameters'].subscriber.model
                receiver_mesh, receiver_model = receiver.mesh, receiver.model
                swapped = swap_subject_file(daemon.http_port, second)
                self.assertEqual(swapped['change']['state'], 'done', swapped)
                self.assertEqual(swapped['file'], second)
                # The same subscriptions take the new subject's frames: 30 each at least.
                for encoding, c in collectors.items():
                    self.assertTrue(wait_until(lambda: c.subscriber.mesh is not before[encoding] and
                                               c.count(c.subscriber.mesh) >= 30), f'{encoding}: {c.count()} frames, {c.error}')
                received = receiver.frames_received
                self.assertTrue(wait_until(lambda: receiver.mesh is not receiver_mesh and receiver.frames_received >= received + 30),
                                receiver.describe())
                newest = receiver.take()
            finally:
                receiver.stop()
                for c in collectors.values():
                    c.stop()
            self.assertEqual(daemon.stop(), 0, daemon.log())

        for encoding, c in collectors.items():
            with self.subTest(encoding):
                sub = c.subscriber
                self.assertIsNone(c.error, encoding)
                self.assertEqual((sub.frames_rejected, sub.last_rejection), (0, ''))
                old, new = before[encoding], sub.mesh
                self.assertEqual((old.subject, new.subject), (NAME, NAME))
                self.assertEqual(new.encoding, old.encoding)
                # Another subject: the same body mesh and markers, the marker surface of another take.
                self.assertEqual(new.vertex_count, old.vertex_count)
                self.assertEqual(new.marker_names, old.marker_names)
                self.assertFalse(np.array_equal(new.marker_triangles, old.marker_triangles), 'the same marker surface after the swap')
                meshes = [frame.mesh for frame, _ in c.frames]
                # The old subject's frames, then the new one's; nothing of the old after the first new.
                switch = meshes.index(new)
                self.assertGreaterEqual(switch, 10)
                self.assertTrue(all(m is old for m in meshes[:switch]), 'a third MeshInfo')
                self.assertTrue(all(m is new for m in meshes[switch:]), 'a frame of the old subject after the new one')
                numbers = [frame.frame_number for frame, _ in c.frames]
                print(f'{encoding}: {switch} frames of the first subject, {len(meshes) - switch} of the second '
                      f'(frames {numbers[switch - 1]} then {numbers[switch]})')
                # The new subject's frames are its own: vertices of the new mesh, and they move.
                after = [frame for frame, _ in c.frames[switch:]]
                for frame in after:
                    self.assertEqual(frame.vertices.shape, (new.vertex_count, 3))
                    self.assertTrue(np.isfinite(frame.vertices).all())
                self.assertGreater(np.abs(after[-1].vertices - after[0].vertices).max(), 1.0)
                if encoding == 'parameters':
                    model = sub.model
                    self.assertIsNot(model, model_before)
                    self.assertTrue(all(m is model for _, m in c.frames[switch:]), 'a frame evaluated with the old Model')
                    self.assertTrue(all(m is model_before for _, m in c.frames[:switch]))
                    self.assertEqual(model.vertex_count, new.vertex_count)
                    # Another fit: another reference pose and other parts.
                    self.assertGreater(np.abs(model.reference - model_before.reference).max(), 1.0)
                    # Evaluated with the new Model, a frame sits where the new subject puts it:
                    # near the float subscriber's frame of the same number (the daemon's own).
                    # A looped replay repeats frame numbers: the daemon's receive time tells them apart.
                    floats = {(f.frame_number, f.receive_time_ns): f for f, _ in collectors['float'].frames
                              if f.mesh is not before['float']}
                    common = [f for f in after if (f.frame_number, f.receive_time_ns) in floats]
                    self.assertGreater(len(common), 0, 'no frame of the new subject in common with the float subscriber')
                    worst = max(np.abs(f.vertices - floats[f.frame_number, f.receive_time_ns].vertices).max() for f in common)
                    print(f'parameters after the swap: {len(common)} frames within {worst:.3g} mm of the float subscriber')
                    self.assertLess(worst, 0.01)

        # The Receiver (the Blender add-on's) hands over the new subject's frames.
        self.assertIsNot(receiver.mesh, receiver_mesh)
        self.assertIsNot(receiver.model, receiver_model)
        self.assertEqual(receiver.model.vertex_count, receiver.mesh.vertex_count)
        self.assertIsNotNone(newest)
        self.assertIs(newest.mesh, receiver.mesh)
        self.assertEqual((receiver.connections, receiver.meshes_received), (1, 2))
        self.assertEqual(newest.vertices.shape, (receiver.mesh.vertex_count, 3))


if __name__ == '__main__':
    unittest.main(verbosity=2)
