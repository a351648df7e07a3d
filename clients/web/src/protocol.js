// The subscriber protocol (docs/subscriber-protocol.md): one protocol message per binary
// WebSocket message. The page speaks version 2; version 1 is still read (the golden fixtures of
// both versions test this decoder). Everything is little-endian; DataView reads are used
// throughout, so the decoder does not depend on the host's byte order or on alignment (MeshInfo
// is unaligned).

export const MAGIC = 0x46534b53; // "SKSF" read as a little-endian u32
export const PROTOCOL_VERSION = 2; // what this page speaks
export const HEADER_BYTES = 12;
export const MAX_PAYLOAD_BYTES = 64 * 1024 * 1024;
const MAX_HELLO_STRING_BYTES = 256;

export const MessageType = Object.freeze({ HELLO: 1, MESH_INFO: 2, FRAME: 3, STATUS: 4, ACK: 5, MODEL: 6, PACKED: 7 });

// How the positions travel (version 2 Hello, MeshInfo and Status).
export const Encoding = Object.freeze({ FLOAT: 0, QUANTISED: 1, COMPRESSED: 2, PARAMETERS: 3 });
export const ENCODING_NAMES = Object.freeze(['float', 'quantised', 'compressed', 'parameters']);

// PACED: this side sends Ack for every Frame and the daemon keeps at most PACED_WINDOW Frames
// unacknowledged, so a slow page never has seconds of frames queued in front of it.
// QUANTISED is version 1 only (version 2 names the encoding instead).
// PACKED (version 2): MeshInfo and the Model come as Packed messages (packed_message.js).
export const Wants = Object.freeze({ NORMALS: 1, QUANTISED: 2, MARKERS: 4, NO_MESH: 8, PACED: 16, PACKED: 32 });
export const PACED_WINDOW = 2;
export const FrameFlags = Object.freeze({
  NORMALS: 1, QUANTISED: 2, MARKERS: 4, NO_POSITIONS: 8, // both versions
  PARAMETERS: 16, COMPRESSED: 32, KEY: 64, TIMECODE: 128, // version 2
});
const FRAME_FLAGS_OF_VERSION = { 1: 0x0f, 2: 0xff };

export const MarkerStatus = Object.freeze({ MEASURED: 0, RELABELLED: 1, FILLED_PCA: 2, FILLED_RIGID: 3, HELD: 4 });
export const NO_PART = 255;

// Which arrays decodeFrameArrays wrote.
export const Decoded = Object.freeze({ POSITIONS: 1, NORMALS: 2, MARKERS: 4 });

export const SourceState = Object.freeze({ CONNECTING: 0, STREAMING: 1, DISCONNECTED: 2, FINISHED: 3, REFUSED: 4 });
export const SOURCE_STATE_NAMES = ['connecting', 'streaming', 'disconnected', 'finished', 'refused'];

// Size of the fixed Frame fields before the arrays, and of the version 2 timecode after them.
const FRAME_FIXED_BYTES = 4 + 4 + 8 + 8 + 8 + 4 + 4 + 2 + 2 + 4 + 4;
const TIMECODE_BYTES = 16;
// A part's fit in a parameter block: A (27), R (9), d (3) as f32, then u32 flags.
export const PART_PARAMETER_BYTES = 160;
// The compressed positions block before the coded bytes: key frame number, origin, step, byte count.
export const COMPRESSED_POSITIONS_HEADER_BYTES = 32;

// A message that breaks the spec.
export class ProtocolError extends Error {
  constructor(message) {
    super(message);
    this.name = 'ProtocolError';
  }
}

// Zero bytes after a block of this many bytes, so the next block starts at a multiple of 4.
export const paddingTo4 = (bytes) => (4 - (bytes % 4)) % 4;

export function writeHeader(view, version, type, payloadBytes) {
  view.setUint32(0, MAGIC, true);
  view.setUint16(4, version, true);
  view.setUint16(6, type, true);
  view.setUint32(8, payloadBytes, true);
}

const utf8Encoder = new TextEncoder();

// Hello: version 1 carries the wants alone; version 2 also the encoding, the subject's name
// (empty: the daemon's first subject) and the daemon's shared token (empty when it has none).
export function encodeHello(wants, { version = PROTOCOL_VERSION, encoding = Encoding.PARAMETERS, subject = '', token = '' } = {}) {
  const allowed = version === 1 ? 0x1f : 0x3d;
  if ((wants & ~allowed) !== 0) throw new ProtocolError(`Hello wants 0x${wants.toString(16)} has bits version ${version} does not define`);
  if (version === 1) {
    const buffer = new ArrayBuffer(HEADER_BYTES + 4);
    const view = new DataView(buffer);
    writeHeader(view, 1, MessageType.HELLO, 4);
    view.setUint32(HEADER_BYTES, wants >>> 0, true);
    return buffer;
  }
  if (version !== 2) throw new ProtocolError(`protocol version ${version} is not spoken here`);
  const subjectBytes = utf8Encoder.encode(subject);
  const tokenBytes = utf8Encoder.encode(token);
  for (const [what, bytes] of [['subject', subjectBytes], ['token', tokenBytes]]) {
    if (bytes.length > MAX_HELLO_STRING_BYTES) throw new ProtocolError(`Hello ${what} of ${bytes.length} bytes is over ${MAX_HELLO_STRING_BYTES}`);
  }
  const payload = 8 + 2 + subjectBytes.length + 2 + tokenBytes.length;
  const buffer = new ArrayBuffer(HEADER_BYTES + payload);
  const view = new DataView(buffer);
  writeHeader(view, 2, MessageType.HELLO, payload);
  let o = HEADER_BYTES;
  view.setUint32(o, wants >>> 0, true); o += 4;
  view.setUint32(o, encoding >>> 0, true); o += 4;
  for (const bytes of [subjectBytes, tokenBytes]) {
    view.setUint16(o, bytes.length, true); o += 2;
    new Uint8Array(buffer, o, bytes.length).set(bytes); o += bytes.length;
  }
  return buffer;
}

export function encodeAck(frameNumber, version = PROTOCOL_VERSION) {
  const buffer = new ArrayBuffer(HEADER_BYTES + 4);
  const view = new DataView(buffer);
  writeHeader(view, version, MessageType.ACK, 4);
  view.setUint32(HEADER_BYTES, frameNumber >>> 0, true);
  return buffer;
}

// Checks the 12-byte header of a whole message of the version spoken and returns its type.
export function readHeader(view, version = PROTOCOL_VERSION) {
  if (view.byteLength < HEADER_BYTES) throw new ProtocolError(`message of ${view.byteLength} bytes is shorter than the header`);
  const magic = view.getUint32(0, true);
  if (magic !== MAGIC) throw new ProtocolError(`bad magic 0x${magic.toString(16)}`);
  const messageVersion = view.getUint16(4, true);
  if (messageVersion !== version) throw new ProtocolError(`protocol version ${messageVersion}, expected ${version}`);
  const type = view.getUint16(6, true);
  const lastType = version >= 2 ? MessageType.PACKED : MessageType.ACK;
  if (type < MessageType.HELLO || type > lastType) throw new ProtocolError(`unknown message type ${type}`);
  const payload = view.getUint32(8, true);
  if (payload > MAX_PAYLOAD_BYTES) throw new ProtocolError(`payload of ${payload} bytes is over the 64 MiB limit`);
  if (payload !== view.byteLength - HEADER_BYTES) {
    throw new ProtocolError(`header announces ${payload} payload bytes but the message carries ${view.byteLength - HEADER_BYTES}`);
  }
  return type;
}

// Bounds-checked sequential reader over one message's payload.
export class PayloadReader {
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
  // count little-endian values into a new typed array (endianness-safe, once per connection).
  u32Array(count, field) {
    this.need(4 * count, field);
    const out = new Uint32Array(count);
    for (let i = 0; i < count; ++i, this.offset += 4) out[i] = this.view.getUint32(this.offset, true);
    return out;
  }
  f32Array(count, field) {
    this.need(4 * count, field);
    const out = new Float32Array(count);
    for (let i = 0; i < count; ++i, this.offset += 4) out[i] = this.view.getFloat32(this.offset, true);
    return out;
  }
  string(field) {
    const length = this.u16(`${field} length`);
    return utf8.decode(this.bytes(length, field));
  }
  skip(count, field) { this.need(count, field); this.offset += count; }
  expectEnd() {
    if (this.offset !== this.view.byteLength) {
      throw new ProtocolError(`${this.what} has ${this.view.byteLength - this.offset} unexpected trailing bytes`);
    }
  }
}

const utf8 = new TextDecoder('utf-8', { fatal: false });

function encodingOf(value, what) {
  if (value >= ENCODING_NAMES.length) throw new ProtocolError(`${what} names unknown encoding ${value}`);
  return value;
}

// The compressed vertex order must list every vertex exactly once.
function checkPermutation(order, vertexCount) {
  if (order.length === 0) return;
  const seen = new Uint8Array(vertexCount);
  for (let i = 0; i < order.length; ++i) {
    const v = order[i];
    if (v >= vertexCount) throw new ProtocolError(`MeshInfo compressed vertex order names vertex ${v} (V = ${vertexCount})`);
    if (seen[v]) throw new ProtocolError(`MeshInfo compressed vertex order names vertex ${v} twice`);
    seen[v] = 1;
  }
}

// MeshInfo: allocated once per connection, so plain arrays are fine here.
export function decodeMeshInfo(view, version = PROTOCOL_VERSION) {
  const r = new PayloadReader(view, 'MeshInfo');
  const vertexCount = r.u32('vertex_count');
  const faceCount = r.u32('face_count');
  const markerCount = r.u32('marker_count');
  const partCount = r.u32('part_count');
  const sourceRateHz = r.f32('source_rate_hz');
  const faces = r.u32Array(3 * faceCount, 'faces');
  for (let i = 0; i < faces.length; ++i) {
    if (faces[i] >= vertexCount) throw new ProtocolError(`MeshInfo face vertex ${faces[i]} is out of range (V = ${vertexCount})`);
  }
  const dominantPart = new Uint8Array(r.bytes(vertexCount, 'dominant parts'));
  const markerTriangleCount = r.u32('marker_triangle_count');
  const markerTriangles = r.u32Array(3 * markerTriangleCount, 'marker triangles');
  for (let i = 0; i < markerTriangles.length; ++i) {
    if (markerTriangles[i] >= markerCount) {
      throw new ProtocolError(`MeshInfo marker triangle index ${markerTriangles[i]} is out of range (M = ${markerCount})`);
    }
  }
  r.need(2 * markerCount, 'marker names');
  const markerNames = new Array(markerCount);
  for (let i = 0; i < markerCount; ++i) markerNames[i] = r.string('marker name');
  const info = { version, vertexCount, faceCount, markerCount, partCount, sourceRateHz, faces, dominantPart, markerTriangles, markerNames,
    subject: '', encoding: Encoding.FLOAT, compressedOrder: new Uint32Array(0) };
  if (version >= 2) {
    info.subject = r.string('subject name');
    info.encoding = encodingOf(r.u32('encoding'), 'MeshInfo');
    const orderCount = r.u32('compressed vertex order count');
    if (orderCount !== 0 && orderCount !== vertexCount) {
      throw new ProtocolError(`MeshInfo has a compressed vertex order of ${orderCount} for ${vertexCount} vertices`);
    }
    if (info.encoding === Encoding.COMPRESSED && orderCount !== vertexCount) {
      throw new ProtocolError('MeshInfo serves the compressed encoding without a compressed vertex order');
    }
    info.compressedOrder = r.u32Array(orderCount, 'compressed vertex order');
    checkPermutation(info.compressedOrder, vertexCount);
  }
  r.expectEnd();
  return info;
}

export function decodeStatus(view, version = PROTOCOL_VERSION) {
  const r = new PayloadReader(view, 'Status');
  const state = r.u32('source state');
  const lastState = version >= 2 ? SourceState.REFUSED : SourceState.FINISHED;
  if (state > lastState) throw new ProtocolError(`Status has unknown source state ${state}`);
  const sourceRateHz = r.f32('source_rate_hz');
  const framesReceived = r.u64('frames received');
  const framesPublished = r.u64('frames published');
  const detail = r.string('detail');
  const status = { state, stateName: SOURCE_STATE_NAMES[state], sourceRateHz, framesReceived, framesPublished, detail,
    subject: '', subjectPresent: true, encoding: -1 };
  if (version >= 2) {
    status.subject = r.string('subject name');
    const present = r.u32('subject present');
    if (present > 1) throw new ProtocolError(`Status subject presence ${present} is not 0 or 1`);
    status.subjectPresent = present === 1;
    status.encoding = encodingOf(r.u32('encoding'), 'Status');
  }
  r.expectEnd();
  return status;
}

// The fixed fields of a Frame and where its blocks are, read in place into a reused object (no
// allocation per frame).
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
    // Version 2 timecode (valid with FrameFlags.TIMECODE).
    this.timecode = { hours: 0, minutes: 0, seconds: 0, frames: 0, subframe: 0, subframesPerFrame: 0, rateHz: 0, flags: 0 };
    // Byte offsets into the message, and sizes, of the blocks (0 bytes: absent).
    this.positionsAt = 0;
    this.positionsBytes = 0;
    this.normalsAt = 0;
    this.normalsBytes = 0;
    this.markersAt = 0;
  }

  // Reads the fixed fields, checks the flags, and finds the blocks, which must fill the message
  // exactly.
  read(view, version = PROTOCOL_VERSION) {
    const fixed = HEADER_BYTES + FRAME_FIXED_BYTES + (version >= 2 ? TIMECODE_BYTES : 0);
    if (view.byteLength < fixed) throw new ProtocolError(`Frame of ${view.byteLength} bytes is shorter than its fixed fields`);
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
    if (version >= 2) {
      const t = this.timecode;
      t.hours = view.getUint8(o); t.minutes = view.getUint8(o + 1); t.seconds = view.getUint8(o + 2); t.frames = view.getUint8(o + 3);
      t.subframe = view.getUint16(o + 4, true);
      t.subframesPerFrame = view.getUint16(o + 6, true);
      t.rateHz = view.getFloat32(o + 8, true);
      t.flags = view.getUint32(o + 12, true);
      o += TIMECODE_BYTES;
    }
    this.checkFlags(version);
    this.findBlocks(view, o);
  }

  // The combinations the spec rules out, as the daemon's own decoder checks them.
  checkFlags(version) {
    const f = this.flags;
    const n = this.frameNumber;
    if ((f & ~FRAME_FLAGS_OF_VERSION[version]) !== 0) throw new ProtocolError(`Frame ${n} has unknown flags 0x${f.toString(16)}`);
    const encodings = ((f & FrameFlags.QUANTISED) !== 0) + ((f & FrameFlags.COMPRESSED) !== 0) + ((f & FrameFlags.PARAMETERS) !== 0);
    const positions = (f & FrameFlags.NO_POSITIONS) === 0;
    let problem = '';
    if (encodings > 1) problem = 'more than one encoding of the positions';
    else if (!positions && (this.vertexCount !== 0 || encodings !== 0)) problem = 'positions with "no positions"';
    else if (!positions && (f & FrameFlags.NORMALS)) problem = 'normals without positions';
    else if ((f & FrameFlags.PARAMETERS) && (f & FrameFlags.NORMALS)) problem = 'normals with parameters';
    else if ((f & FrameFlags.PARAMETERS) && this.vertexCount !== 0) problem = `${this.vertexCount} vertices with parameters`;
    else if ((f & FrameFlags.KEY) && !(f & FrameFlags.COMPRESSED)) problem = 'the key frame flag without compression';
    else if (!(f & FrameFlags.MARKERS) && this.markerCount !== 0) problem = `${this.markerCount} markers without the markers flag`;
    if (problem) throw new ProtocolError(`Frame ${n} has ${problem}`);
  }

  findBlocks(view, start) {
    const f = this.flags;
    const V = this.vertexCount;
    const end = view.byteLength;
    const counted = (at, headerBytes, what) => {
      if (at + headerBytes + 4 > end) throw new ProtocolError(`Frame ${this.frameNumber} truncated in its ${what}`);
      const coded = view.getUint32(at + headerBytes, true);
      return headerBytes + 4 + coded + paddingTo4(coded);
    };
    let o = start;
    this.positionsAt = this.normalsAt = this.markersAt = 0;
    this.positionsBytes = this.normalsBytes = 0;
    if (f & FrameFlags.PARAMETERS) {
      if (o + 8 > end) throw new ProtocolError(`Frame ${this.frameNumber} truncated in its parameters`);
      const parts = view.getUint32(o, true);
      const members = view.getUint32(o + 4, true);
      this.positionsBytes = 8 + PART_PARAMETER_BYTES * parts + 12 * members;
    } else if (f & FrameFlags.COMPRESSED) {
      this.positionsBytes = counted(o, COMPRESSED_POSITIONS_HEADER_BYTES - 4, 'compressed positions');
    } else if ((f & FrameFlags.NO_POSITIONS) === 0) {
      const quantisedBlock = 6 * V + paddingTo4(6 * V);
      this.positionsBytes = (f & FrameFlags.QUANTISED) ? 24 + quantisedBlock : 12 * V;
      if (f & FrameFlags.NORMALS) this.normalsBytes = (f & FrameFlags.QUANTISED) ? quantisedBlock : 12 * V;
    }
    this.positionsAt = o;
    o += this.positionsBytes;
    if ((f & FrameFlags.COMPRESSED) && (f & FrameFlags.NORMALS)) this.normalsBytes = counted(o, 0, 'compressed normals');
    this.normalsAt = o;
    o += this.normalsBytes;
    this.markersAt = o;
    if (f & FrameFlags.MARKERS) o += 13 * this.markerCount + paddingTo4(this.markerCount);
    if (o !== end) throw new ProtocolError(`Frame ${this.frameNumber} is ${end} bytes, its flags and counts need ${o}`);
  }
}

// Decodes the float or quantised positions and normals and the markers of a Frame whose header
// was read by FrameHeader.read into the caller's preallocated arrays (compressed and parameter
// positions are decoded elsewhere). Returns which arrays were written, as Decoded bits.
export function decodeFrameArrays(view, header, out) {
  const V = header.vertexCount;
  const f = header.flags;
  const quantised = (f & FrameFlags.QUANTISED) !== 0;
  const plain = (f & (FrameFlags.NO_POSITIONS | FrameFlags.PARAMETERS | FrameFlags.COMPRESSED)) === 0;
  let written = 0;
  if (plain) {
    if (V !== out.positions.length / 3) throw new ProtocolError(`Frame ${header.frameNumber} has ${V} vertices, MeshInfo said ${out.positions.length / 3}`);
    const p = out.positions;
    let o = header.positionsAt;
    if (quantised) {
      const ox = view.getFloat32(o, true), oy = view.getFloat32(o + 4, true), oz = view.getFloat32(o + 8, true);
      const sx = view.getFloat32(o + 12, true), sy = view.getFloat32(o + 16, true), sz = view.getFloat32(o + 20, true);
      o += 24;
      for (let i = 0; i < 3 * V; i += 3, o += 6) {
        p[i] = ox + view.getUint16(o, true) * sx;
        p[i + 1] = oy + view.getUint16(o + 2, true) * sy;
        p[i + 2] = oz + view.getUint16(o + 4, true) * sz;
      }
    } else {
      for (let i = 0; i < 3 * V; ++i, o += 4) p[i] = view.getFloat32(o, true);
    }
    written |= Decoded.POSITIONS;
    if (f & FrameFlags.NORMALS) {
      const n = out.normals;
      o = header.normalsAt;
      if (quantised) {
        for (let i = 0; i < 3 * V; ++i, o += 2) n[i] = view.getInt16(o, true) / 32767;
      } else {
        for (let i = 0; i < 3 * V; ++i, o += 4) n[i] = view.getFloat32(o, true);
      }
      written |= Decoded.NORMALS;
    }
  }
  if (f & FrameFlags.MARKERS) {
    const M = header.markerCount;
    if (M !== out.markerStatus.length) throw new ProtocolError(`Frame ${header.frameNumber} has ${M} markers, MeshInfo said ${out.markerStatus.length}`);
    const m = out.markers;
    let o = header.markersAt;
    for (let i = 0; i < 3 * M; ++i, o += 4) m[i] = view.getFloat32(o, true);
    const s = out.markerStatus;
    for (let i = 0; i < M; ++i, ++o) s[i] = view.getUint8(o);
    written |= Decoded.MARKERS;
  }
  return written;
}
