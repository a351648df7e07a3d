"""The subscriber protocol's messages as bytes (docs/subscriber-protocol.md, versions 1 and 2).

Decoders take a message's payload (after the 12-byte header) and return plain objects with
numpy arrays that view the payload where the layout allows; each raises ProtocolError naming
the rule that was broken. No sockets here.
"""
import struct
import zlib

import numpy as np

MAGIC = 0x46534B53  # "SKSF"
HEADER = struct.Struct('<IHHI')
HEADER_BYTES = HEADER.size
MAX_PAYLOAD = 64 << 20
VERSIONS = (1, 2)

HELLO, MESH_INFO, FRAME, STATUS, ACK, MODEL, PACKED = 1, 2, 3, 4, 5, 6, 7
MESSAGE_NAMES = {HELLO: 'Hello', MESH_INFO: 'MeshInfo', FRAME: 'Frame', STATUS: 'Status', ACK: 'Ack', MODEL: 'Model',
                 PACKED: 'Packed'}

ENCODINGS = ('float', 'quantised', 'compressed', 'parameters')
FLOAT, QUANTISED, COMPRESSED, PARAMETERS = range(4)

WANT_NORMALS, WANT_QUANTISED, WANT_MARKERS, WANT_NO_MESH, WANT_PACED = 1, 2, 4, 8, 16
WANT_PACKED = 32  # version 2: MeshInfo and Model come as Packed messages

FRAME_NORMALS, FRAME_QUANTISED, FRAME_MARKERS, FRAME_NO_POSITIONS = 1, 2, 4, 8
FRAME_PARAMETERS, FRAME_COMPRESSED, FRAME_KEY, FRAME_TIMECODE = 16, 32, 64, 128

SOURCE_STATES = ('connecting', 'streaming', 'disconnected', 'finished', 'refused')
REFUSED = 4

MARKER_STATUS = ('measured', 'relabelled', 'filled by PCA', 'filled rigidly', 'held')

_FRAME_FIXED = struct.Struct('<IIqqqIIHHII')  # 52 bytes
_TIMECODE = struct.Struct('<BBBBHHfI')  # 16 bytes
_STATUS_FIXED = struct.Struct('<IfQQ')
PART_BYTES = 80  # a Model part
PARAMETER_PART_BYTES = 160  # a Frame's part parameters


class Error(Exception):
    """Anything that ends a subscription: its message is one line that says why."""


class ProtocolError(Error):
    """Bytes that do not follow the subscriber protocol; the message says which rule."""


def printable(text, limit=256):
    """Text from the daemon made fit for a one-line message: every character outside printable
    ASCII (line breaks, terminal escapes) becomes \\xNN or \\uNNNN, and long text is cut."""
    out = ''.join(c if ' ' <= c <= '~' else f'\\x{ord(c):02x}' if ord(c) < 256 else f'\\u{ord(c):04x}' for c in text[:limit])
    return out + (f'... ({len(text)} characters)' if len(text) > limit else '')


def padding_to_4(n):
    return (4 - n % 4) % 4


class _Reader:
    """Reads little-endian fields from a payload, each read checked against what is left."""

    def __init__(self, payload, what):
        self.data = memoryview(payload)
        self.at = 0
        self.what = what

    def remaining(self):
        return len(self.data) - self.at

    def need(self, n, field):
        if n > self.remaining():
            raise ProtocolError(f'{self.what}: {field} truncated ({n} bytes needed, {self.remaining()} left)')

    def unpack(self, fmt, field):
        s = struct.Struct(fmt)
        self.need(s.size, field)
        values = s.unpack_from(self.data, self.at)
        self.at += s.size
        return values

    def u32(self, field):
        return self.unpack('<I', field)[0]

    def array(self, dtype, count, field):
        dtype = np.dtype(dtype)
        self.need(dtype.itemsize * count, field)
        out = np.frombuffer(self.data, dtype, count, self.at)
        self.at += dtype.itemsize * count
        return out

    def string(self, field):
        (n,) = self.unpack('<H', field)
        self.need(n, field)
        raw = bytes(self.data[self.at:self.at + n])
        self.at += n
        try:
            return raw.decode('utf-8')
        except UnicodeDecodeError:
            raise ProtocolError(f'{self.what}: {field} is not UTF-8') from None

    def skip(self, n, field='padding'):
        self.need(n, field)
        self.at += n

    def finish(self):
        if self.remaining():
            raise ProtocolError(f'{self.what}: {self.remaining()} bytes left over after the message')


def decode_header(data, versions=VERSIONS):
    """(version, type, payload bytes) of a 12-byte header."""
    if len(data) < HEADER_BYTES:
        raise ProtocolError(f'message header truncated: {len(data)} of 12 bytes')
    magic, version, kind, size = HEADER.unpack_from(data)
    if magic != MAGIC:
        raise ProtocolError('bad magic (not a skinstream subscriber stream)')
    if version not in versions:
        raise ProtocolError(f'unsupported protocol version {version} (this side speaks {" and ".join(map(str, versions))})')
    if kind not in MESSAGE_NAMES or (kind in (MODEL, PACKED) and version < 2):
        raise ProtocolError(f'unknown message type {kind} in version {version}')
    if size > MAX_PAYLOAD:
        raise ProtocolError(f'payload of {size} bytes exceeds the limit of {MAX_PAYLOAD}')
    return version, kind, size


# A packed type's fixed counts, kept before the deflated stream: (bytes, offset of the u32 N of
# the 3N-value array after them, its name).
_PACKED_HEADS = {MESH_INFO: (20, 4, 'face count'), MODEL: (16, 0, 'vertex count')}
_MOST_INFLATED_PER_BYTE = 1032  # deflate's longest match in its shortest code


def unpack(payload, max_payload=MAX_PAYLOAD):
    """(type, payload) of the MeshInfo or Model a Packed message holds: its counts, then the rest
    inflated with the first 3N u32 values decoded (byte planes joined, each value plus the value
    three before it)."""
    if len(payload) < 8:
        raise ProtocolError(f'Packed: truncated ({len(payload)} of 8 bytes of its fields)')
    kind, reserved, size = struct.unpack_from('<HHI', payload)
    if kind not in _PACKED_HEADS:
        raise ProtocolError(f'Packed: holds a message of type {kind} (only MeshInfo and Model are packed)')
    if reserved:
        raise ProtocolError(f'Packed: reserved field is {reserved}, not 0')
    if size > max_payload:
        raise ProtocolError(f'Packed: unpacked size {size} over the limit of {max_payload}')
    head_bytes, count_at, count_name = _PACKED_HEADS[kind]
    if len(payload) < 8 + head_bytes:
        raise ProtocolError(f'Packed: truncated in its counts ({len(payload) - 8} of {head_bytes} bytes)')
    if size < head_bytes:
        raise ProtocolError(f'Packed: unpacked size {size} shorter than its counts')
    head = bytes(payload[8:8 + head_bytes])
    stream = bytes(payload[8 + head_bytes:])
    rest_bytes = size - head_bytes
    if rest_bytes > len(stream) * _MOST_INFLATED_PER_BYTE + 64:
        raise ProtocolError(f'Packed: {len(stream)} deflated bytes cannot make {rest_bytes}')
    count = 3 * struct.unpack_from('<I', head, count_at)[0]
    if 4 * count > rest_bytes:
        raise ProtocolError(f'Packed: its {count_name} needs {4 * count} bytes, the unpacked size leaves {rest_bytes}')
    inflater = zlib.decompressobj()
    try:
        rest = inflater.decompress(stream, rest_bytes or 1)  # (a max_length of 0 would mean no limit)
    except zlib.error as e:
        raise ProtocolError(f'Packed: the deflated stream is corrupt ({e})') from None
    if inflater.unconsumed_tail:
        raise ProtocolError(f'Packed: the deflated stream makes more than the unpacked size {rest_bytes}')
    if not inflater.eof:
        raise ProtocolError(f'Packed: the deflated stream ends early ({len(rest)} of {rest_bytes} bytes made)')
    if inflater.unused_data:
        raise ProtocolError(f'Packed: {len(inflater.unused_data)} bytes after the deflated stream')
    if len(rest) != rest_bytes:
        raise ProtocolError(f'Packed: the deflated stream makes {len(rest)} bytes, the unpacked size says {rest_bytes}')
    planes = np.frombuffer(rest, np.uint8, 4 * count).reshape(4, count).astype(np.uint32)
    deltas = planes[0] | planes[1] << 8 | planes[2] << 16 | planes[3] << 24
    values = deltas.reshape(-1, 3).cumsum(axis=0, dtype=np.uint32)  # wraps modulo 2^32, as the differences did
    return kind, head + values.astype('<u4').tobytes() + rest[4 * count:]


def message(kind, payload, version):
    return HEADER.pack(MAGIC, version, kind, len(payload)) + payload


def _short_string(text, what):
    raw = text.encode('utf-8')
    if len(raw) > 256:
        raise ValueError(f'{what} of {len(raw)} bytes (at most 256)')
    return struct.pack('<H', len(raw)) + raw


def encode_hello(version, wants, encoding=FLOAT, subject='', token=''):
    payload = struct.pack('<I', wants)
    if version >= 2:
        payload += struct.pack('<I', encoding) + _short_string(subject, 'subject') + _short_string(token, 'token')
    return message(HELLO, payload, version)


def encode_ack(version, frame_number):
    return message(ACK, struct.pack('<I', frame_number), version)


class MeshInfo:
    """What the daemon says of the subject once after Hello: topology, markers, encoding."""

    def __init__(self, payload, version, max_vertices=4_000_000, max_markers=4096):
        r = _Reader(payload, 'MeshInfo')
        v, f, m, self.part_count, self.source_rate_hz = r.unpack('<IIIIf', 'counts')
        # Checked before anything is made for them: 67 million vertices fit in 64 MiB.
        if v > max_vertices:
            raise ProtocolError(f'MeshInfo: {v} vertices, more than this subscriber takes ({max_vertices}, its max_vertices)')
        if m > max_markers:
            raise ProtocolError(f'MeshInfo: {m} markers, more than this subscriber takes ({max_markers}, its max_markers)')
        self.vertex_count, self.marker_count = v, m
        self.faces = r.array('<u4', 3 * f, 'faces').reshape(f, 3)
        if f and int(self.faces.max()) >= v:
            raise ProtocolError(f'MeshInfo: face index {int(self.faces.max())} out of range')
        self.dominant_part = r.array('u1', v, 'dominant parts')
        t = r.u32('marker triangle count')
        self.marker_triangles = r.array('<u4', 3 * t, 'marker triangles').reshape(t, 3)
        if t and int(self.marker_triangles.max()) >= m:
            raise ProtocolError(f'MeshInfo: marker triangle index {int(self.marker_triangles.max())} out of range')
        self.marker_names = [r.string('marker name') for _ in range(m)]
        self.subject = ''
        self.encoding = FLOAT
        self.compressed_order = None
        if version >= 2:
            self.subject = r.string('subject name')
            self.encoding = r.u32('encoding')
            if self.encoding >= len(ENCODINGS):
                raise ProtocolError(f'MeshInfo: unknown encoding {self.encoding}')
            n = r.u32('compressed vertex order count')
            if n not in (0, v):
                raise ProtocolError(f'MeshInfo: a compressed vertex order of {n} for {v} vertices')
            order = r.array('<u4', n, 'compressed vertex order')
            if n:
                if np.bincount(order, minlength=v).max() != 1 or int(order.max()) >= v:
                    raise ProtocolError(f'MeshInfo: the compressed vertex order is not a permutation of the {v} vertices')
                self.compressed_order = order
        r.finish()


class Status:
    """What the daemon says of its source, on every change and at 1 Hz."""

    def __init__(self, payload, version):
        r = _Reader(payload, 'Status')
        state, self.source_rate_hz, self.frames_received, self.frames_published = r.unpack(_STATUS_FIXED.format, 'fields')
        if state > (4 if version >= 2 else 3):
            raise ProtocolError(f'Status: unknown source state {state}')
        self.state = SOURCE_STATES[state]
        self.refused = state == REFUSED
        self.detail = r.string('detail')
        self.subject, self.subject_present, self.encoding = '', True, None
        if version >= 2:
            self.subject = r.string('subject name')
            present, self.encoding = r.unpack('<II', 'presence and encoding')
            if present > 1:
                raise ProtocolError(f'Status: subject presence {present} is not 0 or 1')
            self.subject_present = present == 1
        r.finish()


class Model:
    """The parameter encoding's static half (the Model message): see evaluation.py."""

    def __init__(self, payload):
        r = _Reader(payload, 'Model')
        v, p, y, k = r.unpack('<IIII', 'counts')
        expected = 16 + 12 * v + PART_BYTES * p + 12 * y + v + k + padding_to_4(v + k) + 4 * k
        if expected != len(payload):
            raise ProtocolError(f'Model: counts ({v} vertices, {p} parts, {y} members, {k} influences) say {expected} bytes, '
                                f'the payload holds {len(payload)}')
        self.vertex_count, self.part_count, self.member_count, self.influence_count = v, p, y, k
        self.reference = r.array('<f4', 3 * v, 'reference vertices').reshape(v, 3)
        parts = r.array('u1', PART_BYTES * p, 'parts').reshape(p, PART_BYTES)
        floats = parts[:, :76].copy().view('<f4')  # 19 floats a part
        self.rotation = floats[:, 0:9].reshape(p, 3, 3)
        self.translation = floats[:, 9:12]
        self.box_min = floats[:, 12:15]
        self.box_max = floats[:, 15:18]
        self.sigma = floats[:, 18]
        self.part_members = parts[:, 76:80].copy().view('<u4').ravel()
        self.members = r.array('<f4', 3 * y, 'members').reshape(y, 3)
        self.influences_per_vertex = r.array('u1', v, 'influence counts')
        self.influence_parts = r.array('u1', k, 'influence parts')
        r.skip(padding_to_4(v + k))
        self.influence_weights = r.array('<f4', k, 'influence weights')
        self._validate()

    def _validate(self):
        def fail(why):
            raise ProtocolError(f'Model: {why}')
        if self.vertex_count == 0 or self.part_count == 0:
            fail('no vertices or no parts')
        if int(self.part_members.sum()) != self.member_count or self.part_members.min() < 1:
            fail(f'the parts count {int(self.part_members.sum())} members (each at least 1), the header {self.member_count}')
        if int(self.influences_per_vertex.astype(np.int64).sum()) != self.influence_count or self.influences_per_vertex.min() < 1:
            fail(f'the vertices count {int(self.influences_per_vertex.astype(np.int64).sum())} influences (each at least 1), '
                 f'the header {self.influence_count}')
        if int(self.influence_parts.max()) >= self.part_count:
            fail(f'an influence of part {int(self.influence_parts.max())} of {self.part_count}')
        for name in ('reference', 'rotation', 'translation', 'box_min', 'box_max', 'sigma', 'members', 'influence_weights'):
            if not np.isfinite(getattr(self, name)).all():
                fail(f'{name.replace("_", " ")} not finite')
        if (self.sigma < 0).any() or (self.box_min > self.box_max).any():
            fail('a negative dilation or an empty box')


class Timecode:
    __slots__ = ('hours', 'minutes', 'seconds', 'frames', 'subframe', 'subframes_per_frame', 'rate_hz', 'drop_frame', 'field')

    def __init__(self, fields):
        (self.hours, self.minutes, self.seconds, self.frames, self.subframe, self.subframes_per_frame, self.rate_hz,
         flags) = fields
        self.drop_frame = bool(flags & 1)
        self.field = bool(flags & 2)

    def __str__(self):
        separator = ';' if self.drop_frame else ':'
        return f'{self.hours:02d}:{self.minutes:02d}:{self.seconds:02d}{separator}{self.frames:02d}'


class FrameView:
    """A Frame payload cut into its blocks, each a memoryview of the payload (no copies)."""

    def __init__(self, payload, version):
        r = _Reader(payload, 'Frame')
        (self.frame_number, flags, self.source_time_ns, self.receive_time_ns, self.publish_time_ns, v, m,
         self.markers_filled, self.markers_relabelled, self.pipeline_dropped,
         self.subscriber_dropped) = r.unpack(_FRAME_FIXED.format, 'fixed part')
        self.flags, self.vertex_count, self.marker_count = flags, v, m
        self.timecode = None
        if version >= 2:
            fields = r.unpack(_TIMECODE.format, 'timecode')
            if flags & FRAME_TIMECODE:
                self.timecode = Timecode(fields)
        if flags & ~(0xFF if version >= 2 else 0xF):
            raise ProtocolError(f'Frame: reserved flag bits set ({flags})')
        has_positions = not flags & FRAME_NO_POSITIONS
        encodings = sum(bool(flags & bit) for bit in (FRAME_QUANTISED, FRAME_COMPRESSED, FRAME_PARAMETERS))
        if encodings > 1:
            raise ProtocolError('Frame: more than one encoding of the positions')
        if not has_positions and (v or encodings or flags & FRAME_NORMALS):
            raise ProtocolError('Frame: positions or normals with "no positions"')
        if flags & FRAME_PARAMETERS and (v or flags & FRAME_NORMALS):
            raise ProtocolError('Frame: a vertex count or normals with parameters')
        if flags & FRAME_KEY and not flags & FRAME_COMPRESSED:
            raise ProtocolError('Frame: key frame flag without compression')
        if not flags & FRAME_MARKERS and m:
            raise ProtocolError('Frame: marker count without markers')
        self.positions = self.normals = None
        if flags & FRAME_PARAMETERS:
            r.need(8, 'parameters')
            parts, members = struct.unpack_from('<II', r.data, r.at)
            self.positions = self._block(r, 8 + PARAMETER_PART_BYTES * parts + 12 * members, 'parameters')
        elif flags & FRAME_COMPRESSED:
            self.positions = self._block(r, self._counted(r, 28, 'compressed positions'), 'compressed positions')
            if flags & FRAME_NORMALS:
                self.normals = self._block(r, self._counted(r, 0, 'compressed normals'), 'compressed normals')
        elif has_positions:
            quantised = flags & FRAME_QUANTISED
            values = 2 * 3 * v + padding_to_4(6 * v) if quantised else 12 * v
            expected = (24 if quantised else 0) + values * (2 if flags & FRAME_NORMALS else 1)
            expected += 12 * m + m + padding_to_4(m) if flags & FRAME_MARKERS else 0
            if expected != r.remaining():
                raise ProtocolError(f'Frame: counts say {expected} bytes of data, the payload holds {r.remaining()}')
            self.positions = self._block(r, (24 if quantised else 0) + values, 'positions')
            if flags & FRAME_NORMALS:
                self.normals = self._block(r, values, 'normals')
        self.markers = self.marker_status = None
        if flags & FRAME_MARKERS:
            if 12 * m + m + padding_to_4(m) != r.remaining():
                raise ProtocolError(f'Frame: counts say {12 * m + m + padding_to_4(m)} bytes of markers, '
                                    f'the payload holds {r.remaining()}')
            self.markers = r.array('<f4', 3 * m, 'markers').reshape(m, 3)
            self.marker_status = r.array('u1', m, 'marker status')
            r.skip(padding_to_4(m))
            if m and int(self.marker_status.max()) > 4:
                raise ProtocolError(f'Frame: marker status {int(self.marker_status.max())} is not one of 0-4')
        r.finish()

    @staticmethod
    def _block(r, n, what):
        if n > r.remaining():
            raise ProtocolError(f'Frame: {what} of {n} bytes, the payload holds {r.remaining()}')
        block = r.data[r.at:r.at + n]
        r.at += n
        return block

    @staticmethod
    def _counted(r, offset, what):
        """The size of a block whose u32 at `offset` counts the coded bytes after it."""
        r.need(offset + 4, what)
        (coded,) = struct.unpack_from('<I', r.data, r.at + offset)
        if coded > r.remaining():
            raise ProtocolError(f'Frame: {what} says {coded} bytes, more than the payload holds')
        return offset + 4 + coded + padding_to_4(coded)


def float_block(block, count):
    """count x 3 float32 view of a float positions or normals block."""
    return np.frombuffer(block, '<f4', 3 * count).reshape(count, 3)


def quantised_positions(block, count):
    origin = np.frombuffer(block, '<f4', 3, 0)
    step = np.frombuffer(block, '<f4', 3, 12)
    q = np.frombuffer(block, '<u2', 3 * count, 24).reshape(count, 3)
    return origin + q * step


def quantised_normals(block, count):
    q = np.frombuffer(block, '<i2', 3 * count).reshape(count, 3)
    return np.divide(q, np.float32(32767.0), dtype=np.float32)
