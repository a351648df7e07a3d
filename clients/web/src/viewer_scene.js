// The three.js scene: renderer, Z-up camera with orbit controls, hemisphere + directional light,
// a floor grid in the XY plane. Capture data is in mm, Z up, the subject facing +Y.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

// Software WebGL (SwiftShader, llvmpipe) spends most of its time on multisampling: skip it there.
function softwareRenderer() {
  const canvas = document.createElement('canvas');
  const gl = canvas.getContext('webgl2') || canvas.getContext('webgl');
  if (!gl) return false;
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  const name = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : '';
  const lose = gl.getExtension('WEBGL_lose_context');
  if (lose) lose.loseContext();
  return /swiftshader|llvmpipe|software/i.test(name);
}

export class ViewerScene {
  // Throws when no WebGL context can be created; the caller shows that on the page.
  constructor(container) {
    this.container = container;
    // preserveDrawingBuffer: the canvas can be saved or read back (screenshots, tests) at any time.
    this.renderer = new THREE.WebGLRenderer({ antialias: !softwareRenderer(), preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    container.appendChild(this.renderer.domElement);

    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x20242b);

    this.camera = new THREE.PerspectiveCamera(40, 1, 10, 50000);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(0, 4000, 1200);

    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.set(0, 0, 900);
    this.controls.update();

    const hemisphere = new THREE.HemisphereLight(0xdfe8ff, 0x3a3128, 1.6);
    hemisphere.position.set(0, 0, 1); // sky is +Z
    this.scene.add(hemisphere);
    this.keyLight = new THREE.DirectionalLight(0xffffff, 2.0);
    this.keyLight.position.set(1500, 3000, 4000);
    this.scene.add(this.keyLight);
    this.scene.add(this.keyLight.target);

    const grid = new THREE.GridHelper(6000, 30, 0x555a66, 0x383c44);
    grid.rotation.x = Math.PI / 2; // GridHelper lies in XZ; the floor here is XY
    this.scene.add(grid);

    this.resize();
    window.addEventListener('resize', () => this.resize());
  }

  get gl() {
    return this.renderer.getContext();
  }

  resize() {
    const width = this.container.clientWidth || window.innerWidth;
    const height = this.container.clientHeight || window.innerHeight;
    this.renderer.setSize(width, height);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
  }

  // Puts the whole box in view from the front (+Y), slightly above, and orbits around its centre.
  frame(box) {
    const centre = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3());
    const radius = Math.max(size.length() / 2, 100);
    const fov = THREE.MathUtils.degToRad(this.camera.fov);
    const distance = (radius / Math.sin(fov / 2)) * (this.camera.aspect < 1 ? 1 / this.camera.aspect : 1);
    this.camera.position.set(centre.x + 0.25 * distance, centre.y + distance, centre.z + 0.2 * distance);
    this.camera.near = Math.max(1, distance / 100);
    this.camera.far = distance * 20;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
    this.keyLight.target.position.copy(centre);
    this.keyLight.position.set(centre.x + distance, centre.y + 2 * distance, centre.z + 2 * distance);
  }

  render() {
    this.controls.update();
    this.renderer.render(this.scene, this.camera);
  }
}
