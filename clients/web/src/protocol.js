// The subscriber protocol (docs/subscriber-protocol.md): one protocol message per binary
// WebSocket message. Everything is little-endian; DataView reads are used throughout, so the
// decoder does not depend on the host's byte order or on alignment (MeshInfo is unaligned).
// Version 1, and version 2's float and quantised encodings: a page naming a subject speaks
// version 2, and every message says its version in its header.

export const MAGIC = 0x46534b53; // "SKSF" read as a little-endian u32
export const PROTOCOL_VERSION = 1;
export const VERSION_2 = 2;
export const HEADER_BYTES = 12;
export const MAX_PAYLOAD_BYTES = 64 * 1024 * 1024;

export const MessageType = Object.freeze({ HELLO: 1, MESH_INFO: 2, FRAME: 3, STATUS: 4, ACK: 5 });

// PACED: this side sends Ack for every Frame and the daemon keeps at most PACED_WINDOW Frames
// unacknowledged, so a slow page never has seconds of frames queued in front of it.
export const Wants = Object.freeze({ NORMALS: 1, QUANTISED: 2, MARKERS: 4, NO_MESH: 8, PACED: 16 });
export const PACED_WINDOW = 2;
export const FrameFlags = Object.freeze({ NORMALS: 1, QUANTISED: 2, MARKERS: 4, NO_POSITIONS: 8 });

export const MarkerStatus = Object.freeze({ MEASURED: 0, RELABELLED: 1, FILLED_PCA: 2, FILLED_RIGID: 3, HELD: 4 });
export const NO_PART = 255;

// Which arrays decodeFrameArrays wrote.
export const Decoded = Object.freeze({ POSITIONS: 1, NORMALS: 2, MARKERS: 4 });

// REFUSED (version 2): the daemon refuses this subscriber (e.g. a subject it does not serve).
export const SourceState = Object.freeze({ CONNECTING: 0, STREAMING: 1, DISCONNECTED: 2, FINISHED: 3, REFUSED: 4 });
export const SOURCE_STATE_NAMES = ['connecting', 'streaming', 'disconnected', 'finished', 'refused'];
// Version 2: how positions are sent.
export const Encoding = Object.freeze({ FLOAT: 0, QUANTISED: 1, COMPRESSED: 2, PARAMETERS: 3 });
const TIMECODE_FLAG = 0x80; // version 2 Frames: the timecode fields hold the source's timecode

// Size of the fixed Frame fields before the arrays (version 2 adds 16 bytes of timecode).
const FRAME_FIXED_BYTES = 4 + 4 + 8 + 8 + 8 + 4 + 4 + 2 + 2 + 4 + 4;
const frameFixedBytes = (version) => FRAME_FIXED_BYTES + (version >= VERSION_2 ? 16 : 0);
// The version a message's header says.
export const messageVersion = (view) => view.getUint16(4, true);

// A message that breaks the spec: the connection must be closed.
export class ProtocolError extends Error {
  constructor(message) {
    super(message);
    this.name = 'ProtocolError';
  }
}

// The two subscriber -> daemon messages carry one u32 each.
function encodeU32Message(type, value) {
  const buffer = new ArrayBuffer(HEADER_BYTES + 4);
  const view = new DataView(buffer);
  view.setUint32(0, MAGIC, true);
  view.setUint16(4, PROTOCOL_VERSION, true);
  view.setUint16(6, type, true);
  view.setUint32(8, 4, true);
  view.setUint32(12, value >>> 0, true);
  return buffer;
}

const utf8Encoder = new TextEncoder();

// Version 1 without `version2`; with it ({ subject, encoding, token }), version 2: the wants
// without the quantised bit (the encoding says it), the encoding, the subject's name ('' = the
// daemon's first) and the daemon's token ('' = none).
export function encodeHello(wants, version2 = null) {
  if ((wants & ~0x1f) !== 0) throw new ProtocolError(`Hello wants 0x${wants.toString(16)} has unknown bits`);
  if (version2 === null) return encodeU32Message(MessageType.HELLO, wants);
  const subject = utf8Encoder.encode(version2.subject || '');
  const token = utf8Encoder.encode(version2.token || '');
  if (subject.length > 256 || token.length > 256) throw new ProtocolError('Hello subject and token are at most 256 bytes');
  const payload = 8 + 2 + subject.length + 2 + token.length;
  const buffer = new ArrayBuffer(HEADER_BYTES + payload);
  const view = new DataView(buffer);
  view.setUint32(0, MAGIC, true);
  view.setUint16(4, VERSION_2, true);
  view.setUint16(6, MessageType.HELLO, true);
  view.setUint32(8, payload, true);
  view.setUint32(12, wants & ~Wants.QUANTISED, true);
  view.setUint32(16, version2.encoding || Encoding.FLOAT, true);
  view.setUint16(20, subject.length, true);
  new Uint8Array(buffer, 22, subject.length).set(subject);
  view.setUint16(22 + subject.length, token.length, true);
  new Uint8Array(buffer, 24 + subject.length, token.length).set(token);
  return buffer;
}

export function encodeAck(frameNumber) {
  return encodeU32Message(MessageType.ACK, frameNumber);
}

// Checks the 12-byte header of a whole message and returns its type.
export function readHeader(view) {
  if (view.byteLength < HEADER_BYTES) throw new ProtocolError(`message of ${view.byteLength} bytes is shorter than the header`);
  const magic = view.getUint32(0, true);
  if (magic !== MAGIC) throw new ProtocolError(`bad magic 0x${magic.toString(16)}`);
  const version = view.getUint16(4, true);
  if (version !== PROTOCOL_VERSION && version !== VERSION_2) throw new ProtocolError(`protocol version ${version}, expected 1 or 2`);
  const type = view.getUint16(6, true);
  if (type < MessageType.HELLO || type > MessageType.STATUS) throw new ProtocolError(`unknown message type ${type}`);
  const payload = view.getUint32(8, true);
  if (payload > MAX_PAYLOAD_BYTES) throw new ProtocolError(`payload of ${payload} bytes is over the 64 MiB limit`);
  if (payload !== view.byteLength - HEADER_BYTES) {
    throw new ProtocolError(`header announces ${payload} payload bytes but the message carries ${view.byteLength - HEADER_BYTES}`);
  }
  return type;
}

// Bounds-checked sequential reader over one message's payload.
class PayloadReader {
  constructor(view, what) {
    this.view = view;
    this.offset = HEADER_BYTES;
    this.what = what;
  }
  need(bytes, field) {
    if (this.offset + bytes > this.view.byteLength) {
      throw new ProtocolError(`${this.what} truncated in ${field} (needs ${bytes} bytes at offset ${this.offset}, message has ${this.view.byteLength})`);
    }
  }
  u8(field) { this.need(1, field); const v = this.view.getUint8(this.offset); this.offset += 1; return v; }
  u16(field) { this.need(2, field); const v = this.view.getUint16(this.offset, true); this.offset += 2; return v; }
  u32(field) { this.need(4, field); const v = this.view.getUint32(this.offset, true); this.offset += 4; return v; }
  f32(field) { this.need(4, field); const v = this.view.getFloat32(this.offset, true); this.offset += 4; return v; }
  // i64/u64 as Number: nanoseconds since the epoch fit in 2^53 with ~0.25 µs resolution.
  i64(field) { this.need(8, field); const v = Number(this.view.getBigInt64(this.offset, true)); this.offset += 8; return v; }
  u64(field) { this.need(8, field); const v = Number(this.view.getBigUint64(this.offset, true)); this.offset += 8; return v; }
  bytes(count, field) {
    this.need(count, field);
    const b = new Uint8Array(this.view.buffer, this.view.byteOffset + this.offset, count);
    this.offset += count;
    return b;
  }
  string(field) { const length = this.u16(`${field} length`); return utf8.decode(this.bytes(length, field)); }
  expectEnd() {
    if (this.offset !== this.view.byteLength) {
      throw new ProtocolError(`${this.what} has ${this.view.byteLength - this.offset} unexpected trailing bytes`);
    }
  }
}

const utf8 = new TextDecoder('utf-8', { fatal: false });

// MeshInfo: allocated once per connection, so plain arrays are fine here.
export function decodeMeshInfo(view) {
  const r = new PayloadReader(view, 'MeshInfo');
  const vertexCount = r.u32('vertex_count');
  const faceCount = r.u32('face_count');
  const markerCount = r.u32('marker_count');
  const partCount = r.u32('part_count');
  const sourceRateHz = r.f32('source_rate_hz');
  r.need(12 * faceCount, 'faces');
  const faces = new Uint32Array(3 * faceCount);
  for (let i = 0; i < faces.length; ++i) faces[i] = r.u32('faces');
  for (let i = 0; i < faces.length; ++i) {
    if (faces[i] >= vertexCount) throw new ProtocolError(`MeshInfo face vertex ${faces[i]} is out of range (V = ${vertexCount})`);
  }
  const dominantPart = new Uint8Array(r.bytes(vertexCount, 'dominant parts'));
  const markerTriangleCount = r.u32('marker_triangle_count');
  r.need(12 * markerTriangleCount, 'marker triangles');
  const markerTriangles = new Uint32Array(3 * markerTriangleCount);
  for (let i = 0; i < markerTriangles.length; ++i) markerTriangles[i] = r.u32('marker triangles');
  for (let i = 0; i < markerTriangles.length; ++i) {
    if (markerTriangles[i] >= markerCount) {
      throw new ProtocolError(`MeshInfo marker triangle index ${markerTriangles[i]} is out of range (M = ${markerCount})`);
    }
  }
  const markerNames = new Array(markerCount);
  for (let i = 0; i < markerCount; ++i) markerNames[i] = r.string('marker name');
  // Version 2: the subject and the encoding served.
  const version2 = messageVersion(view) >= VERSION_2;
  const subject = version2 ? r.string('subject') : '';
  const encoding = version2 ? r.u32('encoding') : Encoding.FLOAT;
  r.expectEnd();
  return { vertexCount, faceCount, markerCount, partCount, sourceRateHz, faces, dominantPart, markerTriangles, markerNames, subject, encoding };
}

export function decodeStatus(view) {
  const r = new PayloadReader(view, 'Status');
  const version2 = messageVersion(view) >= VERSION_2;
  const state = r.u32('source state');
  if (state > (version2 ? SourceState.REFUSED : SourceState.FINISHED)) throw new ProtocolError(`Status has unknown source state ${state}`);
  const sourceRateHz = r.f32('source_rate_hz');
  const framesReceived = r.u64('frames received');
  const framesPublished = r.u64('frames published');
  const detail = r.string('detail');
  // Version 2: the subject, whether it is in the source's latest frames, the encoding served.
  const subject = version2 ? r.string('subject') : '';
  const subjectPresent = version2 ? r.u32('subject present') !== 0 : true;
  const encoding = version2 ? r.u32('encoding') : Encoding.FLOAT;
  r.expectEnd();
  return { state, stateName: SOURCE_STATE_NAMES[state], sourceRateHz, framesReceived, framesPublished, detail, subject, subjectPresent, encoding };
}

// The fixed fields of a Frame, read in place into a reused object (no allocation per frame).
export class FrameHeader {
  constructor() {
    this.frameNumber = 0;
    this.flags = 0;
    this.sourceTimeNs = 0;
    this.receiveTimeNs = 0;
    this.publishTimeNs = 0;
    this.vertexCount = 0;
    this.markerCount = 0;
    this.markersFilled = 0;
    this.markersRelabelled = 0;
    this.framesDroppedPipeline = 0;
    this.framesDroppedSubscriber = 0;
    this.fixedBytes = FRAME_FIXED_BYTES; // of this frame's version
  }

  // Reads the fixed fields and checks that the arrays the flags announce fit the message exactly.
  read(view) {
    this.fixedBytes = frameFixedBytes(messageVersion(view));
    if (view.byteLength < HEADER_BYTES + this.fixedBytes) {
      throw new ProtocolError(`Frame of ${view.byteLength} bytes is shorter than its fixed fields`);
    }
    let o = HEADER_BYTES;
    this.frameNumber = view.getUint32(o, true); o += 4;
    this.flags = view.getUint32(o, true); o += 4;
    this.sourceTimeNs = Number(view.getBigInt64(o, true)); o += 8;
    this.receiveTimeNs = Number(view.getBigInt64(o, true)); o += 8;
    this.publishTimeNs = Number(view.getBigInt64(o, true)); o += 8;
    this.vertexCount = view.getUint32(o, true); o += 4;
    this.markerCount = view.getUint32(o, true); o += 4;
    this.markersFilled = view.getUint16(o, true); o += 2;
    this.markersRelabelled = view.getUint16(o, true); o += 2;
    this.framesDroppedPipeline = view.getUint32(o, true); o += 4;
    this.framesDroppedSubscriber = view.getUint32(o, true); o += 4;
    // Version 2's timecode (bit 7) is read past; its other encodings are not asked for.
    const known = this.fixedBytes > FRAME_FIXED_BYTES ? 0xf | TIMECODE_FLAG : 0xf;
    if ((this.flags & ~known) !== 0) throw new ProtocolError(`Frame ${this.frameNumber} has unknown flags 0x${this.flags.toString(16)}`);
    const expected = frameBytes(this.flags, this.vertexCount, this.markerCount, this.fixedBytes);
    if (expected !== view.byteLength) {
      throw new ProtocolError(`Frame ${this.frameNumber} is ${view.byteLength} bytes, its flags and counts need ${expected}`);
    }
  }
}

// Zero bytes after a block of this many bytes, so the next block starts at a multiple of 4.
const paddingTo4 = (bytes) => (4 - (bytes % 4)) % 4;

// Total message size a Frame must have for these flags and counts.
export function frameBytes(flags, vertexCount, markerCount, fixedBytes = FRAME_FIXED_BYTES) {
  const quantised = (flags & FrameFlags.QUANTISED) !== 0;
  const quantisedBlock = 6 * vertexCount + paddingTo4(6 * vertexCount);
  let bytes = HEADER_BYTES + fixedBytes;
  if ((flags & FrameFlags.NO_POSITIONS) === 0) bytes += quantised ? 24 + quantisedBlock : 12 * vertexCount;
  if ((flags & FrameFlags.NORMALS) !== 0) bytes += quantised ? quantisedBlock : 12 * vertexCount;
  if ((flags & FrameFlags.MARKERS) !== 0) bytes += 13 * markerCount + paddingTo4(markerCount);
  return bytes;
}

// Decodes the arrays of a Frame whose header was read by FrameHeader.read into the caller's
// preallocated arrays. Returns which arrays were written, as Decoded bits.
export function decodeFrameArrays(view, header, out) {
  let o = HEADER_BYTES + header.fixedBytes;
  const V = header.vertexCount;
  const quantised = (header.flags & FrameFlags.QUANTISED) !== 0;
  let written = 0;
  if ((header.flags & FrameFlags.NO_POSITIONS) === 0) {
    if (V !== out.positions.length / 3) throw new ProtocolError(`Frame ${header.frameNumber} has ${V} vertices, MeshInfo said ${out.positions.length / 3}`);
    const p = out.positions;
    if (quantised) {
      const ox = view.getFloat32(o, true), oy = view.getFloat32(o + 4, true), oz = view.getFloat32(o + 8, true);
      const sx = view.getFloat32(o + 12, true), sy = view.getFloat32(o + 16, true), sz = view.getFloat32(o + 20, true);
      o += 24;
      for (let i = 0; i < 3 * V; i += 3, o += 6) {
        p[i] = ox + view.getUint16(o, true) * sx;
        p[i + 1] = oy + view.getUint16(o + 2, true) * sy;
        p[i + 2] = oz + view.getUint16(o + 4, true) * sz;
      }
      o += paddingTo4(6 * V);
    } else {
      for (let i = 0; i < 3 * V; ++i, o += 4) p[i] = view.getFloat32(o, true);
    }
    written |= Decoded.POSITIONS;
  }
  if ((header.flags & FrameFlags.NORMALS) !== 0) {
    const n = out.normals;
    if (V !== n.length / 3) throw new ProtocolError(`Frame ${header.frameNumber} normals for ${V} vertices, MeshInfo said ${n.length / 3}`);
    if (quantised) {
      for (let i = 0; i < 3 * V; ++i, o += 2) n[i] = view.getInt16(o, true) / 32767;
      o += paddingTo4(6 * V);
    } else {
      for (let i = 0; i < 3 * V; ++i, o += 4) n[i] = view.getFloat32(o, true);
    }
    written |= Decoded.NORMALS;
  }
  if ((header.flags & FrameFlags.MARKERS) !== 0) {
    const M = header.markerCount;
    if (M !== out.markerStatus.length) throw new ProtocolError(`Frame ${header.frameNumber} has ${M} markers, MeshInfo said ${out.markerStatus.length}`);
    const m = out.markers;
    for (let i = 0; i < 3 * M; ++i, o += 4) m[i] = view.getFloat32(o, true);
    const s = out.markerStatus;
    for (let i = 0; i < M; ++i, ++o) s[i] = view.getUint8(o);
    written |= Decoded.MARKERS;
  }
  return written;
}
