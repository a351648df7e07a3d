// GLSL ES 3.00 of the GPU evaluation (gpu_evaluator.js), the protocol's "How the subscriber
// evaluates vertex j" (docs/subscriber-protocol.md) in float, as the daemon does it
// (core/deform/mesh_evaluator.cpp). Each pass draws one point per item (member or vertex) onto
// that item's own texel of a float render target: the vertex shader does the work (compute(i),
// then POINT_VERTEX_MAIN places the point) and the fragment shader only stores what it was handed.
//
// Defines (set per Model): TARGET_WIDTH, TARGET_HEIGHT (the pass's render target),
// TABLE_WIDTH (the long index tables: vertices, influences, fans), MEMBER_WIDTH (per member).
//
// The parts texture has one row per part, of 13 RGBA texels:
//   0-8   A_t, row r in texels 3r..3r+2: (a0 a1 a2 a3) (a4 a5 a6 a7) (a8, rbf, 0, 0), where rbf
//         is 1 when the RBF term applies this frame (stored in row 0's third texel only);
//   9-11  row r of R_t and d_t[r]: (R[r][0] R[r][1] R[r][2] d[r]);
//   12    static: (1 / sigma, or 0 for a part without an RBF term; first member; member count; 0).

const COMMON = /* glsl */ `
precision highp float;
precision highp int;
precision highp sampler2D;
precision highp usampler2D;

ivec2 texelOf(int index, int width) { return ivec2(index % width, index / width); }
`;

const QUADRATIC = /* glsl */ `
uniform sampler2D parts;

// One row of A_t q(s), q = (x, y, z, x², y², z², xy, yz, zx).
float quadraticRow(int part, int row, vec4 q0, vec4 q1, float q2) {
  return dot(texelFetch(parts, ivec2(3 * row, part), 0), q0) + dot(texelFetch(parts, ivec2(3 * row + 1, part), 0), q1) +
         texelFetch(parts, ivec2(3 * row + 2, part), 0).x * q2;
}

vec3 quadratic(int part, vec3 s) {
  vec4 q0 = vec4(s, s.x * s.x);
  vec4 q1 = vec4(s.y * s.y, s.z * s.z, s.x * s.y, s.y * s.z);
  float q2 = s.z * s.x;
  return vec3(quadraticRow(part, 0, q0, q1, q2), quadraticRow(part, 1, q0, q1, q2), quadraticRow(part, 2, q0, q1, q2));
}
`;

// The RBF centres of this frame: c_i = A_t q(p^0_i) for every member i of every part.
export const CENTRES_VERTEX = /* glsl */ `${COMMON}${QUADRATIC}
uniform sampler2D members; // per member: p^0 x y z, part

vec4 compute(int i) {
  vec4 member = texelFetch(members, texelOf(i, MEMBER_WIDTH), 0);
  return vec4(quadratic(int(member.w), member.xyz), 0.0);
}
`;

// Eqs. 8 and 9 for vertex j: the sum over its influences (part p, weight beta) of
// beta R_t^T (A_t q(s) + RBF + (u - s) - d_t).
export const POSITIONS_VERTEX = /* glsl */ `${COMMON}${QUADRATIC}
uniform usampler2D vertexSpans; // per vertex: first influence, influences, first fan entry, fan length
uniform sampler2D influences;   // per influence two texels: (s x y z, beta), (u - s x y z, part)
uniform sampler2D centres;      // per member: c_i of this frame (CENTRES_VERTEX)
uniform sampler2D weights;      // per member: w_i of this frame

// sum_i w_i phi(|l - c_i| / sigma) over the part's members, added to l. phi is the uniform cubic
// B-spline with support 2, summed as 6 phi (two fused multiply-adds) times w / 6.
vec3 withRbf(int part, vec3 l) {
  vec4 info = texelFetch(parts, ivec2(12, part), 0);
  if (texelFetch(parts, ivec2(2, part), 0).y == 0.0 || info.x == 0.0) return l;
  vec3 deformed = l;
  int first = int(info.y);
  int end = first + int(info.z);
  for (int i = first; i < end; ++i) {
    ivec2 texel = texelOf(i, MEMBER_WIDTH);
    vec3 offset = (l - texelFetch(centres, texel, 0).xyz) * info.x;
    float squared = dot(offset, offset);
    float r = sqrt(squared);
    // Without a branch (cheaper where shader lanes run in step): 0 beyond the support.
    float far = max(2.0 - r, 0.0);
    float phi6 = r < 1.0 ? (3.0 * r - 6.0) * squared + 4.0 : far * far * far;
    deformed += phi6 * (texelFetch(weights, texel, 0).xyz * (1.0 / 6.0));
  }
  return deformed;
}

vec4 compute(int j) {
  uvec4 span = texelFetch(vertexSpans, texelOf(j, TABLE_WIDTH), 0);
  vec3 sum = vec3(0.0);
  int end = int(span.x + span.y);
  for (int k = int(span.x); k < end; ++k) {
    vec4 inside = texelFetch(influences, texelOf(2 * k, TABLE_WIDTH), 0);
    vec4 outside = texelFetch(influences, texelOf(2 * k + 1, TABLE_WIDTH), 0);
    int part = int(outside.w);
    vec3 l = withRbf(part, quadratic(part, inside.xyz));
    vec4 row0 = texelFetch(parts, ivec2(9, part), 0);
    vec4 row1 = texelFetch(parts, ivec2(10, part), 0);
    vec4 row2 = texelFetch(parts, ivec2(11, part), 0);
    vec3 shifted = l + outside.xyz - vec3(row0.w, row1.w, row2.w);
    sum += inside.w * (shifted.x * row0.xyz + shifted.y * row1.xyz + shifted.z * row2.xyz); // beta R^T shifted
  }
  return vec4(sum, 1.0);
}
`;

// The unit area-weighted normal of vertex j: sum (n_i - v) x (n_i+1 - v) over its fan.
export const NORMALS_VERTEX = /* glsl */ `${COMMON}
uniform usampler2D vertexSpans;
uniform usampler2D fans;       // the fans' neighbours, one per texel
uniform sampler2D positions;   // POSITIONS_VERTEX's output, TABLE_WIDTH texels wide

vec3 positionOf(int vertex) { return texelFetch(positions, texelOf(vertex, TABLE_WIDTH), 0).xyz; }

vec4 compute(int j) {
  uvec4 span = texelFetch(vertexSpans, texelOf(j, TABLE_WIDTH), 0);
  vec3 centre = positionOf(j);
  vec3 n = vec3(0.0);
  int first = int(span.z);
  int end = first + int(span.w);
  if (end > first) {
    vec3 a = positionOf(int(texelFetch(fans, texelOf(first, TABLE_WIDTH), 0).x)) - centre;
    for (int k = first + 1; k < end; ++k) {
      vec3 b = positionOf(int(texelFetch(fans, texelOf(k, TABLE_WIDTH), 0).x)) - centre;
      n += cross(a, b); // twice the face's area: area-weighted
      a = b;
    }
  }
  // A zero normal stays zero: the smallest normal float keeps the root finite, as the daemon's.
  return vec4(n * inversesqrt(dot(n, n) + 1.17549435e-38), 0.0);
}
`;

// Each pass's vertex shader: one of the computations above, then this.
export const POINT_VERTEX_MAIN = /* glsl */ `
flat out vec4 value;
void main() {
  value = compute(gl_VertexID);
  vec2 texel = vec2(texelOf(gl_VertexID, TARGET_WIDTH)) + 0.5;
  gl_Position = vec4(texel / vec2(TARGET_WIDTH, TARGET_HEIGHT) * 2.0 - 1.0, 0.0, 1.0);
  gl_PointSize = 1.0;
}
`;
export const STORE_FRAGMENT = /* glsl */ `
precision highp float;
flat in vec4 value;
layout(location = 0) out vec4 stored;
void main() { stored = value; }
`;
