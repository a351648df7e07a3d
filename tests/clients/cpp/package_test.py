"""The C++ client library as a user gets it: `cmake --install` into a scratch prefix, the
top-level examples/ configured and built out of tree against it with find_package, and the
example run against the real skinstreamd replaying the demo subject: vertex 0 of each frame
agrees across encodings (float as the reference), and the example rides out the daemon going
away and coming back.

Usage: package_test.py BUILD_DIR SOURCE_DIR SKINSTREAMD DEMO_DIR SCRATCH_DIR"""
import os
import re
import shutil
import subprocess
import sys
import threading
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support.daemon_process import DaemonProcess  # noqa: E402

BUILD, SOURCE, SKINSTREAMD, DEMO, SCRATCH = sys.argv[1:6]
LINE = re.compile(r'^frame (\d+) vertex 0: (\S+) (\S+) (\S+) mm \((\w+)\)$')


def daemon(port=0):
    return DaemonProcess(SKINSTREAMD, '--subject', os.path.join(DEMO, 'subject.sksubj'), '--replay',
                         os.path.join(DEMO, 'live.c3d'), '--loop', '--speed', '0.2', scratch=SCRATCH, sub_port=port)


class Example:
    """The example program running, its stdout lines and stderr collected as they come."""

    def __init__(self, program, port, encoding, frames):
        self.process = subprocess.Popen([program, '127.0.0.1', str(port), encoding, str(frames)], stdout=subprocess.PIPE,
                                        stderr=subprocess.PIPE, text=True)
        self.lines, self.errors = [], []
        self._threads = [threading.Thread(target=self._collect, args=(s, out)) for s, out in
                         ((self.process.stdout, self.lines), (self.process.stderr, self.errors))]
        for t in self._threads:
            t.start()

    @staticmethod
    def _collect(stream, out):
        for line in stream:
            out.append(line.rstrip('\n'))

    def wait_for(self, what, count, seconds=120):
        deadline = time.monotonic() + seconds
        while len(what) < count and time.monotonic() < deadline and self.process.poll() is None:
            time.sleep(0.05)
        return len(what) >= count

    def finish(self, seconds=180):
        try:
            code = self.process.wait(seconds)
        except subprocess.TimeoutExpired:
            self.process.kill()
            code = self.process.wait()
        for t in self._threads:
            t.join()
        return code

    def vertices(self):
        found = {}
        for line in self.lines:
            m = LINE.match(line)
            assert m, f'unexpected output line: {line!r}'
            found[int(m.group(1))] = (tuple(float(m.group(i)) for i in (2, 3, 4)), m.group(5))
        return found


class InstalledPackage(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        shutil.rmtree(SCRATCH, ignore_errors=True)
        os.makedirs(SCRATCH)
        cls.prefix = os.path.join(SCRATCH, 'prefix')
        subprocess.run(['cmake', '--install', BUILD, '--prefix', cls.prefix], check=True, stdout=subprocess.DEVNULL)
        example_build = os.path.join(SCRATCH, 'example-build')
        configure = subprocess.run(['cmake', '-S', os.path.join(SOURCE, 'examples'), '-B', example_build, '-G', 'Ninja',
                                    '-DCMAKE_BUILD_TYPE=Release', f'-DCMAKE_PREFIX_PATH={cls.prefix}'],
                                   capture_output=True, text=True)
        assert configure.returncode == 0, configure.stdout + configure.stderr
        cls.configure_output = configure.stdout
        build = subprocess.run(['cmake', '--build', example_build], capture_output=True, text=True)
        assert build.returncode == 0, build.stdout + build.stderr
        cls.program = os.path.join(example_build, 'first_vertex')

    def test_installs_the_public_header_the_library_and_the_package(self):
        installed = sorted(os.path.relpath(os.path.join(d, f), self.prefix) for d, _, files in os.walk(self.prefix) for f in files)
        headers = [f for f in installed if f.startswith('include/')]
        # The codecs and the evaluator stay inside; the evaluator is open through its C ABI.
        self.assertEqual(headers, ['include/skinstream/client.h', 'include/skinstream/evaluator_c.h'])
        self.assertIn('lib/libskinstream_client.so.0', installed)
        exported = subprocess.run(['nm', '-D', '--defined-only', os.path.join(self.prefix, 'lib', 'libskinstream_client.so.0')],
                                  capture_output=True, text=True, check=True).stdout
        c_functions = sorted(set(re.findall(r' T (skinstream_evaluator_\w+)', exported)))
        self.assertEqual(c_functions, ['skinstream_evaluator_abi_version', 'skinstream_evaluator_create', 'skinstream_evaluator_destroy',
                                       'skinstream_evaluator_evaluate', 'skinstream_evaluator_vertex_count'])
        self.assertIn('lib/cmake/skinstream_client/skinstream_clientConfig.cmake', installed)
        self.assertIn('lib/cmake/skinstream_client/skinstream_clientConfigVersion.cmake', installed)
        # Found in the prefix, not in the build tree.
        self.assertIn(f'from {self.prefix}/lib/cmake/skinstream_client', self.configure_output)
        self.assertRegex(self.configure_output, r"built for CPU level '(x86-64-v\d)?'")

    def test_every_encoding_prints_the_daemons_vertex_zero(self):
        with daemon() as d:
            runs = {e: Example(self.program, d.sub_port, e, 25) for e in ('float', 'compressed', 'parameters')}
            codes = {e: run.finish() for e, run in runs.items()}
        for encoding, code in codes.items():
            self.assertEqual(code, 0, runs[encoding].errors)
        found = {e: run.vertices() for e, run in runs.items()}
        reference = found['float']
        self.assertEqual(len(reference), 25)
        # Tolerances: parameters evaluated as the daemon does (0.01 mm), compressed within half
        # a step of the key's grid (0.025 mm); the printed 4 decimals add 0.0001 mm.
        for encoding, tolerance in (('compressed', 0.025), ('parameters', 0.01)):
            common = sorted(set(reference) & set(found[encoding]))
            self.assertGreaterEqual(len(common), 10, encoding)
            for number in common:
                vertex, served = found[encoding][number]
                self.assertEqual(served, encoding)
                for a, b in zip(vertex, reference[number][0]):
                    self.assertAlmostEqual(a, b, delta=tolerance + 1e-4, msg=f'{encoding} frame {number}')
        # The subject moves: vertex 0 is not the same in every frame.
        self.assertGreater(len({v for v, _ in reference.values()}), 5)

    def test_rides_out_the_daemon_going_away_and_coming_back(self):
        first = daemon()
        port = first.sub_port
        run = Example(self.program, port, 'compressed', 30)
        try:
            self.assertTrue(run.wait_for(run.lines, 5), run.errors)
            first.stop()
            self.assertTrue(run.wait_for(run.errors, 2, 30), 'no error line while the daemon was away')
            with daemon(port):
                self.assertEqual(run.finish(), 0, run.errors)
        finally:
            first.stop()
            if run.process.poll() is None:
                run.process.kill()
        self.assertEqual(len(run.lines), 30)
        run.vertices()  # every line is a vertex line (the replay restarts, so frame numbers repeat)
        for line in run.errors:  # one line each, naming the daemon and the wait
            self.assertRegex(line, r'^127\.0\.0\.1:\d+: .*; retrying in \d+ ms$')


if __name__ == '__main__':
    unittest.main(argv=sys.argv[:1], verbosity=2)
