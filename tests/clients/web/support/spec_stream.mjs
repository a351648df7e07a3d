// A small subject and its version 2 messages, written byte by byte from the tables of
// docs/subscriber-protocol.md (independently of clients/web/src, which only decodes), and its
// evaluation as the spec's "How the subscriber evaluates vertex j" writes it, in double: what
// the page's decoders and GPU evaluation are tested against without a daemon.
//
// The subject is a sheet of 12 x 8 vertices in the XZ plane, 20 mm apart, cut in two parts along
// x with a band of vertices blended between them; part 1's reference frame is rotated 30 degrees
// about y, and part 0's box leaves the sheet's left edge outside (carried rigidly).

export const MessageType = { HELLO: 1, MESH_INFO: 2, FRAME: 3, STATUS: 4, ACK: 5, MODEL: 6 };
export const Encoding = { FLOAT: 0, QUANTISED: 1, COMPRESSED: 2, PARAMETERS: 3 };
const MAGIC = 0x46534b53;
const f32 = Math.fround;

// Little-endian writer that grows as it goes.
export class ByteWriter {
  constructor() {
    this.bytes = new Uint8Array(256);
    this.view = new DataView(this.bytes.buffer);
    this.length = 0;
  }
  room(n) {
    if (this.length + n <= this.bytes.length) return;
    const bigger = new Uint8Array(Math.max(2 * this.bytes.length, this.length + n));
    bigger.set(this.bytes);
    this.bytes = bigger;
    this.view = new DataView(bigger.buffer);
  }
  u8(v) { this.room(1); this.view.setUint8(this.length, v); this.length += 1; return this; }
  u16(v) { this.room(2); this.view.setUint16(this.length, v, true); this.length += 2; return this; }
  u32(v) { this.room(4); this.view.setUint32(this.length, v >>> 0, true); this.length += 4; return this; }
  i64(v) { this.room(8); this.view.setBigInt64(this.length, BigInt(v), true); this.length += 8; return this; }
  f32(v) { this.room(4); this.view.setFloat32(this.length, v, true); this.length += 4; return this; }
  raw(bytes) { this.room(bytes.length); this.bytes.set(bytes, this.length); this.length += bytes.length; return this; }
  string(s) { const b = new TextEncoder().encode(s); return this.u16(b.length).raw(b); }
  pad4() { while (this.length % 4 !== 0) this.u8(0); return this; }
  result() { return this.bytes.slice(0, this.length); }
}

// A whole message: the 12-byte header, then the payload.
export function message(type, payload, version = 2) {
  const w = new ByteWriter().u32(MAGIC).u16(version).u16(type).u32(payload.length).raw(payload);
  return w.result().buffer;
}

function rotationAboutY(degrees) {
  const a = (degrees * Math.PI) / 180;
  return [Math.cos(a), 0, Math.sin(a), 0, 1, 0, -Math.sin(a), 0, Math.cos(a)].map(f32);
}

export function makeSheetSubject() {
  const nx = 12;
  const ny = 8;
  const V = nx * ny;
  const referenceVertices = new Float32Array(3 * V);
  for (let j = 0; j < ny; ++j) {
    for (let i = 0; i < nx; ++i) referenceVertices.set([20 * i - 110, 5, 1000 + 20 * j], 3 * (j * nx + i));
  }
  const faces = [];
  for (let j = 0; j + 1 < ny; ++j) {
    for (let i = 0; i + 1 < nx; ++i) {
      const a = j * nx + i;
      faces.push(a, a + 1, a + nx + 1, a, a + nx + 1, a + nx);
    }
  }
  const parts = [
    { rotation: [1, 0, 0, 0, 1, 0, 0, 0, 1].map(f32), translation: [110, -5, -1000].map(f32), sigma: f32(45),
      members: [[20, 0, 10], [60, 0, 10], [20, 0, 120], [60, 0, 120], [100, 0, 60]] },
    { rotation: rotationAboutY(30), translation: [-530, -5, -900].map(f32), sigma: f32(60),
      members: [[0, 0, 0], [80, 0, 30], [40, 0, -60], [90, 0, -90]] },
  ];
  for (const part of parts) {
    part.members = part.members.map((m) => m.map(f32));
    part.boxMin = [0, 1, 2].map((a) => Math.min(...part.members.map((m) => m[a])));
    part.boxMax = [0, 1, 2].map((a) => Math.max(...part.members.map((m) => m[a])));
  }
  // Columns 0-4: part 0; 5-6: both (beta 0.75 / 0.25, then 0.25 / 0.75); 7-11: part 1.
  const influences = [];
  const dominantPart = new Uint8Array(V);
  for (let v = 0; v < V; ++v) {
    const column = v % nx;
    if (column <= 4) influences.push([{ part: 0, beta: 1 }]);
    else if (column === 5) influences.push([{ part: 0, beta: 0.75 }, { part: 1, beta: 0.25 }]);
    else if (column === 6) influences.push([{ part: 1, beta: 0.75 }, { part: 0, beta: 0.25 }]);
    else influences.push([{ part: 1, beta: 1 }]);
    dominantPart[v] = influences[v][0].part;
  }
  const markerNames = parts.flatMap((part, p) => part.members.map((_, i) => `P${p}M${i}`));
  return { vertexCount: V, faces: Uint32Array.from(faces), referenceVertices, parts, influences, dominantPart, markerNames };
}

// A frame's parameters: each part's A near [I 0 0] with small quadratic terms, its rotation
// and translation moving it, the RBF term on for part 0 only.
export function makeParameters(subject, t) {
  return {
    parts: subject.parts.map((part, p) => {
      const A = new Array(27).fill(0);
      for (let r = 0; r < 3; ++r) A[9 * r + r] = 1 + 0.02 * (r + 1) * Math.sin(t + p);
      A[3] = 2e-4 * Math.cos(t); // x² into x
      A[9 + 6] = 1e-4 * (p + 1); // xy into y
      A[18 + 5] = -3e-4 * Math.sin(t); // z² into z
      A[18 + 8] = 1.5e-4; // zx into z
      const rotation = rotationAboutY(10 * t + 30 * p);
      const translation = part.translation.map((d, a) => d + 15 * Math.sin(t + a));
      return { A: A.map(f32), R: rotation, d: translation.map(f32), rbf: p === 0 };
    }),
    weights: Float32Array.from(subject.parts.flatMap((part) => part.members.flatMap((_, i) => [3 * Math.sin(t + i), -2, 1.5 * Math.cos(i)]))),
  };
}

const memberCount = (subject) => subject.parts.reduce((n, part) => n + part.members.length, 0);
const influenceCount = (subject) => subject.influences.reduce((n, list) => n + list.length, 0);

// MeshInfo; order: the compressed vertex order (with the compressed encoding).
export function encodeMeshInfo(subject, { encoding = Encoding.PARAMETERS, order = null, partCount = subject.parts.length, version = 2 } = {}) {
  const w = new ByteWriter().u32(subject.vertexCount).u32(subject.faces.length / 3).u32(subject.markerNames.length).u32(partCount).f32(120);
  for (const index of subject.faces) w.u32(index);
  w.raw(subject.dominantPart).u32(0);
  for (const name of subject.markerNames) w.string(name);
  if (version >= 2) {
    w.string('Sheet').u32(encoding).u32(order ? order.length : 0);
    if (order) for (const v of order) w.u32(v);
  }
  return message(MessageType.MESH_INFO, w.result(), version);
}

export function encodeModel(subject, { version = 2, partOf = (k, part) => part } = {}) {
  const w = new ByteWriter().u32(subject.vertexCount).u32(subject.parts.length).u32(memberCount(subject)).u32(influenceCount(subject));
  for (const x of subject.referenceVertices) w.f32(x);
  for (const part of subject.parts) {
    for (const x of [...part.rotation, ...part.translation, ...part.boxMin, ...part.boxMax, part.sigma]) w.f32(x);
    w.u32(part.members.length);
  }
  for (const part of subject.parts) for (const m of part.members) m.forEach((x) => w.f32(x));
  for (const list of subject.influences) w.u8(list.length);
  let k = 0;
  for (const list of subject.influences) for (const { part } of list) w.u8(partOf(k++, part));
  w.pad4();
  for (const list of subject.influences) for (const { beta } of list) w.f32(beta);
  return message(MessageType.MODEL, w.result(), version);
}

function frameFixed(w, frameNumber, flags, vertexCount) {
  const receiveNs = BigInt(Date.now()) * 1000000n;
  w.u32(frameNumber).u32(flags).i64(0).i64(receiveNs).i64(receiveNs).u32(vertexCount).u32(0).u16(0).u16(0).u32(0).u32(0);
  for (let i = 0; i < 16; ++i) w.u8(0); // no timecode
}

// A parameter Frame (flags: parameters 16).
export function encodeParameterFrame(frameNumber, parameters, { partCountField = parameters.parts.length, version = 2 } = {}) {
  const w = new ByteWriter();
  frameFixed(w, frameNumber, 16, 0);
  w.u32(partCountField).u32(parameters.weights.length / 3);
  for (const part of parameters.parts) {
    for (const x of [...part.A, ...part.R, ...part.d]) w.f32(x);
    w.u32(part.rbf ? 1 : 0);
  }
  for (const x of parameters.weights) w.f32(x);
  return message(MessageType.FRAME, w.result(), version);
}

// Compressed positions and normals of the spec (version 2): on the key's grid, coded with
// meshoptimizer's encoder (version 0 of its vertex codec, as the daemon writes). key: null for a
// key frame (this returns its grid as .key), else the key's { frameNumber, origin, step, q }.
export function encodeCompressedFrame(encoder, frameNumber, positions, normals, order, key = null) {
  const V = order.length;
  let grid = key;
  if (grid === null) {
    const low = [Infinity, Infinity, Infinity];
    const high = [-Infinity, -Infinity, -Infinity];
    for (let v = 0; v < V; ++v) {
      for (let a = 0; a < 3; ++a) {
        low[a] = Math.min(low[a], positions[3 * v + a]);
        high[a] = Math.max(high[a], positions[3 * v + a]);
      }
    }
    const origin = low.map((x) => f32(x - 250));
    const step = low.map((x, a) => f32((high[a] - x + 500) / 65535));
    grid = { frameNumber, origin, step, q: new Uint16Array(4 * V) };
  }
  const q = new Uint16Array(4 * V);
  for (let i = 0; i < V; ++i) {
    for (let a = 0; a < 3; ++a) {
      const value = Math.round((positions[3 * order[i] + a] - grid.origin[a]) / grid.step[a]);
      q[4 * i + a] = key === null ? value : (value - key.q[4 * i + a]) & 0xffff;
    }
  }
  if (key === null) grid.q = q;
  const coded = encoder.encodeVertexBufferLevel(new Uint8Array(q.buffer), V, 8, 2, 0);
  const ordered = new Float32Array(4 * V);
  for (let i = 0; i < V; ++i) ordered.set(normals.subarray(3 * order[i], 3 * order[i] + 3), 4 * i);
  const codedNormals = encoder.encodeVertexBufferLevel(encoder.encodeFilterOct(ordered, V, 4, 8), V, 4, 2, 0);
  const w = new ByteWriter();
  frameFixed(w, frameNumber, 1 | 32 | (key === null ? 64 : 0), V);
  w.u32(grid.frameNumber);
  grid.origin.forEach((x) => w.f32(x));
  grid.step.forEach((x) => w.f32(x));
  w.u32(coded.length).raw(coded).pad4();
  w.u32(codedNormals.length).raw(codedNormals).pad4();
  return { buffer: message(MessageType.FRAME, w.result()), key: grid };
}

// The positions a decoder of that frame must give: the grid points the frame was coded to.
export function onGrid(positions, grid) {
  return positions.map((x, i) => grid.origin[i % 3] + Math.round((x - grid.origin[i % 3]) / grid.step[i % 3]) * grid.step[i % 3]);
}

const quadraticTerms = (x) => [x[0], x[1], x[2], x[0] * x[0], x[1] * x[1], x[2] * x[2], x[0] * x[1], x[1] * x[2], x[2] * x[0]];

function cubicBSpline(r) {
  const a = Math.max(2 - r, 0);
  const b = Math.max(1 - r, 0);
  return (a * a * a - 4 * b * b * b) / 6;
}

// Every vertex as the spec evaluates it, in double: Float64Array(3V).
export function evaluateAsSpecified(subject, parameters) {
  const out = new Float64Array(3 * subject.vertexCount);
  let firstMember = 0;
  const firsts = subject.parts.map((part) => { const f = firstMember; firstMember += part.members.length; return f; });
  for (let j = 0; j < subject.vertexCount; ++j) {
    const v0 = subject.referenceVertices.subarray(3 * j, 3 * j + 3);
    for (const { part: p, beta } of subject.influences[j]) {
      const part = subject.parts[p];
      const fit = parameters.parts[p];
      const u = [0, 1, 2].map((r) => part.translation[r] + part.rotation[3 * r] * v0[0] + part.rotation[3 * r + 1] * v0[1] + part.rotation[3 * r + 2] * v0[2]);
      const s = u.map((x, r) => Math.min(Math.max(x, part.boxMin[r]), part.boxMax[r]));
      const quadratic = (x) => { const q = quadraticTerms(x); return [0, 1, 2].map((r) => q.reduce((sum, qc, c) => sum + fit.A[9 * r + c] * qc, 0)); };
      const l = quadratic(s);
      if (fit.rbf && part.sigma > 0) {
        const sum = [0, 0, 0];
        part.members.forEach((member, i) => {
          const c = quadratic(member);
          const phi = cubicBSpline(Math.hypot(l[0] - c[0], l[1] - c[1], l[2] - c[2]) / part.sigma);
          for (let a = 0; a < 3; ++a) sum[a] += phi * parameters.weights[3 * (firsts[p] + i) + a];
        });
        for (let a = 0; a < 3; ++a) l[a] += sum[a];
      }
      const local = l.map((x, a) => x + (u[a] - s[a]) - fit.d[a]);
      for (let r = 0; r < 3; ++r) out[3 * j + r] += beta * (fit.R[r] * local[0] + fit.R[3 + r] * local[1] + fit.R[6 + r] * local[2]);
    }
  }
  return out;
}

// Unit area-weighted vertex normals of the faces, in double.
export function vertexNormals(positions, faces) {
  const n = new Float64Array(positions.length);
  for (let f = 0; f < faces.length; f += 3) {
    const [a, b, c] = [faces[f], faces[f + 1], faces[f + 2]];
    const e1 = [0, 1, 2].map((k) => positions[3 * b + k] - positions[3 * a + k]);
    const e2 = [0, 1, 2].map((k) => positions[3 * c + k] - positions[3 * a + k]);
    const cross = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
    for (const v of [a, b, c]) for (let k = 0; k < 3; ++k) n[3 * v + k] += cross[k];
  }
  for (let v = 0; v < n.length; v += 3) {
    const length = Math.hypot(n[v], n[v + 1], n[v + 2]);
    for (let k = 0; k < 3; ++k) n[v + k] /= length;
  }
  return n;
}
