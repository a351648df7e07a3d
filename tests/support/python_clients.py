"""What the Python-driven client tests share: the package from the source tree on sys.path, and
the programs, demo subject, scratch folder and C++ client library ctest hands them in the
environment (by hand: the build tree's)."""
import os
import sys

TESTS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOURCE = os.path.dirname(TESTS)
sys.path.insert(0, os.path.join(SOURCE, 'clients', 'python'))

SKINSTREAMD = os.environ.get('SKINSTREAMD', os.path.join(SOURCE, 'build', 'bin', 'skinstreamd'))
SKINSTREAM_CLI = os.environ.get('SKINSTREAM_CLI', os.path.join(SOURCE, 'build', 'bin', 'skinstream'))
DEMO = os.environ.get('SKINSTREAM_DEMO_DIR', os.path.join(SOURCE, 'build', 'demo'))
SCRATCH = os.environ.get('SKINSTREAM_TEST_TMP_DIR', os.path.join(SOURCE, 'build', 'test_tmp', 'python'))
FIXTURES = os.path.join(TESTS, 'protocol', 'fixtures', 'subscriber')
# The package finds libskinstream_client by this variable (skinstream/client_library.py).
CLIENT_LIBRARY = os.environ.setdefault('SKINSTREAM_CLIENT_LIBRARY',
                                       os.path.join(SOURCE, 'build', 'clients', 'cpp', 'libskinstream_client.so.0'))


def demo_daemon(*extra, port=0, speed='0.2'):
    """skinstreamd replaying the demo subject's take in a loop (a fifth of real time by default,
    so that every subscriber of a test takes every frame on a shared machine)."""
    from support.daemon_process import DaemonProcess
    return DaemonProcess(SKINSTREAMD, '--subject', os.path.join(DEMO, 'subject.sksubj'), '--replay',
                         os.path.join(DEMO, 'live.c3d'), '--loop', '--speed', speed, *extra, scratch=SCRATCH, sub_port=port)


def fixture(name):
    with open(os.path.join(FIXTURES, name), 'rb') as f:
        return f.read()
