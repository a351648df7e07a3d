// The version 2 Model message (everything static that turns a Frame's parameters into the mesh,
// docs/subscriber-protocol.md) and the check of each Frame's parameter block against it. Both
// reject bad bytes with a one-line ProtocolError, as the daemon's own decoder does.
import { FrameFlags, HEADER_BYTES, PART_PARAMETER_BYTES, PayloadReader, ProtocolError, paddingTo4 } from './protocol.js';

const PART_BYTES = 80;
// Largest relative error accepted in R^0 R^0T = I: the evaluation takes R^T as R^-1.
const ORTHONORMAL_TOLERANCE = 1e-4;

function allFinite(array, from = 0, to = array.length) {
  for (let i = from; i < to; ++i) if (!Number.isFinite(array[i])) return false;
  return true;
}

// Returns { vertexCount, partCount, memberCount, influenceCount, referenceVertices (3V),
// rotation (9P, row-major), translation (3P), boxMin (3P), boxMax (3P), sigma (P),
// partMembers (P), firstMember (P), memberReference (3Y), influenceCounts (V),
// firstInfluence (V + 1), influenceParts (K), influenceWeights (K) }.
export function decodeModel(view) {
  const r = new PayloadReader(view, 'Model');
  const V = r.u32('vertex_count');
  const P = r.u32('part_count');
  const Y = r.u32('member_count');
  const K = r.u32('influence_count');
  const payload = view.byteLength - HEADER_BYTES;
  const expected = 16 + 12 * V + PART_BYTES * P + 12 * Y + V + K + paddingTo4(V + K) + 4 * K;
  if (expected !== payload) {
    throw new ProtocolError(`Model counts (${V} vertices, ${P} parts, ${Y} members, ${K} influences) say ${expected} bytes, the payload holds ${payload}`);
  }
  if (V === 0 || P === 0) throw new ProtocolError(`Model of ${V} vertices and ${P} parts`);
  if (P > 255) throw new ProtocolError(`Model of ${P} parts: influences name parts in one byte`);
  const model = { vertexCount: V, partCount: P, memberCount: Y, influenceCount: K };
  model.referenceVertices = r.f32Array(3 * V, 'reference vertices');
  if (!allFinite(model.referenceVertices)) throw new ProtocolError('Model has a reference vertex that is not finite');

  model.rotation = new Float32Array(9 * P);
  model.translation = new Float32Array(3 * P);
  model.boxMin = new Float32Array(3 * P);
  model.boxMax = new Float32Array(3 * P);
  model.sigma = new Float32Array(P);
  model.partMembers = new Uint32Array(P);
  model.firstMember = new Uint32Array(P);
  let members = 0;
  for (let p = 0; p < P; ++p) {
    model.rotation.set(r.f32Array(9, 'part rotation'), 9 * p);
    model.translation.set(r.f32Array(3, 'part translation'), 3 * p);
    model.boxMin.set(r.f32Array(3, 'part box'), 3 * p);
    model.boxMax.set(r.f32Array(3, 'part box'), 3 * p);
    model.sigma[p] = r.f32('part sigma');
    const count = r.u32('part member count');
    checkPart(model, p, count);
    model.firstMember[p] = members;
    model.partMembers[p] = count;
    members += count;
  }
  if (members !== Y) throw new ProtocolError(`Model parts count ${members} members, the header ${Y}`);
  model.memberReference = r.f32Array(3 * Y, 'member reference positions');
  if (!allFinite(model.memberReference)) throw new ProtocolError("Model has a member's reference position that is not finite");

  model.influenceCounts = new Uint8Array(r.bytes(V, 'influences per vertex'));
  model.firstInfluence = new Uint32Array(V + 1);
  for (let v = 0; v < V; ++v) {
    if (model.influenceCounts[v] === 0) throw new ProtocolError(`Model vertex ${v} has no influence`);
    model.firstInfluence[v + 1] = model.firstInfluence[v] + model.influenceCounts[v];
  }
  if (model.firstInfluence[V] !== K) throw new ProtocolError(`Model vertices count ${model.firstInfluence[V]} influences, the header ${K}`);
  model.influenceParts = new Uint8Array(r.bytes(K, 'influence parts'));
  r.skip(paddingTo4(V + K), 'padding');
  model.influenceWeights = r.f32Array(K, 'influence weights');
  r.expectEnd();
  checkInfluences(model);
  return model;
}

function checkPart(model, p, memberCount) {
  const problem = (text) => new ProtocolError(`Model part ${p} ${text}`);
  if (memberCount < 1) throw problem('has no members');
  if (!allFinite(model.rotation, 9 * p, 9 * p + 9) || !allFinite(model.translation, 3 * p, 3 * p + 3) ||
      !allFinite(model.boxMin, 3 * p, 3 * p + 3) || !allFinite(model.boxMax, 3 * p, 3 * p + 3) ||
      !Number.isFinite(model.sigma[p]) || model.sigma[p] < 0) {
    throw problem('has a value that is not finite (or a negative dilation)');
  }
  for (let a = 0; a < 3; ++a) if (model.boxMin[3 * p + a] > model.boxMax[3 * p + a]) throw problem(`has an empty box on axis ${a}`);
  const R = model.rotation.subarray(9 * p, 9 * p + 9);
  for (let i = 0; i < 3; ++i) {
    for (let j = 0; j < 3; ++j) {
      const dot = R[3 * i] * R[3 * j] + R[3 * i + 1] * R[3 * j + 1] + R[3 * i + 2] * R[3 * j + 2];
      if (Math.abs(dot - (i === j ? 1 : 0)) > ORTHONORMAL_TOLERANCE) throw problem('has a reference rotation that is not orthonormal');
    }
  }
}

function checkInfluences(model) {
  const { vertexCount: V, partCount: P, firstInfluence, influenceParts, influenceWeights } = model;
  for (let v = 0; v < V; ++v) {
    let sum = 0;
    for (let k = firstInfluence[v]; k < firstInfluence[v + 1]; ++k) {
      if (influenceParts[k] >= P) throw new ProtocolError(`Model vertex ${v} is influenced by part ${influenceParts[k]} of ${P}`);
      const beta = influenceWeights[k];
      if (!Number.isFinite(beta) || beta < 0) throw new ProtocolError(`Model vertex ${v} has a negative or non-finite weight`);
      sum += beta;
    }
    if (Math.abs(sum - 1) > 1e-3) throw new ProtocolError(`Model vertex ${v}'s weights sum to ${sum}, not 1`);
  }
}

// A Frame's parameter block (header.positionsAt, read by FrameHeader) against the Model: the
// counts match, every value is finite, the flags are 0 or 1.
export function checkParameterBlock(view, header, model) {
  const n = header.frameNumber;
  if ((header.flags & FrameFlags.PARAMETERS) === 0) throw new ProtocolError(`Frame ${n} carries no parameters`);
  let o = header.positionsAt;
  const parts = view.getUint32(o, true);
  const members = view.getUint32(o + 4, true);
  if (parts !== model.partCount || members !== model.memberCount) {
    throw new ProtocolError(`Frame ${n} has parameters of ${parts} parts and ${members} members, the Model ${model.partCount} and ${model.memberCount}`);
  }
  o += 8;
  for (let p = 0; p < parts; ++p, o += PART_PARAMETER_BYTES) {
    for (let i = 0; i < 39; ++i) {
      if (!Number.isFinite(view.getFloat32(o + 4 * i, true))) throw new ProtocolError(`Frame ${n} part ${p} has a value that is not finite`);
    }
    const flags = view.getUint32(o + 156, true);
    if (flags > 1) throw new ProtocolError(`Frame ${n} part ${p} has reserved flag bits set (${flags})`);
  }
  for (let i = 0; i < 3 * members; ++i, o += 4) {
    if (!Number.isFinite(view.getFloat32(o, true))) throw new ProtocolError(`Frame ${n} has an RBF weight that is not finite`);
  }
}
