"""What the Python-driven client tests share: the package from the source tree on sys.path, and
the programs, demo subject, scratch folder and C++ client library ctest hands them in the
environment (by hand: the build tree's)."""
import os
import sys
import time

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


def wait_until(condition, seconds=60):
    """Polls `condition` every 20 ms: True once it holds, False after `seconds`."""
    deadline = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.02)
    return True


def demo_daemon(*extra, port=0, speed='0.2'):
    """skinstreamd replaying the demo subject's take in a loop (a fifth of real time by default,
    so that every subscriber of a test takes every frame on a shared machine)."""
    from support.daemon_process import DaemonProcess
    return DaemonProcess(SKINSTREAMD, '--subject', os.path.join(DEMO, 'subject.sksubj'), '--replay',
                         os.path.join(DEMO, 'live.c3d'), '--loop', '--speed', speed, *extra, scratch=SCRATCH, sub_port=port)


def fixture(name):
    with open(os.path.join(FIXTURES, name), 'rb') as f:
        return f.read()


def swap_subjects():
    """(first, second): two subject files of one body fitted to two takes, for a swap at run time
    (the ctest fixture swap_subjects, tests/support/make_swap_subjects.sh; by hand: built here
    when missing)."""
    folder = os.environ.get('SKINSTREAM_SWAP_SUBJECTS_DIR', os.path.join(SOURCE, 'build', 'test_tmp', 'swap_subjects'))
    paths = tuple(os.path.join(folder, f'{name}.sksubj') for name in ('first', 'second'))
    if not all(os.path.exists(path) for path in paths):
        import subprocess
        subprocess.run(['bash', os.path.join(TESTS, 'support', 'make_swap_subjects.sh'), SKINSTREAM_CLI, folder], check=True)
    return paths


SWAP_SUBJECT = 'body'  # the subject's name in swap_daemon
SWAP_TOKEN = 'swap-test-token-0123456789'


def swap_daemon(first):
    """skinstreamd serving the subject file `first` as SWAP_SUBJECT from a loop of CMU 85_02 at
    half speed, with the control API on (the token SWAP_TOKEN)."""
    from support.daemon_process import DaemonProcess
    os.makedirs(SCRATCH, exist_ok=True)
    token_file = os.path.join(SCRATCH, f'swap_token_{os.getpid()}')
    with open(token_file, 'w') as f:
        f.write(SWAP_TOKEN + '\n')
    os.chmod(token_file, 0o600)
    return DaemonProcess(SKINSTREAMD, '--subject', f'{SWAP_SUBJECT}={first}', '--replay',
                         os.path.join(SOURCE, 'replay_data', 'cmu', '85_02.c3d'), '--replay-subject', SWAP_SUBJECT, '--loop',
                         '--speed', '0.5', '--control-token-file', token_file, scratch=SCRATCH)


def swap_subject_file(http_port, path, seconds=60, wait=None):
    """POST /subjects/SWAP_SUBJECT/file {"file": path}, then GET /subjects/SWAP_SUBJECT until the
    change is done or failed: that answer. `wait(seconds)` waits between two GETs (time.sleep by
    default; Blender's test runs the add-on's timer meanwhile)."""
    import json
    import time
    import urllib.error
    import urllib.request

    def control(method, route, body=None):
        request = urllib.request.Request(f'http://127.0.0.1:{http_port}{route}', method=method,
                                         data=None if body is None else json.dumps(body).encode(),
                                         headers={'Authorization': f'Bearer {SWAP_TOKEN}', 'Content-Type': 'application/json'})
        try:
            with urllib.request.urlopen(request, timeout=10) as answer:
                return json.loads(answer.read())
        except urllib.error.HTTPError as e:
            raise AssertionError(f'{method} {route}: {e.code} {e.read().decode(errors="replace")}') from None

    control('POST', f'/subjects/{SWAP_SUBJECT}/file', {'file': path})
    deadline = time.monotonic() + seconds
    while True:
        subject = control('GET', f'/subjects/{SWAP_SUBJECT}')
        if subject['change']['state'] in ('done', 'failed'):
            return subject
        if time.monotonic() > deadline:
            raise AssertionError(f'the swap to {path} did not finish within {seconds} s: {subject}')
        (wait or time.sleep)(0.05)
