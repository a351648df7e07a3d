// The live preview page: a worker receives the stream from the daemon that served the page;
// the page draws the newest frame on each animation frame and keeps the status bar and banner
// current.
import * as THREE from 'three';
import { Wants, Decoded, FrameHeader, SourceState, decodeFrameArrays } from './protocol.js';
import { ViewerScene } from './viewer_scene.js';
import { BodyMesh } from './body_mesh.js';
import { MarkerOverlay } from './marker_overlay.js';
import { StatusBar } from './status_bar.js';
import { installToggles } from './toggles.js';
import { chosenSubject, installSubjectPicker } from './subject_picker.js';

const SAMPLED_POINTS = 8;
const STATUS_INTERVAL_MS = 250;

// Wall clock in ms with sub-ms resolution, comparable with the daemon's system-clock stamps.
const wallClockMs = () => performance.timeOrigin + performance.now();

const params = new URLSearchParams(window.location.search);
// Quantised by default: half the bytes (640 kB a frame for 53,500 vertices with normals),
// measured 2.5x more frames reaching a software-WebGL page; positions stay within 0.03 mm.
const quantised = params.get('quantised') !== '0';
const version2 = chosenSubject(params, quantised);
const streamUrl = params.get('stream') ||
  `${window.location.protocol === 'https:' ? 'wss:' : 'ws:'}//${window.location.host}/stream`;

const statusBar = new StatusBar();
let viewerScene = null;
let webglError = '';
try {
  viewerScene = new ViewerScene(document.getElementById('viewport'));
} catch (error) {
  webglError = `WebGL is not available (${error.message}); the stream is still decoded.`;
}

let meshInfo = null;
let bodyMesh = null;
let markerOverlay = null;
let targets = null;
let needsFraming = true;
let sceneDirty = true;
const shown = { mesh: true, markers: true, parts: false, surface: false };

// The newest frame handed over by the worker and not yet drawn.
const header = new FrameHeader();
let pendingView = null;
let framesRendered = 0;
let lastRenderedFrameNumber = -1;
let latencyMs = NaN;
const sampleIndices = new Uint32Array(SAMPLED_POINTS);
const samplePositions = new Float32Array(3 * SAMPLED_POINTS);
let sampleFromMarkers = false;
let stats = null; // the worker's latest counters

function applyToggles() {
  if (bodyMesh) {
    bodyMesh.setVisible(shown.mesh);
    bodyMesh.setPartColours(shown.parts);
  }
  if (markerOverlay) {
    markerOverlay.setPointsVisible(shown.markers);
    markerOverlay.setSurfaceVisible(shown.surface);
  }
  sceneDirty = true;
}

function removeFromScene() {
  if (bodyMesh) {
    if (viewerScene) viewerScene.scene.remove(bodyMesh.object);
    bodyMesh.dispose();
  }
  if (markerOverlay) {
    if (viewerScene) viewerScene.scene.remove(markerOverlay.points, markerOverlay.surface);
    markerOverlay.dispose();
  }
}

// Once per MeshInfo (each connection): the only place the per-frame buffers are allocated.
function buildScene(info) {
  const sameShape = meshInfo !== null && meshInfo.vertexCount === info.vertexCount && meshInfo.markerCount === info.markerCount;
  removeFromScene();
  meshInfo = info;
  bodyMesh = info.vertexCount > 0 ? new BodyMesh(info) : null;
  markerOverlay = info.markerCount > 0 ? new MarkerOverlay(info) : null;
  if (viewerScene) {
    if (bodyMesh) viewerScene.scene.add(bodyMesh.object);
    if (markerOverlay) viewerScene.scene.add(markerOverlay.points, markerOverlay.surface);
  }
  targets = {
    positions: bodyMesh ? bodyMesh.positions : new Float32Array(0),
    normals: bodyMesh ? bodyMesh.normals : new Float32Array(0),
    markers: markerOverlay ? markerOverlay.positions : new Float32Array(0),
    markerStatus: markerOverlay ? markerOverlay.status : new Uint8Array(0),
  };
  applyToggles();
  if (!sameShape) needsFraming = true;
  pendingView = null;

  sampleFromMarkers = info.vertexCount === 0;
  const count = sampleFromMarkers ? info.markerCount : info.vertexCount;
  for (let i = 0; i < SAMPLED_POINTS; ++i) sampleIndices[i] = Math.floor((i * count) / SAMPLED_POINTS);
}

function frameCamera() {
  const box = new THREE.Box3();
  if (bodyMesh) box.setFromBufferAttribute(bodyMesh.positionAttribute);
  else if (markerOverlay) box.setFromBufferAttribute(markerOverlay.positionAttribute);
  if (!box.isEmpty()) viewerScene.frame(box);
}

function copySample() {
  const source = sampleFromMarkers ? targets.markers : targets.positions;
  if (source.length === 0) return;
  for (let i = 0; i < SAMPLED_POINTS; ++i) {
    const v = 3 * sampleIndices[i];
    samplePositions[3 * i] = source[v];
    samplePositions[3 * i + 1] = source[v + 1];
    samplePositions[3 * i + 2] = source[v + 2];
  }
}

const worker = new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
const READY = { kind: 'ready' };

function drawPendingFrame() {
  header.read(pendingView); // checked by the worker already; this fills the reused header
  const written = decodeFrameArrays(pendingView, header, targets);
  pendingView = null;
  worker.postMessage(READY); // the worker may send the next one while this one is drawn
  if (bodyMesh && (written & Decoded.POSITIONS)) bodyMesh.commit((written & Decoded.NORMALS) !== 0);
  if (markerOverlay && (written & Decoded.MARKERS)) markerOverlay.commit();
  copySample();
  ++framesRendered;
  lastRenderedFrameNumber = header.frameNumber;
  latencyMs = wallClockMs() - header.receiveTimeNs / 1e6;
  if (needsFraming && viewerScene) {
    frameCamera();
    needsFraming = false;
  }
  sceneDirty = true;
}

function animate() {
  requestAnimationFrame(animate);
  if (pendingView !== null) drawPendingFrame();
  if (viewerScene && sceneDirty) {
    sceneDirty = false;
    viewerScene.render();
  }
}

worker.onmessage = (event) => {
  const message = event.data;
  if (message.kind === 'frame') {
    if (meshInfo) pendingView = new DataView(message.buffer);
  } else if (message.kind === 'meshInfo') {
    buildScene(message.meshInfo);
    worker.postMessage(READY);
  } else if (message.kind === 'stats') {
    stats = message;
  }
};
worker.onerror = (event) => {
  webglError = `stream worker failed: ${event.message}`;
};

function statusSnapshot() {
  const status = stats ? stats.status : null;
  return {
    lastFrameNumber: lastRenderedFrameNumber,
    sourceRateHz: stats ? stats.sourceRateHz : 0,
    announcedRateHz: stats ? stats.announcedRateHz : 0,
    latencyMs,
    framesDroppedPipeline: header.framesDroppedPipeline,
    framesDroppedSubscriber: header.framesDroppedSubscriber,
    framesSkipped: stats ? stats.framesSkipped : 0,
    markersFilled: header.markersFilled,
    markersRelabelled: header.markersRelabelled,
    markerCount: meshInfo ? meshInfo.markerCount : 0,
    sourceStateName: status ? status.stateName : (framesRendered > 0 ? 'streaming' : 'waiting'),
    sourceDetail: status ? status.detail : '',
  };
}

function updateStatus() {
  statusBar.show(statusSnapshot());
  const state = stats ? stats.connectionState : 'connecting';
  const status = stats ? stats.status : null;
  if (status && status.state === SourceState.REFUSED) {
    statusBar.showBanner('error', `The daemon refused this page: ${status.detail}`);
  } else if (status && status.subject && !status.subjectPresent && status.state === SourceState.STREAMING) {
    statusBar.showBanner('source', `Subject ${status.subject} is not in the stream; waiting for it.`);
  } else if (state === 'closed') {
    const seconds = (stats.retryInMs / 1000).toFixed(1);
    statusBar.showBanner('connection', `Connection to the daemon closed (${stats.closeReason}). Reconnecting in ${seconds} s…`);
  } else if (state === 'connecting') {
    statusBar.showBanner('connection', `Connecting to ${streamUrl}…`);
  } else if (stats.sourceGone) {
    const why = status && status.state >= 2 ? `the daemon reports the source ${status.stateName}${status.detail ? ` (${status.detail})` : ''}`
      : 'no frames for over 1 s';
    statusBar.showBanner('source', `Source gone: ${why}.`);
  } else if (webglError) {
    statusBar.showBanner('error', webglError);
  } else {
    statusBar.showBanner('', '');
  }
}

installToggles(shown, applyToggles);
if (viewerScene) viewerScene.controls.addEventListener('change', () => { sceneDirty = true; });
window.addEventListener('resize', () => { sceneDirty = true; });

// Read-only view of the counters, for tests and for a curious user's console.
const banner = document.getElementById('banner');
window.skinstreamViewer = Object.freeze({
  get framesReceived() { return stats ? stats.framesReceived : 0; },
  get framesRendered() { return framesRendered; },
  get framesSkipped() { return stats ? stats.framesSkipped : 0; },
  get lastFrameNumber() { return lastRenderedFrameNumber; },
  get lastReceivedFrameNumber() { return stats ? stats.lastReceivedFrameNumber : -1; },
  get frameNumbersWentBack() { return stats ? stats.frameNumbersWentBack : 0; },
  get vertexCount() { return meshInfo ? meshInfo.vertexCount : 0; },
  get markerCount() { return meshInfo ? meshInfo.markerCount : 0; },
  get sampleIsMarkers() { return sampleFromMarkers; },
  get samplePositions() { return Array.from(samplePositions); },
  get sourceRateHz() { return stats ? stats.sourceRateHz : 0; },
  get announcedRateHz() { return stats ? stats.announcedRateHz : 0; },
  get latencyMs() { return latencyMs; },
  get arrivalLatencyMs() { return stats ? stats.arrivalLatencyMs : NaN; },
  get clockSkewMs() { return Date.now() - wallClockMs(); },
  get connectionState() { return stats ? stats.connectionState : 'connecting'; },
  get reconnects() { return stats ? stats.reconnects : 0; },
  get sourceState() { return stats && stats.status ? stats.status.stateName : 'unknown'; },
  get quantised() { return quantised; },
  get subject() { return meshInfo ? meshInfo.subject : ''; },
  get webgl() { return viewerScene !== null; },
  get webglVersion() { return viewerScene ? (viewerScene.renderer.capabilities.isWebGL2 ? 2 : 1) : 0; },
  get bannerText() { return banner.hidden ? '' : banner.textContent; },
});

worker.postMessage({ kind: 'start', url: streamUrl, wants: Wants.NORMALS | Wants.MARKERS | Wants.PACED | (quantised ? Wants.QUANTISED : 0),
  version2 });
installSubjectPicker(document.getElementById('panel'), params);
setInterval(updateStatus, STATUS_INTERVAL_MS);
updateStatus();
requestAnimationFrame(animate);
