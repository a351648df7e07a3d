// The Model message and the parameter block checks (clients/web/src/model_message.js): the
// golden Model, a small subject's Model written from the spec's tables, and damaged ones, each
// refused with a one-line ProtocolError naming what is wrong.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { readFixture, resized, patched, random, webSource } from './support/fixtures.mjs';
import { makeSheetSubject, makeParameters, encodeModel, encodeParameterFrame } from './support/spec_stream.mjs';

const protocol = await import(webSource('protocol.js'));
const { decodeModel, checkParameterBlock } = await import(webSource('model_message.js'));
const { ProtocolError, FrameHeader } = protocol;

function model(buffer) {
  const view = new DataView(buffer);
  assert.equal(protocol.readHeader(view), protocol.MessageType.MODEL);
  return decodeModel(view);
}

function refused(buffer, pattern, what) {
  assert.throws(() => model(buffer), (error) => {
    assert.ok(error instanceof ProtocolError, `${what}: ${error.name}: ${error.message}`);
    assert.doesNotMatch(error.message, /\n/);
    if (pattern) assert.match(error.message, pattern, what);
    return true;
  }, what);
}

test('the golden Model', () => {
  const m = model(readFixture('model.bin'));
  assert.deepEqual([m.vertexCount, m.partCount, m.memberCount, m.influenceCount], [3, 2, 3, 4]);
  assert.deepEqual(Array.from(m.referenceVertices), [0, 0, 0, 100, 0, 0, 0, 100, 0]);
  assert.deepEqual(Array.from(m.translation), [-10, 0, 0, 0, 0, 0]);
  assert.deepEqual(Array.from(m.rotation.subarray(9)), [0, 1, 0, -1, 0, 0, 0, 0, 1]);
  assert.deepEqual(Array.from(m.boxMin.subarray(0, 3)), [-5, -5, -5]);
  assert.deepEqual(Array.from(m.sigma), [20, 0]);
  assert.deepEqual(Array.from(m.partMembers), [2, 1]);
  assert.deepEqual(Array.from(m.firstMember), [0, 2]);
  assert.deepEqual(Array.from(m.memberReference), [-5, 0, 0, 5, 0, 0, 0, 0, 0]);
  assert.deepEqual(Array.from(m.influenceCounts), [2, 1, 1]);
  assert.deepEqual(Array.from(m.firstInfluence), [0, 2, 3, 4]);
  assert.deepEqual(Array.from(m.influenceParts), [0, 1, 0, 1]);
  assert.deepEqual(Array.from(m.influenceWeights), [0.75, 0.25, 1, 1]);
});

test("a subject's Model written from the spec decodes to the subject", () => {
  const subject = makeSheetSubject();
  const m = model(encodeModel(subject));
  assert.equal(m.vertexCount, subject.vertexCount);
  assert.deepEqual(m.referenceVertices, subject.referenceVertices);
  assert.deepEqual(Array.from(m.partMembers), subject.parts.map((p) => p.members.length));
  assert.deepEqual(Array.from(m.influenceCounts), subject.influences.map((list) => list.length));
  assert.deepEqual(Array.from(m.influenceParts), subject.influences.flatMap((list) => list.map((i) => i.part)));
});

test('a damaged Model is refused with its reason', () => {
  const good = readFixture('model.bin');
  for (let length = 12; length < good.byteLength; ++length) refused(resized(good, length), /Model/, `cut to ${length} bytes`);
  refused(resized(good, good.byteLength + 4), /say \d+ bytes, the payload holds/, 'four bytes too many');
  refused(patched(good, (v) => v.setUint16(4, 1, true)), null, 'a version 1 Model');
  // Offsets in model.bin: counts at 12, v^0 at 28, parts at 64 (80 bytes each), p^0 at 224,
  // influence counts at 260, influence parts at 263, betas at 268.
  refused(patched(good, (v) => v.setUint8(263 + 1, 2)), /influenced by part 2 of 2/, 'an influence of a part past the count');
  refused(patched(good, (v) => v.setUint8(260, 3)), /count 5 influences, the header 4/, 'influence counts that do not add up');
  refused(patched(good, (v) => v.setUint8(261, 0)), /vertex 1 has no influence/, 'a vertex without influence');
  refused(patched(good, (v) => v.setFloat32(268, 0.5, true)), /weights sum to 0.75/, 'weights that do not sum to 1');
  refused(patched(good, (v) => v.setFloat32(28, NaN, true)), /not finite/, 'a reference vertex NaN');
  refused(patched(good, (v) => v.setFloat32(64, 2, true)), /not orthonormal/, 'a reference rotation that is not one');
  refused(patched(good, (v) => v.setFloat32(64 + 72, -1, true)), /negative dilation/, 'a negative sigma');
  refused(patched(good, (v) => v.setFloat32(64 + 48, 9, true)), /empty box on axis 0/, 'an empty box');
  refused(patched(good, (v) => v.setUint32(64 + 76, 0, true)), /has no members/, 'a part without members');
  refused(patched(good, (v) => v.setUint32(64 + 80 + 76, 2, true)), /parts count 4 members, the header 3/, 'member counts that do not add up');
  refused(patched(good, (v) => v.setUint32(16, 1000000, true)), /say \d+ bytes/, 'a part count the payload does not hold');

  const next = random(6);
  for (let trial = 0; trial < 3000; ++trial) {
    const bytes = new Uint8Array(good.slice(0));
    for (let f = 0; f < 1 + trial % 3; ++f) bytes[12 + Math.floor(next() * (bytes.length - 12))] = Math.floor(next() * 256);
    try {
      model(bytes.buffer);
    } catch (error) {
      assert.ok(error instanceof ProtocolError, `trial ${trial}: ${error.name}: ${error.message}`);
    }
  }
});

test("a Frame's parameters are checked against the Model", () => {
  const subject = makeSheetSubject();
  const m = model(encodeModel(subject));
  const check = (buffer) => {
    const view = new DataView(buffer);
    const header = new FrameHeader();
    header.read(view);
    checkParameterBlock(view, header, m);
  };
  const parameters = makeParameters(subject, 0.3);
  check(encodeParameterFrame(7, parameters));

  const fails = (buffer, pattern, what) => assert.throws(() => check(buffer), (error) => error instanceof ProtocolError && pattern.test(error.message), what);
  const threeParts = { ...parameters, parts: [...parameters.parts, parameters.parts[0]] };
  fails(encodeParameterFrame(8, threeParts), /parameters of 3 parts and 9 members, the Model 2 and 9/, 'a part count that does not match');
  const fewerWeights = { ...parameters, weights: parameters.weights.subarray(0, 24) };
  fails(encodeParameterFrame(9, fewerWeights), /2 parts and 8 members, the Model 2 and 9/, 'a member count that does not match');
  const nan = structuredClone(parameters);
  nan.parts[1].A[4] = NaN;
  fails(encodeParameterFrame(10, nan), /part 1 has a value that is not finite/, 'a NaN in A');
  const infinite = structuredClone(parameters);
  infinite.weights[5] = Infinity;
  fails(encodeParameterFrame(11, infinite), /RBF weight that is not finite/, 'an infinite weight');
  const flagged = patched(encodeParameterFrame(12, parameters), (v) => v.setUint32(80 + 8 + 156, 2, true));
  fails(flagged, /reserved flag bits set \(2\)/, 'a reserved flag bit');
});
