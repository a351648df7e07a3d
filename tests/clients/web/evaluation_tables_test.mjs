// The static tables of the GPU evaluation (clients/web/src/evaluation_tables.js): the fans give
// the faces' area-weighted normals on closed, open and non-manifold meshes, and each influence
// holds the clamped reference point and the offset beyond it that eq. 8 needs.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { random, webSource } from './support/fixtures.mjs';
import { makeSheetSubject, encodeModel, vertexNormals } from './support/spec_stream.mjs';

const { buildFans, buildEvaluationTables } = await import(webSource('evaluation_tables.js'));
const protocol = await import(webSource('protocol.js'));
const { decodeModel } = await import(webSource('model_message.js'));

// The unnormalised sum over each vertex's fan, as the normals shader forms it.
function fanNormals(positions, vertexCount, { fanOffsets, fans }) {
  const n = new Float64Array(3 * vertexCount);
  const at = (v, k) => positions[3 * v + k];
  for (let v = 0; v < vertexCount; ++v) {
    for (let e = fanOffsets[v]; e + 1 < fanOffsets[v + 1]; ++e) {
      const a = [0, 1, 2].map((k) => at(fans[e], k) - at(v, k));
      const b = [0, 1, 2].map((k) => at(fans[e + 1], k) - at(v, k));
      n[3 * v] += a[1] * b[2] - a[2] * b[1];
      n[3 * v + 1] += a[2] * b[0] - a[0] * b[2];
      n[3 * v + 2] += a[0] * b[1] - a[1] * b[0];
    }
  }
  for (let v = 0; v < n.length; v += 3) {
    const length = Math.hypot(n[v], n[v + 1], n[v + 2]);
    for (let k = 0; k < 3; ++k) n[v + k] /= length;
  }
  return n;
}

function sameNormals(faces, vertexCount, what) {
  const next = random(vertexCount + faces.length);
  const positions = Float64Array.from({ length: 3 * vertexCount }, () => 100 * next());
  const expected = vertexNormals(positions, faces);
  const actual = fanNormals(positions, vertexCount, buildFans(vertexCount, Uint32Array.from(faces)));
  actual.forEach((x, i) => assert.ok(Math.abs(x - expected[i]) < 1e-9, `${what}: normal component ${i} is ${x}, the faces give ${expected[i]}`));
}

test("fans give the faces' area-weighted normals", () => {
  const tetrahedron = [0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2];
  sameNormals(tetrahedron, 4, 'closed tetrahedron');
  const fans = buildFans(4, Uint32Array.from(tetrahedron));
  for (let v = 0; v < 4; ++v) {
    const fan = Array.from(fans.fans.subarray(fans.fanOffsets[v], fans.fanOffsets[v + 1]));
    assert.equal(fan.length, 4, `vertex ${v}: three faces closed into a fan of 4`);
    assert.equal(fan[0], fan[3], `vertex ${v}'s fan closes`);
  }
  sameNormals(Array.from(makeSheetSubject().faces), 96, 'open sheet');
  // Two triangles touching at vertex 0 only, and a fin: three faces on one edge.
  sameNormals([0, 1, 2, 0, 3, 4], 5, 'bow tie');
  const bowTie = buildFans(5, Uint32Array.from([0, 1, 2, 0, 3, 4]));
  assert.deepEqual(Array.from(bowTie.fans.subarray(0, bowTie.fanOffsets[1])), [1, 2, 0, 3, 4], 'pieces separated by the vertex itself');
  sameNormals([0, 1, 2, 1, 0, 3, 0, 1, 4], 5, 'fin');
});

test('influences hold the clamped point, the offset beyond it, beta and the part', () => {
  const subject = makeSheetSubject();
  const buffer = encodeModel(subject);
  const model = decodeModel(new DataView(buffer), protocol.PROTOCOL_VERSION);
  const tables = buildEvaluationTables(model, subject.faces);
  let outside = 0;
  let k = 0;
  for (let v = 0; v < subject.vertexCount; ++v) {
    const span = tables.vertexSpans.subarray(4 * v, 4 * v + 4);
    assert.equal(span[0], k, `vertex ${v}'s first influence`);
    assert.equal(span[1], subject.influences[v].length);
    for (const { part: p, beta } of subject.influences[v]) {
      const part = subject.parts[p];
      const row = tables.influences.subarray(8 * k, 8 * k + 8);
      assert.equal(row[3], beta);
      assert.equal(row[7], p);
      for (let a = 0; a < 3; ++a) {
        let u = part.translation[a];
        for (let c = 0; c < 3; ++c) u += part.rotation[3 * a + c] * subject.referenceVertices[3 * v + c];
        assert.ok(row[a] >= part.boxMin[a] && row[a] <= part.boxMax[a], `vertex ${v} part ${p}: ${row[a]} inside the box on axis ${a}`);
        assert.ok(Math.abs(row[a] + row[4 + a] - u) < 1e-4, `vertex ${v} part ${p}: inside + outside = u on axis ${a}`);
        if (row[4 + a] !== 0) ++outside;
      }
      ++k;
    }
  }
  assert.ok(outside > 10, 'the subject must have points outside their part box');
  assert.deepEqual([tables.maxInfluences, tables.maxMembers], [2, 5]);
  assert.deepEqual(Array.from(tables.members.subarray(4 * 5, 4 * 6)), [...subject.parts[1].members[0], 1], "part 1's first member");
});
