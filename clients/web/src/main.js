// The live preview page: a worker receives the stream from the daemon that served the page;
// the page draws the newest frame on each animation frame and keeps the status bar and banner
// current. With the parameter encoding (the default) the GPU evaluates the mesh from each
// frame's ~12 kB of part parameters; with the others the page uploads the vertices it was sent.
import * as THREE from 'three';
import { Wants, Decoded, Encoding, ENCODING_NAMES, FrameFlags, FrameHeader, SourceState, decodeFrameArrays } from './protocol.js';
import { ViewerScene } from './viewer_scene.js';
import { BodyMesh } from './body_mesh.js';
import { EvaluatedBodyMesh } from './evaluated_body_mesh.js';
import { GpuMeshEvaluator } from './gpu_evaluator.js';
import { MarkerOverlay } from './marker_overlay.js';
import { StatusBar } from './status_bar.js';
import { installToggles } from './toggles.js';
import { installEncodingPicker, requestedEncoding } from './encoding_picker.js';
import { installSubjectPicker } from './subject_picker.js';
import { installSubjectControls } from './subject_controls.js';
import { installTakeControls } from './take_controls.js';

const SAMPLED_POINTS = 8;
const STATUS_INTERVAL_MS = 250;

// Wall clock in ms with sub-ms resolution, comparable with the daemon's system-clock stamps.
const wallClockMs = () => performance.timeOrigin + performance.now();

const params = new URLSearchParams(window.location.search);
const requested = requestedEncoding(params);
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
let bodyMesh = null; // BodyMesh (vertices from the stream) or EvaluatedBodyMesh (from the GPU)
let evaluator = null; // GpuMeshEvaluator, with the parameter encoding
let markerOverlay = null;
let targets = null;
let needsFraming = true;
let sceneDirty = true;
const shown = { mesh: true, markers: true, parts: false, surface: false };

// The newest frame handed over by the worker and not yet drawn.
const header = new FrameHeader();
let pendingFrame = null;
let framesRendered = 0;
let lastRenderedFrameNumber = -1;
let lastRenderedReceiveTimeNs = 0;
let latencyMs = NaN;
// Main-thread time spent on frames: taking them in (decode, upload, GPU passes submitted) and
// drawing the scene, in ms since the page loaded.
let frameWorkMs = 0;
const sampleIndices = new Uint32Array(SAMPLED_POINTS);
const samplePositions = new Float32Array(3 * SAMPLED_POINTS);
const sampledVertex = new Float32Array(3);
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
    bodyMesh = null;
  }
  if (evaluator) {
    evaluator.dispose();
    evaluator = null;
  }
  if (markerOverlay) {
    if (viewerScene) viewerScene.scene.remove(markerOverlay.points, markerOverlay.surface);
    markerOverlay.dispose();
    markerOverlay = null;
  }
}

// Once per MeshInfo (each connection): the only place the per-frame buffers are allocated. With
// the parameter encoding the body waits for the Model.
function buildScene(info) {
  const sameShape = meshInfo !== null && meshInfo.vertexCount === info.vertexCount && meshInfo.markerCount === info.markerCount;
  removeFromScene();
  meshInfo = info;
  if (info.vertexCount > 0 && info.encoding !== Encoding.PARAMETERS) bodyMesh = new BodyMesh(info);
  markerOverlay = info.markerCount > 0 ? new MarkerOverlay(info) : null;
  if (viewerScene) {
    if (bodyMesh) viewerScene.scene.add(bodyMesh.object);
    if (markerOverlay) viewerScene.scene.add(markerOverlay.points, markerOverlay.surface);
  }
  const cpuBody = bodyMesh instanceof BodyMesh;
  targets = {
    positions: cpuBody ? bodyMesh.positions : new Float32Array(0),
    normals: cpuBody ? bodyMesh.normals : new Float32Array(0),
    markers: markerOverlay ? markerOverlay.positions : new Float32Array(0),
    markerStatus: markerOverlay ? markerOverlay.status : new Uint8Array(0),
  };
  applyToggles();
  if (!sameShape) needsFraming = true;
  pendingFrame = null;

  sampleFromMarkers = info.vertexCount === 0;
  const count = sampleFromMarkers ? info.markerCount : info.vertexCount;
  for (let i = 0; i < SAMPLED_POINTS; ++i) sampleIndices[i] = Math.floor((i * count) / SAMPLED_POINTS);
}

// Once per Model: the static tables go to the GPU and the body draws from its evaluation.
function buildEvaluatedBody(model) {
  if (!viewerScene) return; // no WebGL: the banner says so; frames are still counted
  try {
    evaluator = new GpuMeshEvaluator(viewerScene.renderer, model, meshInfo.faces);
  } catch (error) {
    webglError = `The GPU cannot evaluate the parameters: ${error.message}. Choose another encoding.`;
    return;
  }
  bodyMesh = new EvaluatedBodyMesh(meshInfo, evaluator);
  viewerScene.scene.add(bodyMesh.object);
  needsFraming = true;
  applyToggles();
}

function frameCamera() {
  const box = new THREE.Box3();
  if (evaluator) {
    // Once per connection: the evaluated positions are on the GPU only.
    const positions = new Float32Array(3 * evaluator.vertexCount);
    evaluator.readPositions(positions);
    box.setFromArray(positions);
  } else if (bodyMesh) {
    box.setFromBufferAttribute(bodyMesh.positionAttribute);
  } else if (markerOverlay) {
    box.setFromBufferAttribute(markerOverlay.positionAttribute);
  }
  if (!box.isEmpty()) viewerScene.frame(box);
}

function copySample() {
  if (evaluator) return; // read from the GPU only when asked (sampledPositions)
  const source = sampleFromMarkers ? targets.markers : targets.positions;
  if (source.length === 0) return;
  for (let i = 0; i < SAMPLED_POINTS; ++i) {
    const v = 3 * sampleIndices[i];
    samplePositions[3 * i] = source[v];
    samplePositions[3 * i + 1] = source[v + 1];
    samplePositions[3 * i + 2] = source[v + 2];
  }
}

function sampledPositions() {
  if (evaluator && evaluator.frameNumber >= 0) {
    for (let i = 0; i < SAMPLED_POINTS; ++i) {
      evaluator.readVertexPosition(sampleIndices[i], sampledVertex);
      samplePositions.set(sampledVertex, 3 * i);
    }
  }
  return Array.from(samplePositions);
}

const worker = new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
const READY = { kind: 'ready' };

function takeFrame(frame) {
  const view = new DataView(frame.buffer);
  header.read(view); // checked by the worker already; this fills the reused header
  let written = 0;
  if (header.flags & FrameFlags.PARAMETERS) {
    if (evaluator) {
      evaluator.setParameters(view, header);
      evaluator.evaluate();
    }
  } else if ((header.flags & FrameFlags.COMPRESSED) && bodyMesh) {
    bodyMesh.positions.set(frame.positions);
    if (frame.withNormals) bodyMesh.normals.set(frame.normals);
    written = Decoded.POSITIONS | (frame.withNormals ? Decoded.NORMALS : 0);
  }
  written |= decodeFrameArrays(view, header, targets);
  // The worker may send the next one while this one is drawn; decoded arrays go back for reuse.
  if (frame.positions) worker.postMessage({ kind: 'ready', positions: frame.positions, normals: frame.normals }, [frame.positions.buffer, frame.normals.buffer]);
  else worker.postMessage(READY);
  return written;
}

function drawPendingFrame() {
  const written = takeFrame(pendingFrame);
  pendingFrame = null;
  if (bodyMesh instanceof BodyMesh && (written & Decoded.POSITIONS)) bodyMesh.commit((written & Decoded.NORMALS) !== 0);
  if (markerOverlay && (written & Decoded.MARKERS)) markerOverlay.commit();
  copySample();
  ++framesRendered;
  lastRenderedFrameNumber = header.frameNumber;
  lastRenderedReceiveTimeNs = header.receiveTimeNs;
  latencyMs = wallClockMs() - header.receiveTimeNs / 1e6;
  if (needsFraming && viewerScene && (bodyMesh || markerOverlay)) {
    frameCamera();
    needsFraming = false;
  }
  sceneDirty = true;
}

function animate() {
  requestAnimationFrame(animate);
  const started = performance.now();
  const drew = pendingFrame !== null;
  if (drew) drawPendingFrame();
  if (viewerScene && sceneDirty) {
    sceneDirty = false;
    viewerScene.render();
  }
  if (drew) frameWorkMs += performance.now() - started;
}

worker.onmessage = (event) => {
  const message = event.data;
  if (message.kind === 'frame') {
    if (meshInfo) pendingFrame = message;
  } else if (message.kind === 'meshInfo') {
    buildScene(message.meshInfo);
    worker.postMessage(READY);
  } else if (message.kind === 'model') {
    if (meshInfo) buildEvaluatedBody(message.model);
  } else if (message.kind === 'stats') {
    stats = message;
  } else if (message.kind === 'log') {
    console.error(message.line);
  }
};
worker.onerror = (event) => {
  webglError = `stream worker failed: ${event.message}`;
};

function errorText() {
  const count = stats ? stats.errorCount : 0;
  if (count === 0) return requested.problem;
  const rejected = stats.framesRejected > 0 ? `${stats.framesRejected} frames rejected; ` : '';
  return `${rejected}last: ${stats.lastError}`;
}

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
    encodingName: meshInfo ? ENCODING_NAMES[meshInfo.encoding] + (evaluator ? ' (GPU)' : '') : ENCODING_NAMES[requested.encoding],
    errorText: errorText(),
  };
}

function updateStatus() {
  statusBar.show(statusSnapshot());
  const state = stats ? stats.connectionState : 'connecting';
  const status = stats ? stats.status : null;
  if (status && status.state === SourceState.REFUSED) {
    statusBar.showBanner('source', `The daemon refused this viewer: ${status.detail}`);
  } else if (status && status.subject && !status.subjectPresent && status.state === SourceState.STREAMING) {
    statusBar.showBanner('source', `Subject ${status.subject} is not in the stream; waiting for it.`);
  } else if (state === 'closed') {
    const seconds = (stats.retryInMs / 1000).toFixed(1);
    statusBar.showBanner('connection', `Connection to the daemon closed (${stats.closeReason}). Reconnecting in ${seconds} s…`);
  } else if (state === 'connecting') {
    statusBar.showBanner('connection', `Connecting to ${streamUrl}…`);
  } else if (stats.sourceGone) {
    const why = status && status.state >= SourceState.DISCONNECTED ? `the daemon reports the source ${status.stateName}${status.detail ? ` (${status.detail})` : ''}`
      : 'no frames for over 1 s';
    statusBar.showBanner('source', `Source gone: ${why}.`);
  } else if (webglError) {
    statusBar.showBanner('error', webglError);
  } else {
    statusBar.showBanner('', '');
  }
}

installToggles(shown, applyToggles);
installTakeControls();
installSubjectControls(() => (meshInfo ? meshInfo.subject : ''));
installEncodingPicker(document.getElementById('encoding'), requested.encoding);
if (viewerScene) viewerScene.controls.addEventListener('change', () => { sceneDirty = true; });
window.addEventListener('resize', () => { sceneDirty = true; });

// The positions and normals the page drew last (Float32Array, 3 per vertex), with that frame's
// number and the daemon's receive time (which tells apart frames of a looped replay): read back
// from the GPU with the parameter encoding. For tests (it waits for the GPU) and a curious
// user's console.
function readDrawnFrame() {
  const V = meshInfo ? meshInfo.vertexCount : 0;
  const positions = new Float32Array(3 * V);
  const normals = new Float32Array(3 * V);
  if (evaluator) {
    evaluator.readPositions(positions);
    evaluator.readNormals(normals);
  } else if (bodyMesh) {
    positions.set(bodyMesh.positions);
    normals.set(bodyMesh.normals);
  }
  return { frameNumber: lastRenderedFrameNumber, receiveTimeNs: lastRenderedReceiveTimeNs, positions, normals };
}

// Read-only view of the counters, for tests and for a curious user's console.
const banner = document.getElementById('banner');
window.skinstreamViewer = Object.freeze({
  get framesReceived() { return stats ? stats.framesReceived : 0; },
  get framesRendered() { return framesRendered; },
  get framesSkipped() { return stats ? stats.framesSkipped : 0; },
  get framesRejected() { return stats ? stats.framesRejected : 0; },
  get framesWithoutKey() { return stats ? stats.framesWithoutKey : 0; },
  get lastFrameNumber() { return lastRenderedFrameNumber; },
  get lastFrameKey() { return `${lastRenderedFrameNumber}@${lastRenderedReceiveTimeNs}`; },
  get lastReceivedFrameNumber() { return stats ? stats.lastReceivedFrameNumber : -1; },
  get frameNumbersWentBack() { return stats ? stats.frameNumbersWentBack : 0; },
  get vertexCount() { return meshInfo ? meshInfo.vertexCount : 0; },
  get markerCount() { return meshInfo ? meshInfo.markerCount : 0; },
  get sampleIsMarkers() { return sampleFromMarkers; },
  get samplePositions() { return sampledPositions(); },
  get sourceRateHz() { return stats ? stats.sourceRateHz : 0; },
  get announcedRateHz() { return stats ? stats.announcedRateHz : 0; },
  get latencyMs() { return latencyMs; },
  get arrivalLatencyMs() { return stats ? stats.arrivalLatencyMs : NaN; },
  get clockSkewMs() { return Date.now() - wallClockMs(); },
  get connectionState() { return stats ? stats.connectionState : 'connecting'; },
  get reconnects() { return stats ? stats.reconnects : 0; },
  get sourceState() { return stats && stats.status ? stats.status.stateName : 'unknown'; },
  get encodingRequested() { return ENCODING_NAMES[requested.encoding]; },
  get encoding() { return meshInfo ? ENCODING_NAMES[meshInfo.encoding] : ''; },
  get quantised() { return meshInfo !== null && meshInfo.encoding === Encoding.QUANTISED; },
  get subject() { return meshInfo ? meshInfo.subject : ''; },
  get gpuEvaluation() { return evaluator ? evaluator.describe() : null; },
  get frameWorkMs() { return frameWorkMs; },
  get lastError() { return stats ? stats.lastError : ''; },
  get webgl() { return viewerScene !== null; },
  get webglVersion() { return viewerScene ? (viewerScene.renderer.capabilities.isWebGL2 ? 2 : 1) : 0; },
  get bannerText() { return banner.hidden ? '' : banner.textContent; },
  readDrawnFrame,
});

worker.postMessage({
  kind: 'start',
  url: streamUrl,
  hello: { wants: Wants.NORMALS | Wants.MARKERS | Wants.PACED | Wants.PACKED, encoding: requested.encoding, subject: params.get('subject') || '', token: params.get('token') || '' },
});
installSubjectPicker(document.getElementById('panel'), params);
setInterval(updateStatus, STATUS_INTERVAL_MS);
updateStatus();
requestAnimationFrame(animate);
