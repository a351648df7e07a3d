// The compressed encoding of a version 2 Frame (docs/subscriber-protocol.md): positions on a
// 16-bit grid fixed from one key frame to the next, key frames coded as they are and the frames
// between as their difference from the key, in MeshInfo's compressed vertex order, with
// meshoptimizer's vertex codec; normals as 8-bit octahedral vectors, every frame on its own.
// Decoded with the meshoptimizer package's decoder (WebAssembly).
import { MeshoptDecoder } from 'meshoptimizer/decoder';
import { COMPRESSED_POSITIONS_HEADER_BYTES, FrameFlags, ProtocolError } from './protocol.js';

const POSITION_VERTEX_BYTES = 8; // u16 x y z 0
const NORMAL_VERTEX_BYTES = 4; // i8 x y of the octahedral map, 127, 0
// In the positions block, the coded byte count follows the key frame number, origin and step.
const CODED_POSITIONS_COUNT_AT = COMPRESSED_POSITIONS_HEADER_BYTES - 4;

// The codec's output is read in place as u16 and i8 arrays, which assumes a little-endian host
// (every browser's); said plainly rather than decoded wrongly elsewhere.
const LITTLE_ENDIAN = new Uint8Array(new Uint16Array([1]).buffer)[0] === 1;

// Resolves once the WebAssembly decoder is compiled; decode only after it.
export const compressedDecoderReady = MeshoptDecoder.ready;

export class CompressedVertexDecoder {
  // order: MeshInfo's compressed vertex order (checked there to be a permutation).
  constructor(vertexCount, order) {
    if (!LITTLE_ENDIAN) throw new Error('the compressed encoding is decoded on little-endian hosts only');
    this.vertexCount = vertexCount;
    this.order = order;
    this.keyQ = new Uint16Array(4 * vertexCount);
    this.hasKey = false;
    this.keyFrameNumber = 0;
    this.origin = new Float32Array(3);
    this.step = new Float32Array(3);
    this.deltaBytes = new Uint8Array(POSITION_VERTEX_BYTES * vertexCount);
    this.delta = new Uint16Array(this.deltaBytes.buffer);
    this.normalBytes = new Uint8Array(NORMAL_VERTEX_BYTES * vertexCount);
    this.octahedral = new Int8Array(this.normalBytes.buffer);
    this.keyBytes = new Uint8Array(this.keyQ.buffer);
  }

  // For every Frame received (checked by FrameHeader.read), in order: a key frame becomes the key
  // at once, so that the frames after it decode even when this one is never shown. Returns
  // whether decode() can then decode this frame: false for a delta of a key this decoder has not
  // seen (it joined late, or the key gave way in the daemon's queue): skip it until a key frame.
  accept(view, header) {
    const n = header.frameNumber;
    if ((header.flags & FrameFlags.COMPRESSED) === 0) throw new ProtocolError(`Frame ${n} is not compressed`);
    if (header.vertexCount !== this.vertexCount) {
      throw new ProtocolError(`Frame ${n} has ${header.vertexCount} compressed vertices, MeshInfo said ${this.vertexCount}`);
    }
    const o = header.positionsAt;
    const keyFrameNumber = view.getUint32(o, true);
    for (let a = 0; a < 3; ++a) {
      const origin = view.getFloat32(o + 4 + 4 * a, true);
      const step = view.getFloat32(o + 16 + 4 * a, true);
      if (!Number.isFinite(origin) || !Number.isFinite(step) || step <= 0) {
        throw new ProtocolError(`Frame ${n}: the grid's origin or step is not a finite positive number`);
      }
    }
    if ((header.flags & FrameFlags.KEY) === 0) return this.hasKey && keyFrameNumber === this.keyFrameNumber;
    this.hasKey = false; // until this key has decoded
    this.decodeCoded(view, o + CODED_POSITIONS_COUNT_AT, this.keyBytes, POSITION_VERTEX_BYTES, undefined, n, 'positions');
    for (let a = 0; a < 3; ++a) {
      this.origin[a] = view.getFloat32(o + 4 + 4 * a, true);
      this.step[a] = view.getFloat32(o + 16 + 4 * a, true);
    }
    this.keyFrameNumber = keyFrameNumber;
    this.hasKey = true;
    return true;
  }

  // Decodes a frame accept() took (and no key came after) into positions and, when the frame
  // has them and `normals` is given, normals: 3 floats per vertex in the mesh's own order.
  // Returns whether normals were written.
  decode(view, header, positions, normals) {
    const V = this.vertexCount;
    const order = this.order;
    const key = this.keyQ;
    const [ox, oy, oz] = this.origin;
    const [sx, sy, sz] = this.step;
    if (header.flags & FrameFlags.KEY) {
      for (let i = 0; i < V; ++i) {
        const out = 3 * order[i];
        positions[out] = ox + key[4 * i] * sx;
        positions[out + 1] = oy + key[4 * i + 1] * sy;
        positions[out + 2] = oz + key[4 * i + 2] * sz;
      }
    } else {
      const n = header.frameNumber;
      this.decodeCoded(view, header.positionsAt + CODED_POSITIONS_COUNT_AT, this.deltaBytes, POSITION_VERTEX_BYTES, undefined, n, 'positions');
      const d = this.delta;
      for (let i = 0; i < V; ++i) {
        const out = 3 * order[i];
        positions[out] = ox + ((key[4 * i] + d[4 * i]) & 0xffff) * sx;
        positions[out + 1] = oy + ((key[4 * i + 1] + d[4 * i + 1]) & 0xffff) * sy;
        positions[out + 2] = oz + ((key[4 * i + 2] + d[4 * i + 2]) & 0xffff) * sz;
      }
    }
    if ((header.flags & FrameFlags.NORMALS) === 0 || !normals) return false;
    this.decodeCoded(view, header.normalsAt, this.normalBytes, NORMAL_VERTEX_BYTES, 'OCTAHEDRAL', header.frameNumber, 'normals');
    const q = this.octahedral;
    for (let i = 0; i < V; ++i) {
      // The filter leaves unit vectors rounded to 8 bits a component: unit again here.
      const x = q[4 * i], y = q[4 * i + 1], z = q[4 * i + 2];
      const length = Math.sqrt(x * x + y * y + z * z);
      const scale = length > 0 ? 1 / length : 0;
      const out = 3 * order[i];
      normals[out] = x * scale;
      normals[out + 1] = y * scale;
      normals[out + 2] = z * scale;
    }
    return true;
  }

  // The codec's stream of V vertices whose byte count is the u32 at countAt, into target.
  decodeCoded(view, countAt, target, vertexBytes, filter, frameNumber, what) {
    const coded = view.getUint32(countAt, true);
    const source = new Uint8Array(view.buffer, view.byteOffset + countAt + 4, coded);
    try {
      MeshoptDecoder.decodeVertexBuffer(target, this.vertexCount, vertexBytes, source, filter);
    } catch (error) {
      throw new ProtocolError(`Frame ${frameNumber}: the vertex codec refused the compressed ${what} (${error.message})`);
    }
  }
}
