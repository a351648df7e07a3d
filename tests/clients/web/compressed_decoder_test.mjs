// The compressed decoder (clients/web/src/compressed_decoder.js) on frames coded by the
// meshoptimizer package's own encoder as the spec describes them: key and delta frames decode to
// the grid points they were coded to, in the mesh's order, normals within the spec's 1.5
// degrees; a delta of a key not held is skipped; bytes the codec refuses are a ProtocolError.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { createRequire } from 'node:module';
import path from 'node:path';
import { readFixture, patched, repoRoot, webSource } from './support/fixtures.mjs';
import { worstAngleDegrees } from './support/comparisons.mjs';
import { makeSheetSubject, makeParameters, evaluateAsSpecified, vertexNormals, encodeCompressedFrame, onGrid } from './support/spec_stream.mjs';

const protocol = await import(webSource('protocol.js'));
const { CompressedVertexDecoder, compressedDecoderReady } = await import(webSource('compressed_decoder.js'));
const requireWeb = createRequire(path.join(repoRoot, 'clients/web/package.json'));
const { MeshoptEncoder } = await import(requireWeb.resolve('meshoptimizer/encoder'));
await Promise.all([compressedDecoderReady, MeshoptEncoder.ready]);

const subject = makeSheetSubject();
const V = subject.vertexCount;
// A spatial order other than the identity: reversed columns, rows interleaved.
const order = Uint32Array.from({ length: V }, (_, i) => (i * 37) % V);
const frames = [0, 0.1, 0.2, 0.3].map((t) => {
  const positions = Float32Array.from(evaluateAsSpecified(subject, makeParameters(subject, t)));
  return { positions, normals: Float32Array.from(vertexNormals(positions, subject.faces)) };
});

function header(buffer) {
  const h = new protocol.FrameHeader();
  h.read(new DataView(buffer));
  return h;
}

function decodeInto(decoder, buffer) {
  const view = new DataView(buffer);
  const h = header(buffer);
  if (!decoder.accept(view, h)) return null;
  const out = { positions: new Float32Array(3 * V), normals: new Float32Array(3 * V) };
  assert.equal(decoder.decode(view, h, out.positions, out.normals), true);
  return out;
}

test('key and delta frames decode to their grid points, in mesh order', () => {
  const decoder = new CompressedVertexDecoder(V, order);
  const key = encodeCompressedFrame(MeshoptEncoder, 100, frames[0].positions, frames[0].normals, order);
  let grid = key.key;
  for (let f = 0; f < frames.length; ++f) {
    const coded = f === 0 ? key : encodeCompressedFrame(MeshoptEncoder, 100 + f, frames[f].positions, frames[f].normals, order, grid);
    const out = decodeInto(decoder, coded.buffer);
    assert.ok(out, `frame ${f} decodes`);
    assert.deepEqual(out.positions, Float32Array.from(onGrid(frames[f].positions, grid)), `frame ${f} positions`);
    const halfStep = Math.max(...grid.step) / 2;
    const worst = Math.max(...out.positions.map((x, i) => Math.abs(x - frames[f].positions[i])));
    assert.ok(worst <= halfStep * 1.001, `frame ${f}: ${worst} mm from the input, half a step is ${halfStep}`);
    const angle = worstAngleDegrees(out.normals, frames[f].normals);
    assert.ok(angle < 1.5, `frame ${f}: normals ${angle} degrees off`);
  }
});

test('a delta of a key the decoder does not hold is skipped until the next key', () => {
  const decoder = new CompressedVertexDecoder(V, order);
  const key = encodeCompressedFrame(MeshoptEncoder, 200, frames[0].positions, frames[0].normals, order);
  const delta = encodeCompressedFrame(MeshoptEncoder, 201, frames[1].positions, frames[1].normals, order, key.key);
  assert.equal(decodeInto(decoder, delta.buffer), null, 'joined late: no key yet');
  assert.ok(decodeInto(decoder, key.buffer));
  const otherKey = { ...key.key, frameNumber: 150 };
  const stale = encodeCompressedFrame(MeshoptEncoder, 202, frames[1].positions, frames[1].normals, order, otherKey);
  assert.equal(decodeInto(decoder, stale.buffer), null, 'a delta of another key');
  assert.ok(decodeInto(decoder, delta.buffer), 'a delta of the key held');
});

test('bytes the codec refuses, a bad grid or a wrong vertex count are ProtocolErrors', () => {
  const refused = (decoder, buffer, pattern, what) => assert.throws(() => decodeInto(decoder, buffer),
    (error) => error instanceof protocol.ProtocolError && pattern.test(error.message) && !/\n/.test(error.message), what);
  const key = encodeCompressedFrame(MeshoptEncoder, 300, frames[0].positions, frames[0].normals, order);
  const codedAt = 80 + 32; // the positions' coded bytes, after the fixed fields and the block's header
  const damaged = patched(key.buffer, (v) => { for (let i = 0; i < 24; ++i) v.setUint8(codedAt + i, 0xff); });
  refused(new CompressedVertexDecoder(V, order), damaged, /vertex codec refused the compressed positions/, 'damaged positions');
  const noStep = patched(key.buffer, (v) => v.setFloat32(80 + 16, 0, true));
  refused(new CompressedVertexDecoder(V, order), noStep, /origin or step/, 'a step of 0');
  const nanOrigin = patched(key.buffer, (v) => v.setFloat32(80 + 4, NaN, true));
  refused(new CompressedVertexDecoder(V, order), nanOrigin, /origin or step/, 'a NaN origin');
  refused(new CompressedVertexDecoder(V - 1, order.subarray(0, V - 1)), key.buffer, /96 compressed vertices, MeshInfo said 95/, 'a vertex count that does not match');

  // The golden frame's coded bytes are placeholders (it pins the framing): the codec refuses them.
  const golden = readFixture('frame_v2_compressed.bin');
  refused(new CompressedVertexDecoder(3, Uint32Array.from([2, 0, 1])), golden, /vertex codec refused/, 'placeholder bytes');

  // A damaged delta leaves the key held: the next good delta still decodes.
  const decoder = new CompressedVertexDecoder(V, order);
  assert.ok(decodeInto(decoder, key.buffer));
  const delta = encodeCompressedFrame(MeshoptEncoder, 301, frames[1].positions, frames[1].normals, order, key.key);
  refused(decoder, patched(delta.buffer, (v) => { for (let i = 0; i < 24; ++i) v.setUint8(codedAt + i, 0xff); }), /refused/, 'damaged delta');
  assert.ok(decodeInto(decoder, delta.buffer));
});
