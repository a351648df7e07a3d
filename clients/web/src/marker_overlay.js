// Markers as points coloured by their status this frame, and the marker surface as a wireframe
// sharing the same position buffer. Sized once from MeshInfo; updated in place per frame.
import * as THREE from 'three';
import { MarkerStatus } from './protocol.js';

// Measured, relabelled and filled are the three classes a user must tell apart at a glance.
export const MARKER_COLOURS = Object.freeze({
  [MarkerStatus.MEASURED]: new THREE.Color(0x3ddc84),
  [MarkerStatus.RELABELLED]: new THREE.Color(0xffd23f),
  [MarkerStatus.FILLED_PCA]: new THREE.Color(0xff3b5c),
  [MarkerStatus.FILLED_RIGID]: new THREE.Color(0xff7a3b),
  [MarkerStatus.HELD]: new THREE.Color(0xc04dff),
});
const UNKNOWN_STATUS = new THREE.Color(0xffffff);

// A round dot instead of GL's square point: a small disc texture, cut out with alphaTest.
function discTexture() {
  const size = 32;
  const canvas = document.createElement('canvas');
  canvas.width = canvas.height = size;
  const context = canvas.getContext('2d');
  context.fillStyle = '#fff';
  context.beginPath();
  context.arc(size / 2, size / 2, size / 2 - 1, 0, 2 * Math.PI);
  context.fill();
  return new THREE.CanvasTexture(canvas);
}

// Each undirected edge of the marker triangles once, as index pairs for LineSegments.
function uniqueEdges(triangles) {
  const seen = new Set();
  const edges = [];
  for (let t = 0; t < triangles.length; t += 3) {
    for (let k = 0; k < 3; ++k) {
      const a = triangles[t + k];
      const b = triangles[t + ((k + 1) % 3)];
      const key = a < b ? `${a},${b}` : `${b},${a}`;
      if (seen.has(key)) continue;
      seen.add(key);
      edges.push(a, b);
    }
  }
  return new Uint32Array(edges);
}

export class MarkerOverlay {
  constructor(meshInfo) {
    const M = meshInfo.markerCount;
    this.positions = new Float32Array(3 * M);
    this.status = new Uint8Array(M);
    this.colours = new Float32Array(3 * M);
    this.positionAttribute = new THREE.BufferAttribute(this.positions, 3).setUsage(THREE.DynamicDrawUsage);
    this.colourAttribute = new THREE.BufferAttribute(this.colours, 3).setUsage(THREE.DynamicDrawUsage);

    const pointGeometry = new THREE.BufferGeometry();
    pointGeometry.setAttribute('position', this.positionAttribute);
    pointGeometry.setAttribute('color', this.colourAttribute);
    this.points = new THREE.Points(pointGeometry, new THREE.PointsMaterial({
      size: 8, sizeAttenuation: false, vertexColors: true, depthTest: false, map: discTexture(), alphaTest: 0.5,
    }));
    this.points.renderOrder = 2; // drawn over the skin they sit on
    this.points.frustumCulled = false;

    const surfaceGeometry = new THREE.BufferGeometry();
    surfaceGeometry.setAttribute('position', this.positionAttribute);
    surfaceGeometry.setIndex(new THREE.BufferAttribute(uniqueEdges(meshInfo.markerTriangles), 1));
    this.surface = new THREE.LineSegments(surfaceGeometry, new THREE.LineBasicMaterial({ color: 0x7fb7ff, transparent: true, opacity: 0.7 }));
    this.surface.renderOrder = 1;
    this.surface.frustumCulled = false;
  }

  commit() {
    for (let i = 0; i < this.status.length; ++i) {
      const c = MARKER_COLOURS[this.status[i]] || UNKNOWN_STATUS;
      this.colours[3 * i] = c.r;
      this.colours[3 * i + 1] = c.g;
      this.colours[3 * i + 2] = c.b;
    }
    this.positionAttribute.needsUpdate = true;
    this.colourAttribute.needsUpdate = true;
  }

  setPointsVisible(on) {
    this.points.visible = on;
  }

  setSurfaceVisible(on) {
    this.surface.visible = on;
  }

  dispose() {
    this.points.geometry.dispose();
    this.points.material.map.dispose();
    this.points.material.dispose();
    this.surface.geometry.dispose();
    this.surface.material.dispose();
  }
}
