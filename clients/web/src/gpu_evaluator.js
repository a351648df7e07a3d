// Turns each Frame's part parameters into the mesh's vertices and normals on the GPU (WebGL2,
// three.js), so that the page's CPU only copies the ~10 kB of parameters into two small
// textures per frame. Three passes, each drawing one point per item onto its own texel of a
// float render target (evaluation_shaders.js):
//   centres:   c_i = A_t q(p^0_i) per RBF member;
//   positions: eqs. 8 and 9 per vertex, summed over its influences;
//   normals:   the area-weighted normal per vertex over its fan of neighbours.
// The body's material then fetches its vertex's position and normal from the last two targets
// (evaluated_body_mesh.js). Static tables are uploaded once per Model.
import * as THREE from 'three';
import { PART_PARAMETER_BYTES } from './protocol.js';
import { buildEvaluationTables } from './evaluation_tables.js';
import { CENTRES_VERTEX, NORMALS_VERTEX, POSITIONS_VERTEX, POINT_VERTEX_MAIN, STORE_FRAGMENT } from './evaluation_shaders.js';

// Width of the textures indexed by vertex, influence or fan entry: 53,514 vertices are 53 rows.
export const TABLE_WIDTH = 1024;
const PART_TEXELS = 13; // see evaluation_shaders.js
const STATIC_PART_TEXEL = 12;

function dataTexture(data, width, height, format, type) {
  const texture = new THREE.DataTexture(data, width, height, format, type);
  texture.minFilter = texture.magFilter = THREE.NearestFilter;
  texture.generateMipmaps = false;
  texture.needsUpdate = true;
  return texture;
}

// A table of `count` items of `channels` values, padded to whole rows of `width` texels.
function paddedTable(values, count, channels, width) {
  const rows = Math.max(1, Math.ceil(count / width));
  const data = new values.constructor(width * rows * channels);
  data.set(values);
  return { data, width, rows };
}

function floatTarget(width, height) {
  return new THREE.WebGLRenderTarget(width, height, {
    type: THREE.FloatType, format: THREE.RGBAFormat, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
    depthBuffer: false, stencilBuffer: false, generateMipmaps: false,
  });
}

// One pass: `count` points, each computed by `vertexShader`'s compute(i) and drawn onto texel i
// of `target`.
class PointPass {
  constructor(vertexShader, uniforms, defines, count, target) {
    this.material = new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3, vertexShader: vertexShader + POINT_VERTEX_MAIN, fragmentShader: STORE_FRAGMENT, uniforms,
      defines: { ...defines, TARGET_WIDTH: target.width, TARGET_HEIGHT: target.height },
      depthTest: false, depthWrite: false, blending: THREE.NoBlending,
    });
    const geometry = new THREE.BufferGeometry(); // no attributes: the shader indexes by gl_VertexID
    geometry.setDrawRange(0, count);
    this.points = new THREE.Points(geometry, this.material);
    this.points.frustumCulled = false;
    this.scene = new THREE.Scene();
    this.scene.add(this.points);
    this.target = target;
  }

  run(renderer, camera) {
    renderer.setRenderTarget(this.target);
    renderer.render(this.scene, camera);
  }

  dispose() {
    this.points.geometry.dispose();
    this.material.dispose();
    this.target.dispose();
  }
}

export class GpuMeshEvaluator {
  // renderer: a THREE.WebGLRenderer on WebGL2; model: decodeModel's; faces: MeshInfo's.
  // Throws an Error saying what is missing when this GPU cannot run it.
  constructor(renderer, model, faces) {
    const capabilities = renderer.capabilities;
    if (!capabilities.isWebGL2) throw new Error('evaluating parameters needs WebGL2');
    if (!renderer.extensions.has('EXT_color_buffer_float')) throw new Error('evaluating parameters needs EXT_color_buffer_float (float render targets)');
    this.renderer = renderer;
    this.model = model;
    this.vertexCount = model.vertexCount;
    const tables = buildEvaluationTables(model, faces);
    this.loopBounds = { influencesPerVertex: tables.maxInfluences, membersPerPart: tables.maxMembers, fanEntriesPerVertex: tables.maxFan };

    const spans = paddedTable(tables.vertexSpans, model.vertexCount, 4, TABLE_WIDTH);
    const influences = paddedTable(tables.influences, 2 * model.influenceCount, 4, TABLE_WIDTH);
    const fans = paddedTable(tables.fans, tables.fans.length, 1, TABLE_WIDTH);
    const memberWidth = Math.min(TABLE_WIDTH, Math.max(1, model.memberCount));
    const members = paddedTable(tables.members, model.memberCount, 4, memberWidth);
    const tallest = Math.max(spans.rows, influences.rows, fans.rows, members.rows, model.partCount);
    if (tallest > capabilities.maxTextureSize) {
      throw new Error(`the Model needs textures of ${tallest} rows, this GPU allows ${capabilities.maxTextureSize}`);
    }

    const uint = (table, format) => {
      const texture = dataTexture(table.data, table.width, table.rows, format, THREE.UnsignedIntType);
      texture.internalFormat = format === THREE.RedIntegerFormat ? 'R32UI' : 'RGBA32UI';
      return texture;
    };
    this.vertexSpans = uint(spans, THREE.RGBAIntegerFormat);
    this.fans = uint(fans, THREE.RedIntegerFormat);
    this.influences = dataTexture(influences.data, influences.width, influences.rows, THREE.RGBAFormat, THREE.FloatType);
    this.members = dataTexture(members.data, members.width, members.rows, THREE.RGBAFormat, THREE.FloatType);
    // Per frame: the parts' fits (and their static column) and the members' RBF weights.
    this.partData = new Float32Array(4 * PART_TEXELS * model.partCount);
    for (let p = 0; p < model.partCount; ++p) {
      const at = 4 * (PART_TEXELS * p + STATIC_PART_TEXEL);
      this.partData[at] = model.sigma[p] > 0 ? 1 / model.sigma[p] : 0;
      this.partData[at + 1] = model.firstMember[p];
      this.partData[at + 2] = model.partMembers[p];
    }
    this.parts = dataTexture(this.partData, PART_TEXELS, model.partCount, THREE.RGBAFormat, THREE.FloatType);
    this.weightData = new Float32Array(4 * memberWidth * members.rows);
    this.weights = dataTexture(this.weightData, memberWidth, members.rows, THREE.RGBAFormat, THREE.FloatType);

    const vertexRows = spans.rows;
    const defines = { TABLE_WIDTH, MEMBER_WIDTH: memberWidth };
    this.centresPass = new PointPass(CENTRES_VERTEX, { parts: { value: this.parts }, members: { value: this.members } },
      defines, model.memberCount, floatTarget(memberWidth, members.rows));
    this.positionsPass = new PointPass(POSITIONS_VERTEX, {
      parts: { value: this.parts }, vertexSpans: { value: this.vertexSpans }, influences: { value: this.influences },
      centres: { value: this.centresPass.target.texture }, weights: { value: this.weights },
    }, defines, model.vertexCount, floatTarget(TABLE_WIDTH, vertexRows));
    this.normalsPass = new PointPass(NORMALS_VERTEX, {
      vertexSpans: { value: this.vertexSpans }, fans: { value: this.fans }, positions: { value: this.positionsPass.target.texture },
    }, defines, model.vertexCount, floatTarget(TABLE_WIDTH, vertexRows));
    this.camera = new THREE.Camera(); // the passes place their points in clip space themselves

    this.textureSizes = [
      ['vertex spans (RGBA32UI)', spans.width, spans.rows, 16],
      ['influences (RGBA32F, 2 per influence)', influences.width, influences.rows, 16],
      ['fans (R32UI)', fans.width, fans.rows, 4],
      ['members (RGBA32F)', members.width, members.rows, 16],
      ['parts, per frame (RGBA32F)', PART_TEXELS, model.partCount, 16],
      ['RBF weights, per frame (RGBA32F)', memberWidth, members.rows, 16],
      ['centres target (RGBA32F)', memberWidth, members.rows, 16],
      ['positions target (RGBA32F)', TABLE_WIDTH, vertexRows, 16],
      ['normals target (RGBA32F)', TABLE_WIDTH, vertexRows, 16],
    ].map(([name, width, height, texelBytes]) => ({ name, width, height, bytes: width * height * texelBytes }));
    this.frameNumber = -1; // of the parameters last evaluated
    this.readBuffer = null;
  }

  get positionsTexture() { return this.positionsPass.target.texture; }
  get normalsTexture() { return this.normalsPass.target.texture; }

  // Copies a Frame's parameter block (checked by checkParameterBlock) into the per-frame
  // textures. Allocates nothing.
  setParameters(view, header) {
    const P = this.model.partCount;
    const data = this.partData;
    let o = header.positionsAt + 8;
    for (let p = 0; p < P; ++p, o += PART_PARAMETER_BYTES) {
      const row = 4 * PART_TEXELS * p;
      for (let r = 0; r < 3; ++r) {
        // A's row r: 9 floats into texels 3r..3r+2 (the ninth alone in the third).
        const at = row + 12 * r;
        for (let c = 0; c < 8; ++c) data[at + c] = view.getFloat32(o + 4 * (9 * r + c), true);
        data[at + 8] = view.getFloat32(o + 4 * (9 * r + 8), true);
        // R's row r and d[r].
        const rotation = row + 4 * (9 + r);
        for (let c = 0; c < 3; ++c) data[rotation + c] = view.getFloat32(o + 108 + 4 * (3 * r + c), true);
        data[rotation + 3] = view.getFloat32(o + 144 + 4 * r, true);
      }
      data[row + 9] = view.getUint32(o + 156, true) & 1; // the RBF flag, beside A[0][8]
    }
    const weights = this.weightData;
    for (let i = 0; i < this.model.memberCount; ++i, o += 12) {
      weights[4 * i] = view.getFloat32(o, true);
      weights[4 * i + 1] = view.getFloat32(o + 4, true);
      weights[4 * i + 2] = view.getFloat32(o + 8, true);
    }
    this.parts.needsUpdate = true;
    this.weights.needsUpdate = true;
    this.frameNumber = header.frameNumber;
  }

  // Runs the three passes on the parameters set last (the GPU does the work; this only submits).
  evaluate() {
    const renderer = this.renderer;
    const previous = renderer.getRenderTarget();
    this.centresPass.run(renderer, this.camera);
    this.positionsPass.run(renderer, this.camera);
    this.normalsPass.run(renderer, this.camera);
    renderer.setRenderTarget(previous);
  }

  // Reads the evaluated positions (or normals) back into out (3 floats per vertex, mesh order).
  // Waits for the GPU: for tests and framing the camera, never per frame.
  readPositions(out) { this.readTarget(this.positionsPass.target, out); }
  readNormals(out) { this.readTarget(this.normalsPass.target, out); }

  // One vertex's evaluated position into out (3 floats).
  readVertexPosition(vertex, out) {
    const texel = new Float32Array(4);
    this.renderer.readRenderTargetPixels(this.positionsPass.target, vertex % TABLE_WIDTH, Math.floor(vertex / TABLE_WIDTH), 1, 1, texel);
    out[0] = texel[0]; out[1] = texel[1]; out[2] = texel[2];
  }

  readTarget(target, out) {
    if (this.readBuffer === null) this.readBuffer = new Float32Array(4 * target.width * target.height);
    this.renderer.readRenderTargetPixels(target, 0, 0, target.width, target.height, this.readBuffer);
    for (let v = 0; v < this.vertexCount; ++v) {
      out[3 * v] = this.readBuffer[4 * v];
      out[3 * v + 1] = this.readBuffer[4 * v + 1];
      out[3 * v + 2] = this.readBuffer[4 * v + 2];
    }
  }

  // What the GPU path costs: texture sizes and the shaders' loop bounds on this Model.
  describe() {
    return { textures: this.textureSizes, loopBounds: this.loopBounds,
      textureBytes: this.textureSizes.reduce((sum, t) => sum + t.bytes, 0) };
  }

  dispose() {
    for (const pass of [this.centresPass, this.positionsPass, this.normalsPass]) pass.dispose();
    for (const texture of [this.vertexSpans, this.fans, this.influences, this.members, this.parts, this.weights]) texture.dispose();
  }
}
