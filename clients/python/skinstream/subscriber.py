"""One subscription to a skinstreamd over TCP: Hello, then MeshInfo (and the Model for the
parameter encoding), then Frames decoded into numpy arrays, read on the calling thread."""
import logging
import socket
import struct
import time

import numpy as np

from . import protocol as wire
from .decoder_choice import compressed_decoder, parameter_evaluator
from .protocol import Error, ProtocolError

_log = logging.getLogger('skinstream')


class ConnectionLost(Error):
    """The daemon could not be reached, or closed the connection."""


class Refused(Error):
    """The daemon refused this subscriber (unknown subject, wrong token); it says why."""


class Frame:
    """One frame. Arrays are the subscriber's to keep: later frames do not overwrite them.

    vertices: V x 3 float32, mm (None: markers only, or parameters not evaluated)
    normals: V x 3 float32 unit vectors (None when not asked for)
    markers: M x 3 float32, mm, subject order; marker_status: M uint8 (protocol.MARKER_STATUS)
    parameters: the raw parameters block (parameter encoding), for renderers that evaluate it
    themselves; times in ns: source_time_ns (capture), receive_time_ns and publish_time_ns (the
    daemon's system clock), arrival_time_ns and ready_time_ns (here, time.time_ns())."""

    __slots__ = ('frame_number', 'source_time_ns', 'receive_time_ns', 'publish_time_ns', 'arrival_time_ns', 'ready_time_ns',
                 'timecode', 'markers_filled', 'markers_relabelled', 'pipeline_dropped', 'subscriber_dropped',
                 'message_bytes', 'key_frame', 'vertices', 'normals', 'markers', 'marker_status', 'parameters', 'mesh')

    def __repr__(self):
        shape = None if self.vertices is None else self.vertices.shape
        return f'<Frame {self.frame_number} vertices {shape} markers {0 if self.markers is None else len(self.markers)}>'


class Subscriber:
    """A subscription. Connects and sends Hello on construction (ConnectionLost when the daemon
    cannot be reached); next_frame() and frames() read. Every error is an Error subclass with a
    one-line message (the daemon's own words made printable); after one, make a new Subscriber
    (Receiver does that with backoff). A MeshInfo announcing more than max_vertices or
    max_markers is an error before anything is made for it. A Frame
    that breaks the protocol on its own (a value that is not finite, a block of the wrong size)
    is skipped instead, counted in frames_rejected with the reason in last_rejection, and logged
    as a warning ('skinstream' logger) at most once a second.
    libraries=False decodes in numpy even where libmeshoptimizer or libskinstream_client load.
    packed=False asks for MeshInfo and the Model plain instead of packed (deflated; about 2.8
    times fewer bytes to wait for as the subscriber joins)."""

    def __init__(self, host='127.0.0.1', port=8481, encoding='parameters', normals=True, markers=False, mesh=True,
                 paced=False, evaluate=True, subject='', token='', protocol_version=2, connect_timeout=5.0, libraries=True,
                 max_vertices=4_000_000, max_markers=4096, packed=True):
        if encoding not in wire.ENCODINGS:
            raise ValueError(f'unknown encoding "{encoding}" (float, quantised, compressed or parameters)')
        if protocol_version not in wire.VERSIONS:
            raise ValueError(f'protocol version {protocol_version} (this package speaks 1 and 2)')
        self.encoding_asked = wire.ENCODINGS.index(encoding)
        if protocol_version == 1 and (self.encoding_asked > wire.QUANTISED or subject or token):
            raise ValueError('the compressed and parameter encodings, a subject and a token need protocol version 2')
        self.version = protocol_version
        self.paced, self.evaluate, self.want_normals = paced, evaluate, normals
        self.libraries = libraries  # decode with the system's libraries when they load (decoder_choice.py)
        self.max_vertices, self.max_markers = max_vertices, max_markers  # of a MeshInfo, checked before anything is made
        wants = ((wire.WANT_NORMALS if normals else 0) | (wire.WANT_MARKERS if markers else 0) |
                 (0 if mesh else wire.WANT_NO_MESH) | (wire.WANT_PACED if paced else 0))
        if protocol_version == 1 and self.encoding_asked == wire.QUANTISED:
            wants |= wire.WANT_QUANTISED
        if protocol_version == 2 and packed:
            wants |= wire.WANT_PACKED  # MeshInfo and the Model deflated: about 2.8 times fewer bytes as it joins
        self.packed = bool(wants & wire.WANT_PACKED)
        self.peer = f'{host}:{port}'
        self.mesh = None  # protocol.MeshInfo, once it came
        self.model = None  # protocol.Model (parameter encoding)
        self.status = None  # protocol.Status, the latest
        self.frames_skipped = 0  # compressed deltas without their key
        self.frames_rejected = 0  # Frames that broke the protocol on their own, skipped
        self.last_rejection = ''
        self._last_rejection_log = 0.0
        self.bytes_received = 0
        self._evaluator = self._compressed = None
        self._header = bytearray(wire.HEADER_BYTES)
        self._payload = None
        self._filled = 0
        try:
            self._socket = socket.create_connection((host, port), timeout=connect_timeout)
            self._socket.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self._socket.sendall(wire.encode_hello(protocol_version, wants, self.encoding_asked, subject, token))
        except OSError as e:
            raise ConnectionLost(f'{self.peer}: {e.strerror or e}') from None

    def close(self):
        self._socket.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @property
    def encoding(self):
        """The encoding the daemon serves (MeshInfo), or the one asked for before MeshInfo came."""
        if self.mesh is None:
            return wire.ENCODINGS[self.encoding_asked]
        return wire.ENCODINGS[self.mesh.encoding]

    @property
    def decoder(self):
        """What turns the frames into vertices: 'libskinstream_client' or 'numpy' (parameters),
        'libmeshoptimizer' or 'numpy' (compressed), 'numpy' (float, quantised); None before
        MeshInfo (and for parameters before the Model)."""
        if self.mesh is None:
            return None
        if self.mesh.encoding == wire.PARAMETERS:
            return None if self._evaluator is None else self._evaluator.name
        return self._compressed.name if self._compressed is not None else 'numpy'

    def frames(self, timeout=None):
        """Frames as they come; ends when the daemon closes the connection (then raises
        ConnectionLost), or when none came within `timeout` seconds (None: waits for ever)."""
        while True:
            frame = self.next_frame(3600.0 if timeout is None else timeout)
            if frame is None:
                if timeout is None:
                    continue
                return
            yield frame

    def next_frame(self, timeout=1.0):
        """The next frame, or None when none was ready within `timeout` seconds."""
        deadline = time.monotonic() + timeout
        while True:
            message = self._read_message(deadline)
            if message is None:
                return None
            version, kind, payload = message
            if version != self.version:
                raise ProtocolError(f'the daemon answered in protocol version {version}, not {self.version}')
            if kind == wire.PACKED:
                if not self.packed:
                    raise ProtocolError('the daemon sent a Packed message, which this subscriber did not ask for')
                kind, payload = wire.unpack(payload)
            if kind == wire.MESH_INFO:
                self._on_mesh_info(payload)
            elif kind == wire.MODEL:
                self._on_model(payload)
            elif kind == wire.STATUS:
                self.status = wire.Status(payload, version)
                if self.status.refused:
                    raise Refused(f'the daemon refused this subscriber: {wire.printable(self.status.detail)}')
            elif kind == wire.FRAME:
                self._check_frame_order(payload)
                # Its length framed it, so the stream is still in step: a bad frame costs itself only.
                try:
                    frame = self._on_frame(payload)
                except ProtocolError as e:
                    frame = None
                    self._reject(e)
                if self.paced:  # every Frame taken, a skipped one too: the daemon waits while two are unacknowledged
                    self._send(wire.encode_ack(self.version, struct.unpack_from('<I', payload)[0]))
                if frame is not None:
                    return frame
            else:
                raise ProtocolError(f'unexpected {wire.MESSAGE_NAMES[kind]} message from the daemon')

    def _on_mesh_info(self, payload):
        self.mesh = wire.MeshInfo(payload, self.version, self.max_vertices, self.max_markers)
        if self.version == 1:
            self.mesh.encoding = self.encoding_asked
        self.model = self._evaluator = self._compressed = None
        if self.mesh.encoding == wire.COMPRESSED:
            self._compressed = compressed_decoder(self.mesh.vertex_count, self.mesh.compressed_order, self.libraries)

    def _on_model(self, payload):
        if self.mesh is None:
            raise ProtocolError('a Model message before MeshInfo')
        model = wire.Model(payload)
        if model.vertex_count != self.mesh.vertex_count:
            raise ProtocolError(f'the Model has {model.vertex_count} vertices, MeshInfo {self.mesh.vertex_count}')
        self._evaluator = parameter_evaluator(model, payload, self.mesh.faces, self.libraries)
        self.model = model

    def _check_frame_order(self, payload):
        """Frames out of order end the subscription (unlike a frame broken on its own)."""
        if self.mesh is None:
            raise ProtocolError('a Frame before MeshInfo')
        flags = struct.unpack_from('<I', payload, 4)[0] if len(payload) >= 8 else 0
        if flags & wire.FRAME_PARAMETERS and self._evaluator is None:
            raise ProtocolError('a parameter Frame before the Model')

    def _reject(self, error):
        self.frames_rejected += 1
        self.last_rejection = f'frame skipped: {error}'
        now = time.monotonic()
        if now - self._last_rejection_log >= 1.0:
            self._last_rejection_log = now
            _log.warning('%s: %s (%d frames skipped so far)', self.peer, self.last_rejection, self.frames_rejected)

    def _on_frame(self, payload):
        arrival = time.time_ns()
        mesh = self.mesh
        view = wire.FrameView(payload, self.version)
        v = view.vertex_count
        if view.positions is not None and not view.flags & wire.FRAME_PARAMETERS and v != mesh.vertex_count:
            raise ProtocolError(f'a Frame of {v} vertices, MeshInfo says {mesh.vertex_count}')
        if view.markers is not None and len(view.markers) > len(mesh.marker_names):
            raise ProtocolError('a Frame with more markers than MeshInfo names')
        frame = Frame()
        frame.vertices = frame.normals = frame.parameters = None
        flags = view.flags
        if flags & wire.FRAME_PARAMETERS:
            if self._evaluator is None:
                raise ProtocolError('a parameter Frame before the Model')
            frame.parameters = view.positions
            if self.evaluate:
                frame.vertices, frame.normals = self._evaluator.evaluate(view.positions, self.want_normals)
            else:
                self._evaluator.parameters(view.positions)  # checked all the same
        elif flags & wire.FRAME_COMPRESSED:
            if self._compressed is None:
                raise ProtocolError('a compressed Frame, MeshInfo announced another encoding')
            decoded = self._compressed.decode(view.positions, view.normals, bool(flags & wire.FRAME_KEY))
            if decoded is None:
                self.frames_skipped += 1
                return None
            frame.vertices, frame.normals = decoded
        elif view.positions is not None:
            if flags & wire.FRAME_QUANTISED:
                frame.vertices = wire.quantised_positions(view.positions, v)
                frame.normals = None if view.normals is None else wire.quantised_normals(view.normals, v)
            else:
                frame.vertices = wire.float_block(view.positions, v)
                frame.normals = None if view.normals is None else wire.float_block(view.normals, v)
        frame.markers, frame.marker_status = view.markers, view.marker_status
        # Nothing that is not finite reaches the renderer (the parameters were checked as they were read).
        for name in ('vertices', 'normals', 'markers'):
            values = getattr(frame, name)
            if values is not None and not np.isfinite(values).all():
                raise ProtocolError(f'a Frame whose {name} are not all finite')
        for name in ('frame_number', 'source_time_ns', 'receive_time_ns', 'publish_time_ns', 'timecode', 'markers_filled',
                     'markers_relabelled', 'pipeline_dropped', 'subscriber_dropped'):
            setattr(frame, name, getattr(view, name))
        frame.key_frame = bool(flags & wire.FRAME_KEY)
        frame.message_bytes = wire.HEADER_BYTES + len(payload)
        frame.mesh = mesh
        frame.arrival_time_ns = arrival
        frame.ready_time_ns = time.time_ns()
        return frame

    def _send(self, data):
        try:
            self._socket.sendall(data)
        except OSError as e:
            raise ConnectionLost(f'{self.peer}: sending failed: {e.strerror or e}') from None

    def _read_message(self, deadline):
        """(version, type, payload) of the next whole message, or None at the deadline (a message
        read in part is kept for the next call)."""
        while True:
            if self._payload is None:
                target, size = self._header, wire.HEADER_BYTES
            else:
                target, size = self._payload, len(self._payload)
            if self._filled == size:
                if self._payload is None:
                    self._version, self._kind, payload_bytes = wire.decode_header(self._header)
                    self._payload, self._filled = bytearray(payload_bytes), 0
                    continue
                payload, self._payload, self._filled = self._payload, None, 0
                return self._version, self._kind, payload
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            self._socket.settimeout(left)
            try:
                n = self._socket.recv_into(memoryview(target)[self._filled:], size - self._filled)
            except (socket.timeout, BlockingIOError):
                return None
            except OSError as e:
                raise ConnectionLost(f'{self.peer}: {e.strerror or e}') from None
            if n == 0:
                raise ConnectionLost(f'{self.peer}: the daemon closed the connection')
            self._filled += n
            self.bytes_received += n
