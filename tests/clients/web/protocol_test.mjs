// The page's protocol decoder (clients/web/src/protocol.js) on the golden messages of both
// versions, which were written from the spec independently of encoder and decoder, and on
// damaged ones: every bad message is a ProtocolError with a one-line reason, never another error.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { readFixture, resized, patched, random, webSource } from './support/fixtures.mjs';

const protocol = await import(webSource('protocol.js'));
const { ProtocolError, FrameHeader, MessageType, Wants, Encoding, FrameFlags } = protocol;

const close = (actual, expected, what) => assert.ok(
  actual.length === expected.length && expected.every((x, i) => Math.abs(actual[i] - x) <= 1e-4 * Math.max(1, Math.abs(x))),
  `${what}: ${Array.from(actual)} != ${expected}`);

// Decodes a whole message of the version as the page's worker would.
function decode(buffer, version = 2) {
  const view = new DataView(buffer);
  const type = protocol.readHeader(view, version);
  if (type === MessageType.MESH_INFO) return protocol.decodeMeshInfo(view, version);
  if (type === MessageType.STATUS) return protocol.decodeStatus(view, version);
  if (type === MessageType.FRAME) {
    const header = new FrameHeader();
    header.read(view, version);
    return header;
  }
  return type;
}

function rejects(buffer, pattern, what, version = 2) {
  assert.throws(() => decode(buffer, version), (error) => {
    assert.ok(error instanceof ProtocolError, `${what}: ${error.name}: ${error.message}`);
    assert.doesNotMatch(error.message, /\n/, `${what}: the reason is one line`);
    if (pattern) assert.match(error.message, pattern, what);
    return true;
  }, what);
}

test('version 1 golden messages', () => {
  assert.deepEqual(new Uint8Array(protocol.encodeHello(Wants.NORMALS | Wants.MARKERS, { version: 1 })), new Uint8Array(readFixture('hello.bin')));
  const info = decode(readFixture('mesh_info.bin'), 1);
  assert.equal(info.vertexCount, 4);
  assert.equal(info.sourceRateHz, 120);
  assert.deepEqual(Array.from(info.faces), [0, 1, 2, 0, 2, 3]);
  assert.deepEqual(Array.from(info.dominantPart), [0, 1, 255, 1]);
  assert.deepEqual(Array.from(info.markerTriangles), [0, 1, 2]);
  assert.deepEqual(info.markerNames, ['LSHO', 'RSHO', 'C7']);

  for (const name of ['frame_float.bin', 'frame_quantised.bin', 'frame_markers_only.bin']) {
    const buffer = readFixture(name);
    const header = decode(buffer, 1);
    assert.equal(header.frameNumber, 1234, name);
    assert.ok(Math.abs(header.receiveTimeNs - 1.7e18) < 1e3, `${name}: receive time ${header.receiveTimeNs}`);
    assert.equal(header.markersFilled, 3, name);
    assert.equal(header.framesDroppedPipeline, 7, name);
    assert.equal(header.framesDroppedSubscriber, 2, name);
    const vertexCount = name === 'frame_markers_only.bin' ? 0 : 3;
    const out = { positions: new Float32Array(3 * vertexCount), normals: new Float32Array(3 * vertexCount),
      markers: new Float32Array(6), markerStatus: new Uint8Array(2) };
    protocol.decodeFrameArrays(new DataView(buffer), header, out);
    if (vertexCount > 0) {
      close(out.positions, [0, 100, 5, 65535, 131170, 5, 0, 2100, 5], `${name} positions`);
      close(out.normals, [1, 0, 0, 0, -1, 0, 0, 0, 1], `${name} normals`);
    }
    close(out.markers, [1.5, 2.5, 3.5, -4.0, 5.0, 6.25], `${name} markers`);
    assert.deepEqual(Array.from(out.markerStatus), [0, 2], `${name} marker status`);
  }
  const status = decode(readFixture('status.bin'), 1);
  assert.equal(status.stateName, 'disconnected');
  assert.equal(status.framesReceived, 1000);
  assert.equal(status.detail, 'vicon 127.0.0.1:801: connection refused');
  // A version 1 message is not what a version 2 page reads.
  rejects(readFixture('status.bin'), /protocol version 1, expected 2/, 'v1 Status on a v2 connection');
});

test('version 2 golden messages', () => {
  const hello = protocol.encodeHello(Wants.NORMALS | Wants.MARKERS | Wants.PACED, { encoding: Encoding.PARAMETERS, subject: 'Actor2', token: 'stage-token' });
  assert.deepEqual(new Uint8Array(hello), new Uint8Array(readFixture('hello_v2.bin')));
  assert.deepEqual(new Uint8Array(protocol.encodeAck(123456, 1)), new Uint8Array(readFixture('ack.bin')));
  assert.throws(() => protocol.encodeHello(Wants.QUANTISED), ProtocolError, 'version 2 names the encoding, not wants bit 1');

  const info = decode(readFixture('mesh_info_v2.bin'));
  assert.equal(info.vertexCount, 4);
  assert.deepEqual(info.markerNames, ['LSHO', 'RSHO', 'C7']);
  assert.equal(info.subject, 'Actor2');
  assert.equal(info.encoding, Encoding.COMPRESSED);
  assert.deepEqual(Array.from(info.compressedOrder), [2, 0, 3, 1]);

  const status = decode(readFixture('status_v2.bin'));
  assert.equal(status.stateName, 'refused');
  assert.equal(status.detail, 'no subject "Actor3" (subjects: Actor1, Actor2)');
  assert.equal(status.subject, 'Actor3');
  assert.equal(status.subjectPresent, false);
  assert.equal(status.encoding, Encoding.FLOAT);

  const floatFrame = readFixture('frame_v2_float.bin');
  const header = decode(floatFrame);
  assert.equal(header.flags, FrameFlags.MARKERS | FrameFlags.TIMECODE);
  assert.deepEqual({ ...header.timecode, rateHz: Math.round(header.timecode.rateHz * 100) },
    { hours: 10, minutes: 20, seconds: 30, frames: 12, subframe: 1, subframesPerFrame: 5, rateHz: 2997, flags: 1 });
  const out = { positions: new Float32Array(9), normals: new Float32Array(9), markers: new Float32Array(6), markerStatus: new Uint8Array(2) };
  protocol.decodeFrameArrays(new DataView(floatFrame), header, out);
  close(out.positions, [0, 100, 5, 65535, 131170, 5, 0, 2100, 5], 'v2 float positions');
  close(out.markers, [1.5, 2.5, 3.5, -4.0, 5.0, 6.25], 'v2 markers');

  const parameters = decode(readFixture('frame_v2_parameters.bin'));
  assert.equal(parameters.flags, FrameFlags.MARKERS | FrameFlags.PARAMETERS);
  assert.equal(parameters.positionsAt, 12 + 52 + 16);
  assert.equal(parameters.positionsBytes, 8 + 160 + 24);
  assert.equal(parameters.markersAt, parameters.positionsAt + parameters.positionsBytes);

  const compressed = decode(readFixture('frame_v2_compressed.bin'));
  assert.equal(compressed.flags, FrameFlags.NORMALS | FrameFlags.COMPRESSED | FrameFlags.KEY);
  assert.equal(compressed.positionsBytes, 32 + 8);
  assert.equal(compressed.normalsAt, compressed.positionsAt + 40);
  assert.equal(compressed.normalsBytes, 4 + 8);
});

const V2_FIXTURES = ['mesh_info_v2.bin', 'status_v2.bin', 'frame_v2_float.bin', 'frame_v2_parameters.bin', 'frame_v2_compressed.bin'];

test('a truncated or oversized message is rejected, at every length', () => {
  for (const name of V2_FIXTURES) {
    const buffer = readFixture(name);
    for (let length = 0; length < buffer.byteLength; ++length) {
      rejects(buffer.slice(0, length), /shorter than the header|payload bytes/, `${name} cut to ${length} bytes`);
      if (length >= 12) rejects(resized(buffer, length), null, `${name} cut to ${length} bytes, header fixed`);
    }
    rejects(resized(buffer, buffer.byteLength + 4), /trailing|need|bytes/, `${name} with 4 extra bytes`);
  }
});

test('another magic, version, type or a payload over the limit is rejected', () => {
  const buffer = readFixture('frame_v2_float.bin');
  rejects(patched(buffer, (v) => v.setUint8(0, 0x58)), /magic/, 'bad magic');
  rejects(patched(buffer, (v) => v.setUint16(4, 1, true)), /version 1, expected 2/, 'version 1');
  rejects(patched(buffer, (v) => v.setUint16(4, 3, true)), /version 3/, 'version 3');
  rejects(patched(buffer, (v) => v.setUint16(6, 8, true)), /unknown message type 8/, 'type 8');
  rejects(patched(readFixture('status.bin'), (v) => v.setUint16(6, MessageType.PACKED, true)), /unknown message type 7/, 'a Packed message in version 1', 1);
  rejects(patched(readFixture('status.bin'), (v) => v.setUint16(6, MessageType.MODEL, true)), /unknown message type 6/, 'a Model in version 1', 1);
  rejects(patched(buffer, (v) => v.setUint32(8, 64 * 1024 * 1024 + 1, true)), /over the 64 MiB limit/, 'payload over the limit');
});

test('an inconsistent MeshInfo or Frame is rejected with its reason', () => {
  const info = readFixture('mesh_info_v2.bin');
  const orderAt = info.byteLength - 16; // u32[4] order at the end
  rejects(patched(info, (v) => v.setUint32(orderAt + 4, 4, true)), /names vertex 4/, 'order index past V');
  rejects(patched(info, (v) => v.setUint32(orderAt + 4, 2, true)), /names vertex 2 twice/, 'order not a permutation');
  rejects(patched(info, (v) => v.setUint32(12 + 20, 9, true)), /face vertex 9 is out of range/, 'face index past V');
  rejects(patched(info, (v) => v.setUint32(orderAt - 8, 7, true)), /unknown encoding 7/, 'encoding 7');

  const frame = readFixture('frame_v2_parameters.bin');
  const flagsAt = 16;
  const flags = new DataView(frame).getUint32(flagsAt, true);
  rejects(patched(frame, (v) => v.setUint32(flagsAt, flags | 0x100, true)), /unknown flags/, 'flag bit 8');
  rejects(patched(frame, (v) => v.setUint32(flagsAt, flags | FrameFlags.NORMALS, true)), /normals with parameters/, 'normals with parameters');
  rejects(patched(frame, (v) => v.setUint32(flagsAt, flags | FrameFlags.KEY, true)), /key frame flag/, 'key without compression');
  rejects(patched(frame, (v) => v.setUint32(flagsAt, flags | FrameFlags.QUANTISED, true)), /more than one encoding/, 'two encodings');
  rejects(patched(frame, (v) => v.setUint32(80, 2, true)), /its flags and counts need/, 'a part count the block does not hold');
  rejects(patched(frame, (v) => v.setUint32(12 + 32, 2, true)), /vertices with parameters/, 'vertices with parameters');
  const compressed = readFixture('frame_v2_compressed.bin');
  rejects(patched(compressed, (v) => v.setUint32(80 + 28, 1000, true)), /truncated|need/, 'coded bytes past the message');
});

test('random damage never gives anything but a ProtocolError', () => {
  const next = random(31);
  let rejected = 0;
  let decoded = 0;
  for (const name of V2_FIXTURES) {
    const original = readFixture(name);
    for (let trial = 0; trial < 3000; ++trial) {
      const bytes = new Uint8Array(original.slice(0));
      const flips = 1 + Math.floor(next() * 4);
      for (let f = 0; f < flips; ++f) bytes[12 + Math.floor(next() * (bytes.length - 12))] = Math.floor(next() * 256);
      try {
        const result = decode(bytes.buffer);
        if (result instanceof FrameHeader) {
          // Plain vertices only: compressed ones are the compressed decoder's (its own test).
          const plain = (result.flags & (FrameFlags.COMPRESSED | FrameFlags.PARAMETERS | FrameFlags.NO_POSITIONS)) === 0;
          const values = plain ? 3 * result.vertexCount : 0;
          const out = { positions: new Float32Array(values), normals: new Float32Array(values),
            markers: new Float32Array(3 * result.markerCount), markerStatus: new Uint8Array(result.markerCount) };
          protocol.decodeFrameArrays(new DataView(bytes.buffer), result, out);
        }
        ++decoded;
      } catch (error) {
        assert.ok(error instanceof ProtocolError, `${name} trial ${trial}: ${error.name}: ${error.message}`);
        ++rejected;
      }
    }
  }
  assert.ok(rejected > 1000 && decoded > 100, `rejected ${rejected}, decoded ${decoded}: both paths must be exercised`);
});
