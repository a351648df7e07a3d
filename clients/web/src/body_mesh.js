// The deforming body: one BufferGeometry sized from MeshInfo whose position and normal arrays are
// overwritten in place by each rendered frame (no per-frame allocation).
import * as THREE from 'three';
import { fillPartColours } from './part_palette.js';

export class BodyMesh {
  constructor(meshInfo) {
    const V = meshInfo.vertexCount;
    this.positions = new Float32Array(3 * V);
    this.normals = new Float32Array(3 * V);
    const colours = new Float32Array(3 * V);
    fillPartColours(meshInfo.dominantPart, colours);

    this.geometry = new THREE.BufferGeometry();
    this.positionAttribute = new THREE.BufferAttribute(this.positions, 3).setUsage(THREE.DynamicDrawUsage);
    this.normalAttribute = new THREE.BufferAttribute(this.normals, 3).setUsage(THREE.DynamicDrawUsage);
    this.geometry.setAttribute('position', this.positionAttribute);
    this.geometry.setAttribute('normal', this.normalAttribute);
    this.geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    this.geometry.setIndex(new THREE.BufferAttribute(meshInfo.faces, 1));

    this.material = new THREE.MeshStandardMaterial({ color: 0xd8c3b0, roughness: 0.65, metalness: 0.0, side: THREE.DoubleSide });
    this.object = new THREE.Mesh(this.geometry, this.material);
    this.object.frustumCulled = false; // the body moves; its first bounding sphere would go stale
  }

  // After the arrays were written: upload them. Without normals in the stream, derive them.
  commit(hasNormals) {
    this.positionAttribute.needsUpdate = true;
    if (hasNormals) this.normalAttribute.needsUpdate = true;
    else this.geometry.computeVertexNormals();
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
