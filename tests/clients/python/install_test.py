"""`pip install ./clients/python` as CI does it on a clean Debian 12, without the network: a
virtual environment that sees Debian's numpy, setuptools and wheel, pip told to build without
isolation and fetch nothing; then the installed package (not the source tree) imports, decodes
a message and finds the C++ client library by SKINSTREAM_CLIENT_LIBRARY."""
import os
import shutil
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support.python_clients import CLIENT_LIBRARY, FIXTURES, SCRATCH, SOURCE  # noqa: E402


class PipInstall(unittest.TestCase):
    def test_installs_offline_and_imports_from_site_packages(self):
        root = os.path.join(SCRATCH, 'pip_install')
        shutil.rmtree(root, ignore_errors=True)
        # A copy, so that the build leaves nothing in the source tree.
        package = os.path.join(root, 'package')
        shutil.copytree(os.path.join(SOURCE, 'clients', 'python'), package,
                        ignore=shutil.ignore_patterns('build', '*.egg-info', '__pycache__'))
        venv = os.path.join(root, 'venv')
        subprocess.run([sys.executable, '-m', 'venv', '--system-site-packages', venv], check=True)
        python = os.path.join(venv, 'bin', 'python')
        install = subprocess.run([python, '-m', 'pip', 'install', '--no-index', '--no-build-isolation', '--no-deps', package],
                                 capture_output=True, text=True)
        self.assertEqual(install.returncode, 0, install.stdout + install.stderr)
        self.assertIn('Successfully installed skinstream-0.1.0', install.stdout)
        script = ('import skinstream, sys; from skinstream import protocol as wire; '
                  f'data = open({os.path.join(FIXTURES, "mesh_info_v2.bin")!r}, "rb").read(); '
                  'info = wire.MeshInfo(data[12:], 2); print(skinstream.__file__); print(info.subject, info.marker_names); '
                  "print(skinstream.decoders()['parameters'])")
        run = subprocess.run([python, '-c', script], capture_output=True, text=True, cwd=root)
        self.assertEqual(run.returncode, 0, run.stderr)
        where, decoded, parameters = run.stdout.splitlines()
        self.assertTrue(where.startswith(os.path.join(venv, 'lib')), where)
        self.assertEqual(decoded, "Actor2 ['LSHO', 'RSHO', 'C7']")
        if os.path.exists(CLIENT_LIBRARY):  # built (the environment names it for the child too)
            self.assertEqual(parameters, f'libskinstream_client ({CLIENT_LIBRARY})')


if __name__ == '__main__':
    unittest.main(verbosity=2)
