"""The real skinstreamd in the background for the Python-driven tests (as support/daemon_process.h
does for the C++ ones): ephemeral loopback ports read back from its ports file, stopped with
SIGTERM."""
import json
import os
import signal
import subprocess
import tempfile
import time


class DaemonProcess:
    def __init__(self, skinstreamd, *arguments, scratch=None, sub_port=0):
        self.scratch = scratch or tempfile.mkdtemp(prefix='skinstreamd_')
        os.makedirs(self.scratch, exist_ok=True)
        self.ports_path = os.path.join(self.scratch, f'ports_{os.getpid()}_{id(self)}.json')
        self.log_path = self.ports_path + '.log'
        if os.path.exists(self.ports_path):
            os.remove(self.ports_path)
        command = [skinstreamd, '--bind', '127.0.0.1', '--http-port', '0', '--sub-port', str(sub_port), '--ports-file',
                   self.ports_path, *arguments]
        with open(self.log_path, 'wb') as log:
            self.process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 60
        ports = None
        while ports is None:
            if self.process.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f'skinstreamd did not start: {self.log()}')
            time.sleep(0.02)
            try:
                with open(self.ports_path) as f:
                    ports = json.load(f)
            except (FileNotFoundError, json.JSONDecodeError):  # not there yet, or not written whole yet
                pass
        self.sub_port, self.http_port = ports['sub'], ports['http']

    def log(self):
        with open(self.log_path, errors='replace') as f:
            return f.read()

    def pause(self):
        """SIGSTOP: a daemon that stalls with its connections open."""
        self.process.send_signal(signal.SIGSTOP)

    def resume(self):
        self.process.send_signal(signal.SIGCONT)

    def stop(self):
        """Its exit code."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGCONT)
            self.process.terminate()
            try:
                self.process.wait(30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        return self.process.returncode

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()
