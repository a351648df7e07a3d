"""A subscription on a background thread for renderers with a loop of their own (Blender, a game
engine): the socket is read there, the newest frame waits in one slot (never a queue) for the
renderer to take(), and a daemon that goes away is reconnected to with backoff. It can record
every frame that arrives to a PC2 point cache, on the same thread."""
import threading
import time

from .point_cache import PointCacheWriter
from .protocol import Error
from .subscriber import Subscriber


class Receiver:
    """Receiver(host, port, encoding=..., ...): the Subscriber's options. start() begins,
    take() hands over the newest frame once, state()/detail say how the connection is."""

    def __init__(self, host='127.0.0.1', port=8481, first_retry=0.25, longest_retry=4.0, **options):
        self.host, self.port, self.options = host, port, options
        self.first_retry, self.longest_retry = first_retry, longest_retry
        self.frames_received = 0  # since start()
        self.frames_replaced = 0  # arrived and gave way to a newer one before take()
        self.connections = 0  # subscriptions that got their MeshInfo
        self.meshes_received = 0  # MeshInfos: one per connection, and one per subject swapped in by the daemon
        self.mesh = self.model = None  # of the current (or last) subscription
        self.decoder = None  # what decodes its frames (Subscriber.decoder)
        self._state, self._detail, self._retry_at = 'stopped', '', None
        self._newest = None
        self._slot = threading.Lock()
        self._record = threading.Lock()
        self._writer = None
        self._record_error = None
        self._stop = threading.Event()
        self._thread = None

    def start(self):
        if self._thread is not None:
            return
        self._stop.clear()
        self._state = 'connecting'
        self._thread = threading.Thread(target=self._run, name='skinstream-receiver', daemon=True)
        self._thread.start()

    def stop(self, timeout=5.0):
        """Stops the thread and any recording. The thread notices within a quarter of a second
        (or when a connection attempt gives up); timeout=0 does not wait for it."""
        self._stop.set()
        if self._thread is not None:
            if timeout:
                self._thread.join(timeout)
            self._thread = None
        self.stop_recording()
        self._state = 'stopped'

    def take(self):
        """The newest frame not taken yet, or None. Never waits for the network."""
        with self._slot:
            frame, self._newest = self._newest, None
        return frame

    def state(self):
        """'stopped', 'connecting', 'streaming' or 'waiting' (for the next try)."""
        return self._state

    def describe(self):
        """One line for a status bar."""
        where = f'{self.host}:{self.port}'
        if self._state == 'waiting':
            left = max(0.0, self._retry_at - time.monotonic())
            return f'{where}: {self._detail}; retrying in {left:.1f} s'
        if self._state == 'streaming' and self.mesh is not None:
            decoded = f' (decoded by {self.decoder})' if self.decoder else ''
            return f'{where}: streaming "{self.mesh.subject}", {self.frames_received} frames{decoded}'
        return f'{where}: {self._state}'

    def start_recording(self, path, start_frame=0.0):
        """Records the vertices of every frame that arrives from now on (the current mesh's)."""
        if self.mesh is None or not self.mesh.vertex_count:
            raise Error('nothing to record yet: no mesh has arrived')
        writer = PointCacheWriter(path, self.mesh.vertex_count, start_frame)
        with self._record:
            if self._writer is not None:
                self._writer.close()
            self._writer, self._record_error = writer, None

    def stop_recording(self):
        """(path, samples written, error or None) of the recording that stops, or None."""
        with self._record:
            writer, self._writer = self._writer, None
        if writer is None:
            return None
        writer.close()
        return writer.path, writer.sample_count, self._record_error

    def recording(self):
        """(path, samples so far, error or None) of the recording under way, or None."""
        writer = self._writer
        return None if writer is None else (writer.path, writer.sample_count, self._record_error)

    def _run(self):
        wait = self.first_retry
        while not self._stop.is_set():
            self._state = 'connecting'
            subscriber = None
            try:
                subscriber = Subscriber(self.host, self.port, **self.options)
                meshes_here = 0  # on this connection: after the first, subjects the daemon swapped in
                while not self._stop.is_set():
                    frame = subscriber.next_frame(0.25)
                    if subscriber.mesh is not self.mesh and subscriber.mesh is not None:
                        self.mesh, self.model = subscriber.mesh, subscriber.model
                        if meshes_here == 0:
                            self.connections += 1
                        meshes_here += 1
                        self.meshes_received += 1
                    if frame is None:
                        continue
                    self.model, self.decoder = subscriber.model, subscriber.decoder
                    self._arrived(frame)
                    self._state = 'streaming'
                    wait = self.first_retry
            except Error as e:
                where = f'{self.host}:{self.port}'
                self._detail = str(e)[len(where) + 2:] if str(e).startswith(where + ': ') else str(e)
            finally:
                if subscriber is not None:
                    subscriber.close()
            if self._stop.is_set():
                break
            self._retry_at = time.monotonic() + wait
            self._state = 'waiting'
            self._stop.wait(wait)
            wait = min(2 * wait, self.longest_retry)

    def _arrived(self, frame):
        with self._slot:
            if self._newest is not None:
                self.frames_replaced += 1
            self._newest = frame
            self.frames_received += 1  # after the slot: a count that moved means a frame to take
        with self._record:
            if self._writer is None or self._record_error is not None or frame.vertices is None:
                return
            try:
                self._writer.append(frame.vertices)
            except (OSError, ValueError) as e:  # a full disk, or a new mesh of another size: kept until stopped
                self._record_error = str(e)
