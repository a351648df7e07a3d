// The static tables the GPU evaluation reads, prepared once per Model on the CPU (never per
// frame): per influence (vertex, part) its reference point clamped to the part's box and the
// offset beyond it, as the daemon forms them (core/deform/mesh_evaluator.cpp, in double from the
// Model's floats, then rounded to float); per vertex where its influences and its fan of
// neighbours start; the fans themselves.

// Per vertex its neighbours in fan order n_0, n_1, ...: each consecutive pair closes a face
// (v, n_i, n_i+1), so the area-weighted normal is sum (n_i - v) x (n_i+1 - v) with one neighbour
// read per face. Where the faces around v do not form one fan (a border, non-manifold), the
// pieces are separated by v itself, whose offset from v is zero and so adds nothing. The same
// construction as the daemon's (MeshEvaluator's fans).
export function buildFans(vertexCount, faces) {
  const pairOffsets = new Uint32Array(vertexCount + 1);
  for (let i = 0; i < faces.length; ++i) ++pairOffsets[faces[i] + 1];
  for (let v = 0; v < vertexCount; ++v) pairOffsets[v + 1] += pairOffsets[v];
  // Per vertex the (b, c) corners of its faces, in each face's winding.
  const pairs = new Uint32Array(2 * faces.length);
  const fill = pairOffsets.slice(0, vertexCount);
  for (let f = 0; f < faces.length; f += 3) {
    for (let corner = 0; corner < 3; ++corner) {
      const at = 2 * fill[faces[f + corner]]++;
      pairs[at] = faces[f + ((corner + 1) % 3)];
      pairs[at + 1] = faces[f + ((corner + 2) % 3)];
    }
  }
  const fanOffsets = new Uint32Array(vertexCount + 1);
  const fans = [];
  let used = new Uint8Array(16);
  for (let v = 0; v < vertexCount; ++v) {
    const first = pairOffsets[v];
    const count = pairOffsets[v + 1] - first;
    if (used.length < count) used = new Uint8Array(count);
    used.fill(0, 0, count);
    const from = (i) => pairs[2 * (first + i)];
    const to = (i) => pairs[2 * (first + i) + 1];
    for (let left = count; left > 0;) {
      // Start where no other unused pair ends (a border), else anywhere (a closed fan).
      let start = -1;
      for (let i = 0; i < count && start < 0; ++i) {
        if (used[i]) continue;
        let continuesAnother = false;
        for (let j = 0; j < count && !continuesAnother; ++j) continuesAnother = !used[j] && j !== i && to(j) === from(i);
        if (!continuesAnother) start = i;
      }
      for (let i = 0; i < count && start < 0; ++i) if (!used[i]) start = i;
      if (fans.length > fanOffsets[v]) fans.push(v); // separates pieces
      fans.push(from(start));
      for (let i = start; i >= 0;) {
        used[i] = 1;
        --left;
        const reached = to(i);
        fans.push(reached);
        i = -1;
        for (let j = 0; j < count && i < 0; ++j) if (!used[j] && from(j) === reached) i = j;
      }
    }
    fanOffsets[v + 1] = fans.length;
  }
  return { fanOffsets, fans: Uint32Array.from(fans) };
}

// model: decodeModel's result; faces: MeshInfo's (3 per face).
// Returns {
//   influences: Float32Array, 8 per influence: inside x y z, beta, outside x y z, part;
//   vertexSpans: Uint32Array, 4 per vertex: first influence, influence count, first fan entry, fan length;
//   fans: Uint32Array (buildFans);
//   members: Float32Array, 4 per member: p^0 x y z, part;
//   maxInfluences, maxMembers, maxFan: the shaders' loop bounds on this model.
// }
export function buildEvaluationTables(model, faces) {
  const V = model.vertexCount;
  const K = model.influenceCount;
  const influences = new Float32Array(8 * K);
  const v0 = model.referenceVertices;
  const u = [0, 0, 0];
  for (let v = 0; v < V; ++v) {
    for (let k = model.firstInfluence[v]; k < model.firstInfluence[v + 1]; ++k) {
      const p = model.influenceParts[k];
      // u = R^0 v^0 + d^0 in double, summed in the daemon's order, then s = u clamped to the box.
      for (let r = 0; r < 3; ++r) {
        let sum = model.translation[3 * p + r];
        for (let c = 0; c < 3; ++c) sum += model.rotation[9 * p + 3 * r + c] * v0[3 * v + c];
        u[r] = sum;
      }
      const out = 8 * k;
      for (let a = 0; a < 3; ++a) {
        const inside = Math.min(Math.max(u[a], model.boxMin[3 * p + a]), model.boxMax[3 * p + a]);
        influences[out + a] = inside;
        influences[out + 4 + a] = u[a] - inside;
      }
      influences[out + 3] = model.influenceWeights[k];
      influences[out + 7] = p;
    }
  }

  const { fanOffsets, fans } = buildFans(V, faces);
  const vertexSpans = new Uint32Array(4 * V);
  let maxInfluences = 0;
  let maxFan = 0;
  for (let v = 0; v < V; ++v) {
    const influenceCount = model.firstInfluence[v + 1] - model.firstInfluence[v];
    const fanLength = fanOffsets[v + 1] - fanOffsets[v];
    vertexSpans.set([model.firstInfluence[v], influenceCount, fanOffsets[v], fanLength], 4 * v);
    maxInfluences = Math.max(maxInfluences, influenceCount);
    maxFan = Math.max(maxFan, fanLength);
  }

  const Y = model.memberCount;
  const members = new Float32Array(4 * Y);
  let maxMembers = 0;
  for (let p = 0; p < model.partCount; ++p) {
    maxMembers = Math.max(maxMembers, model.partMembers[p]);
    for (let i = model.firstMember[p]; i < model.firstMember[p] + model.partMembers[p]; ++i) {
      members.set(model.memberReference.subarray(3 * i, 3 * i + 3), 4 * i);
      members[4 * i + 3] = p;
    }
  }
  return { influences, vertexSpans, fans, members, maxInfluences, maxMembers, maxFan };
}
