// The subscriber protocol's Packed message (docs/subscriber-protocol.md, type 7): a MeshInfo or
// Model deflated, asked for with Hello's Wants.PACKED so that a joining page waits for 0.84 MB
// instead of 2.4 MB. unpackMessage() gives back the plain message (header and payload) that the
// rest of the page reads as ever. Inflating is asynchronous here (DecompressionStream), so
// StreamConnection holds the messages after a Packed one until it is unpacked.
import { HEADER_BYTES, MAX_PAYLOAD_BYTES, MessageType, PROTOCOL_VERSION, ProtocolError, writeHeader } from './protocol.js';

// A packed type's fixed counts, kept before the deflated stream: their bytes, and where among
// them the N of the 3N-value array that follows them is.
const HEADS = new Map([[MessageType.MESH_INFO, { bytes: 20, countAt: 4, countName: 'face count' }],
  [MessageType.MODEL, { bytes: 16, countAt: 0, countName: 'vertex count' }]]);
const FIELD_BYTES = 8;
const MOST_INFLATED_PER_BYTE = 1032; // deflate's longest match in its shortest code

function adler32(bytes) {
  let a = 1;
  let b = 0;
  for (let i = 0; i < bytes.length;) {
    const end = Math.min(bytes.length, i + 5552); // the most bytes before b can pass 2^32
    for (; i < end; ++i) {
      a += bytes[i];
      b += a;
    }
    a %= 65521;
    b %= 65521;
  }
  return ((b << 16) | a) >>> 0;
}

// The plain message a whole Packed message (header included) holds. Throws ProtocolError.
export async function unpackMessage(buffer, maxPayload = MAX_PAYLOAD_BYTES) {
  const bytes = new Uint8Array(buffer, HEADER_BYTES);
  if (bytes.length < FIELD_BYTES) throw new ProtocolError(`Packed: truncated (${bytes.length} of 8 bytes of its fields)`);
  const view = new DataView(buffer, HEADER_BYTES);
  const type = view.getUint16(0, true);
  const reserved = view.getUint16(2, true);
  const size = view.getUint32(4, true);
  const head = HEADS.get(type);
  if (!head) throw new ProtocolError(`Packed: holds a message of type ${type} (only MeshInfo and Model are packed)`);
  if (reserved !== 0) throw new ProtocolError(`Packed: reserved field is ${reserved}, not 0`);
  if (size > maxPayload) throw new ProtocolError(`Packed: unpacked size ${size} over the limit of ${maxPayload}`);
  if (bytes.length < FIELD_BYTES + head.bytes) throw new ProtocolError('Packed: truncated in its counts');
  if (size < head.bytes) throw new ProtocolError(`Packed: unpacked size ${size} shorter than its counts`);
  const stream = bytes.subarray(FIELD_BYTES + head.bytes);
  const restBytes = size - head.bytes;
  if (restBytes > stream.length * MOST_INFLATED_PER_BYTE + 64) {
    throw new ProtocolError(`Packed: ${stream.length} deflated bytes cannot make ${restBytes}`);
  }
  const count = 3 * view.getUint32(FIELD_BYTES + head.countAt, true);
  if (4 * count > restBytes) {
    throw new ProtocolError(`Packed: its ${head.countName} needs ${4 * count} bytes, the unpacked size leaves ${restBytes}`);
  }
  const out = new Uint8Array(HEADER_BYTES + size);
  const outView = new DataView(out.buffer);
  writeHeader(outView, PROTOCOL_VERSION, type, size);
  out.set(bytes.subarray(FIELD_BYTES, FIELD_BYTES + head.bytes), HEADER_BYTES);
  let at = HEADER_BYTES + head.bytes;
  const reader = new Blob([stream]).stream().pipeThrough(new DecompressionStream('deflate')).getReader();
  try {
    for (;;) {
      const { value, done } = await reader.read();
      if (done) break;
      if (at + value.length > out.length) throw new ProtocolError(`Packed: the deflated stream makes more than the unpacked size ${restBytes}`);
      out.set(value, at);
      at += value.length;
    }
  } catch (error) {
    reader.cancel().catch(() => {});
    if (error instanceof ProtocolError) throw error;
    throw new ProtocolError(`Packed: the deflated stream is corrupt (${String(error.message).split('\n')[0]})`);
  }
  if (at !== out.length) {
    throw new ProtocolError(`Packed: the deflated stream makes ${at - HEADER_BYTES - head.bytes} bytes, the unpacked size says ${restBytes}`);
  }
  // The stream ends with the Adler-32 of what it makes (zlib checks it inside the stream): a
  // DecompressionStream that ignores bytes after the stream (Node's) would otherwise take them.
  const trailer = new DataView(stream.buffer, stream.byteOffset + stream.length - 4, 4).getUint32(0, false);
  if (stream.length < 6 || trailer !== adler32(out.subarray(HEADER_BYTES + head.bytes))) {
    throw new ProtocolError(`Packed: ${stream.length} bytes that are not one deflated stream (bytes after it?)`);
  }
  // The array after the counts: its four byte planes joined, then each value plus the value
  // three before it (modulo 2^32, as the differences were taken).
  const start = HEADER_BYTES + head.bytes;
  const planes = out.slice(start, start + 4 * count);
  for (let i = 0; i < count; ++i) {
    let value = (planes[i] | (planes[count + i] << 8) | (planes[2 * count + i] << 16) | (planes[3 * count + i] << 24)) >>> 0;
    if (i >= 3) value = (value + outView.getUint32(start + 4 * (i - 3), true)) >>> 0;
    outView.setUint32(start + 4 * i, value, true);
  }
  return out.buffer;
}
