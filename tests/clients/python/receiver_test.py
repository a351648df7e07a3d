"""The background Receiver against the real daemon: only the newest frame waits (never a
queue), take() never waits for the network (not even on a daemon that stalls with its
connection open), the daemon going away and coming back on the same port is ridden out with
backoff, and what arrives can be recorded to a PC2 point cache."""
import os
import sys
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support.python_clients import SCRATCH, demo_daemon, wait_until  # noqa: E402
import numpy as np  # noqa: E402
import skinstream  # noqa: E402


class Receiver(unittest.TestCase):
    def test_newest_frame_only_and_a_stalled_daemon_never_blocks_take(self):
        with demo_daemon() as daemon:
            receiver = skinstream.Receiver(port=daemon.sub_port, encoding='compressed')
            receiver.start()
            try:
                self.assertTrue(wait_until(lambda: receiver.frames_received >= 3), receiver.describe())
                time.sleep(0.5)  # frames arrive (24 a second at this speed) and nobody takes them
                first = receiver.take()
                self.assertIsNotNone(first)
                self.assertIsNone(receiver.take())  # handed over once: no queue behind it
                self.assertGreater(receiver.frames_replaced, 0)
                count = receiver.frames_received
                self.assertTrue(wait_until(lambda: receiver.frames_received > count))
                newest = receiver.take()
                self.assertGreater(newest.frame_number, first.frame_number)
                # A daemon that stops answering with the connection open: take() goes on
                # returning at once (with nothing new), the receiver's thread waits alone.
                daemon.pause()
                time.sleep(0.3)
                receiver.take()
                for _ in range(100):
                    self.assertIsNone(receiver.take())
                self.assertEqual(receiver.state(), 'streaming')
                self.assertIn(receiver.decoder, ('libmeshoptimizer', 'numpy'))
                self.assertIn(f'(decoded by {receiver.decoder})', receiver.describe())
                daemon.resume()
                self.assertTrue(wait_until(lambda: receiver.take() is not None))
            finally:
                receiver.stop()
            self.assertEqual(receiver.state(), 'stopped')

    def test_the_daemon_going_away_and_coming_back(self):
        daemon = demo_daemon()
        port = daemon.sub_port
        # Paced: a reader slower than the stream (parameters evaluated in numpy, where the client
        # library is not found) has two frames in flight, not a socket's fill to read before it
        # sees the daemon gone.
        receiver = skinstream.Receiver(port=port, encoding='parameters', markers=True, paced=True, first_retry=0.1,
                                       longest_retry=0.8)
        receiver.start()
        try:
            self.assertTrue(wait_until(lambda: receiver.state() == 'streaming'), receiver.describe())
            self.assertTrue(wait_until(lambda: receiver.take() is not None))
            daemon.stop()
            self.assertTrue(wait_until(lambda: receiver.state() == 'waiting'), receiver.describe())
            line = receiver.describe()
            self.assertRegex(line, rf'^127\.0\.0\.1:{port}: [^;]+; retrying in \d+\.\d s$')
            time.sleep(2.0)  # several failed tries, the wait doubling up to 0.8 s
            self.assertIn('refused', receiver.describe())
            receiver.take()
            self.assertIsNone(receiver.take())
            with demo_daemon(port=port):
                self.assertTrue(wait_until(lambda: receiver.state() == 'streaming'), receiver.describe())
                frame = None
                self.assertTrue(wait_until(lambda: (frame := receiver.take()) is not None))
                self.assertEqual(receiver.connections, 2)
                self.assertEqual(receiver.model.vertex_count, 53514)
        finally:
            daemon.stop()
            receiver.stop()

    def test_records_every_frame_that_arrives_to_a_point_cache(self):
        path = os.path.join(SCRATCH, 'receiver_recording.pc2')
        os.makedirs(SCRATCH, exist_ok=True)
        taken = {}
        with demo_daemon() as daemon:
            receiver = skinstream.Receiver(port=daemon.sub_port, encoding='float', normals=False)
            receiver.start()
            try:
                self.assertTrue(wait_until(lambda: receiver.mesh is not None and receiver.frames_received > 0))
                with self.assertRaises(skinstream.Error):
                    skinstream.Receiver().start_recording(path)  # no mesh yet: nothing to record
                receiver.start_recording(path)
                before = receiver.frames_received
                while receiver.frames_received < before + 12:
                    frame = receiver.take()
                    if frame is not None:
                        taken[frame.frame_number] = frame.vertices.copy()
                    time.sleep(0.01)
                path_written, samples, error = receiver.stop_recording()
            finally:
                receiver.stop()
        self.assertIsNone(error)
        self.assertEqual(path_written, path)
        self.assertGreaterEqual(samples, 12)
        _, _, recorded = skinstream.read_point_cache(path)
        self.assertEqual(recorded.shape, (samples, 53514, 3))
        # Every frame taken while recording is one of the samples, exactly.
        matched = 0
        for vertices in taken.values():
            matched += any(np.array_equal(vertices, sample) for sample in recorded)
        self.assertGreaterEqual(matched, len(taken) - 1)  # the first taken may predate the recording
        self.assertGreater(matched, 0)


if __name__ == '__main__':
    unittest.main(verbosity=2)
