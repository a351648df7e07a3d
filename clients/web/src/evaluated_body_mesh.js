// The deforming body when the GPU evaluates it (gpu_evaluator.js): the standard material's vertex
// shader takes each vertex's position and normal from the evaluator's float render targets
// (texel = vertex index) instead of attributes, so no vertex data crosses from the CPU per frame.
import * as THREE from 'three';
import { fillPartColours } from './part_palette.js';
import { TABLE_WIDTH } from './gpu_evaluator.js';

const FETCH_DECLARATIONS = /* glsl */ `#include <common>
uniform highp sampler2D evaluatedPositions;
uniform highp sampler2D evaluatedNormals;
`;
// gl_VertexID of an indexed draw is the index read, i.e. the mesh's vertex.
const FETCH_NORMAL = /* glsl */ `ivec2 evaluatedTexel = ivec2(gl_VertexID % ${TABLE_WIDTH}, gl_VertexID / ${TABLE_WIDTH});
vec3 objectNormal = texelFetch(evaluatedNormals, evaluatedTexel, 0).xyz;
#ifdef USE_TANGENT
  vec3 objectTangent = vec3(tangent.xyz);
#endif`;
const FETCH_POSITION = /* glsl */ `vec3 transformed = texelFetch(evaluatedPositions, evaluatedTexel, 0).xyz;
#ifdef USE_ALPHAHASH
  vPosition = transformed;
#endif`;

export class EvaluatedBodyMesh {
  // evaluator: a GpuMeshEvaluator; meshInfo: its MeshInfo (faces and dominant parts).
  constructor(meshInfo, evaluator) {
    const V = meshInfo.vertexCount;
    const colours = new Float32Array(3 * V);
    fillPartColours(meshInfo.dominantPart, colours);
    this.geometry = new THREE.BufferGeometry();
    // The reference pose: unused by the shader, but three.js sizes and bounds geometry by it.
    this.geometry.setAttribute('position', new THREE.BufferAttribute(evaluator.model.referenceVertices, 3));
    this.geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    this.geometry.setIndex(new THREE.BufferAttribute(meshInfo.faces, 1));

    this.material = new THREE.MeshStandardMaterial({ color: 0xd8c3b0, roughness: 0.65, metalness: 0.0, side: THREE.DoubleSide });
    this.material.onBeforeCompile = (shader) => {
      shader.uniforms.evaluatedPositions = { value: evaluator.positionsTexture };
      shader.uniforms.evaluatedNormals = { value: evaluator.normalsTexture };
      shader.vertexShader = shader.vertexShader
        .replace('#include <common>', FETCH_DECLARATIONS)
        .replace('#include <beginnormal_vertex>', FETCH_NORMAL)
        .replace('#include <begin_vertex>', FETCH_POSITION);
    };
    this.material.customProgramCacheKey = () => 'skinstream-evaluated-body';
    this.object = new THREE.Mesh(this.geometry, this.material);
    this.object.frustumCulled = false; // the body moves away from its reference pose
  }

  setPartColours(on) {
    this.material.vertexColors = on;
    this.material.color.set(on ? 0xffffff : 0xd8c3b0);
    this.material.needsUpdate = true;
  }

  setVisible(on) {
    this.object.visible = on;
  }

  dispose() {
    this.geometry.dispose();
    this.material.dispose();
  }
}
