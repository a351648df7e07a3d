// The deforming body: one BufferGeometry sized from MeshInfo whose position and normal arrays are
// overwritten in place by each rendered frame (no per-frame allocation).
import * as THREE from 'three';
import { fillPartColours } from './part_palette.js';

const SKIN = 0xd8c3b0;

// What every body shares: the faces, the part colours and the skin material. Subclasses give the
// geometry its vertices (BodyMesh from arrays, EvaluatedBodyMesh from the GPU's evaluation).
export class BodySurface {
  constructor(meshInfo, geometry) {
    const colours = new Float32Array(3 * meshInfo.vertexCount);
    fillPartColours(meshInfo.dominantPart, colours);
    geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    geometry.setIndex(new THREE.BufferAttribute(meshInfo.faces, 1));
    this.geometry = geometry;
    this.material = new THREE.MeshStandardMaterial({ color: SKIN, roughness: 0.65, metalness: 0.0, side: THREE.DoubleSide });
    this.object = new THREE.Mesh(this.geometry, this.material);
    this.object.frustumCulled = false; // the body moves; its first bounding sphere would go stale
  }

  setPartColours(on) {
    this.material.vertexColors = on;
    this.material.color.set(on ? 0xffffff : SKIN);
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

export class BodyMesh extends BodySurface {
  constructor(meshInfo) {
    const V = meshInfo.vertexCount;
    const positions = new Float32Array(3 * V);
    const normals = new Float32Array(3 * V);
    const geometry = new THREE.BufferGeometry();
    const positionAttribute = new THREE.BufferAttribute(positions, 3).setUsage(THREE.DynamicDrawUsage);
    const normalAttribute = new THREE.BufferAttribute(normals, 3).setUsage(THREE.DynamicDrawUsage);
    geometry.setAttribute('position', positionAttribute);
    geometry.setAttribute('normal', normalAttribute);
    super(meshInfo, geometry);
    this.positions = positions;
    this.normals = normals;
    this.positionAttribute = positionAttribute;
    this.normalAttribute = normalAttribute;
  }

  // After the arrays were written: upload them. Without normals in the stream, derive them.
  commit(hasNormals) {
    this.positionAttribute.needsUpdate = true;
    if (hasNormals) this.normalAttribute.needsUpdate = true;
    else this.geometry.computeVertexNormals();
  }
}
