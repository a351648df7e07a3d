#!/usr/bin/env python3
"""The Python package's decoding time per frame, per encoding and decoder, on the demo subject:
a real skinstreamd replays the demo take, one subscriber per (encoding, decoder) in turn takes
FRAMES frames, and the time from a Frame message's last byte to its numpy arrays
(ready_time_ns - arrival_time_ns, wall clock) and the thread's CPU time for it are summarised.
Every encoding is decoded in numpy; compressed also by the system's libmeshoptimizer and
parameters by libskinstream_client when they load (the build tree's library unless
--client-library or SKINSTREAM_CLIENT_LIBRARY names another). The benchmark runs on one core
(--cpu; the daemon, started first, keeps the others). Prints one JSON object; a frame at 120 Hz
has 8.3 ms.

Usage: python3 benchmarks/python_client_benchmark.py [--daemon build/bin/skinstreamd]
           [--demo build/demo] [--client-library PATH] [--frames 60] [--normals] [--cpu 0]"""
import argparse
import json
import os
import platform
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [os.path.join(ROOT, 'clients', 'python'), os.path.join(ROOT, 'tests')]
import numpy as np  # noqa: E402
import skinstream  # noqa: E402
from skinstream.client_library import ENVIRONMENT  # noqa: E402
from support.daemon_process import DaemonProcess  # noqa: E402


class TimedSubscriber(skinstream.Subscriber):
    """Measures the CPU time of decoding each Frame message."""

    cpu_ms = None

    def _on_frame(self, payload):
        start = time.thread_time()
        frame = super()._on_frame(payload)
        if frame is not None:
            self.cpu_ms.append((time.thread_time() - start) * 1e3)
        return frame


def summary(values):
    values = np.asarray(values)
    return {'median': round(float(np.median(values)), 3), 'p90': round(float(np.percentile(values, 90)), 3),
            'max': round(float(values.max()), 3), 'count': int(len(values))}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--daemon', default=os.path.join(ROOT, 'build', 'bin', 'skinstreamd'))
    parser.add_argument('--demo', default=os.path.join(ROOT, 'build', 'demo'))
    parser.add_argument('--client-library', default=os.environ.get(ENVIRONMENT) or
                        os.path.join(ROOT, 'build', 'clients', 'cpp', 'libskinstream_client.so.0'))
    parser.add_argument('--frames', type=int, default=60)
    parser.add_argument('--normals', action='store_true', help='ask for normals too')
    parser.add_argument('--cpu', type=int, default=0, help='the one core the subscribers run on')
    args = parser.parse_args()
    os.environ[ENVIRONMENT] = args.client_library  # before the package first looks for it
    decoders = skinstream.decoders()
    result = {'vertices': None, 'normals': args.normals, 'load_average': os.getloadavg()[0], 'cpu': args.cpu,
              'python': platform.python_version(), 'numpy': np.__version__, 'decoders': decoders, 'encodings': {}}
    with DaemonProcess(args.daemon, '--subject', os.path.join(args.demo, 'subject.sksubj'), '--replay',
                       os.path.join(args.demo, 'live.c3d'), '--loop', '--speed', '0.25') as daemon:
        os.sched_setaffinity(0, {args.cpu})  # after the daemon started: it is not pinned with us
        for encoding in skinstream.ENCODINGS:
            for libraries in ((True, False) if encoding in ('compressed', 'parameters') else (True,)):
                subscriber = TimedSubscriber(port=daemon.sub_port, encoding=encoding, normals=args.normals, libraries=libraries)
                subscriber.cpu_ms = []
                wall, sizes = [], []
                while len(wall) < args.frames:
                    frame = subscriber.next_frame(5.0)
                    if frame is not None:
                        wall.append((frame.ready_time_ns - frame.arrival_time_ns) / 1e6)
                        sizes.append(frame.message_bytes)
                subscriber.close()
                result['vertices'] = subscriber.mesh.vertex_count
                name = f'{encoding} ({subscriber.decoder})'
                if name not in result['encodings']:  # without the library: numpy twice
                    result['encodings'][name] = {'decode_wall_ms': summary(wall), 'decode_cpu_ms': summary(subscriber.cpu_ms),
                                                 'frame_bytes_median': int(np.median(sizes))}
    print(json.dumps(result, indent=1))


if __name__ == '__main__':
    main()
