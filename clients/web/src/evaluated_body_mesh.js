// The deforming body when the GPU evaluates it (gpu_evaluator.js): the standard material's vertex
// shader takes each vertex's position and normal from the evaluator's float render targets
// (texel = vertex index) instead of attributes, so no vertex data crosses from the CPU per frame.
import * as THREE from 'three';
import { BodySurface } from './body_mesh.js';
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

export class EvaluatedBodyMesh extends BodySurface {
  // evaluator: a GpuMeshEvaluator; meshInfo: its MeshInfo (faces and dominant parts).
  constructor(meshInfo, evaluator) {
    const geometry = new THREE.BufferGeometry();
    // The reference pose: unused by the shader, but three.js sizes and bounds geometry by it.
    geometry.setAttribute('position', new THREE.BufferAttribute(evaluator.model.referenceVertices, 3));
    super(meshInfo, geometry);
    this.material.onBeforeCompile = (shader) => {
      shader.uniforms.evaluatedPositions = { value: evaluator.positionsTexture };
      shader.uniforms.evaluatedNormals = { value: evaluator.normalsTexture };
      shader.vertexShader = shader.vertexShader
        .replace('#include <common>', FETCH_DECLARATIONS)
        .replace('#include <beginnormal_vertex>', FETCH_NORMAL)
        .replace('#include <begin_vertex>', FETCH_POSITION);
    };
    this.material.customProgramCacheKey = () => 'skinstream-evaluated-body';
  }
}
