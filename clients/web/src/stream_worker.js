// Worker entry: receives the stream off the page's main thread, so a slow renderer (a tablet,
// software WebGL) never stops the socket from being drained. The daemon's queue then stays
// short and the page always gets the newest frame instead of a backlog seconds old. Compressed
// frames are decoded here too, only those the page will draw (and every key frame, which the
// frames after it need).
//
// Page -> worker: { kind: 'start', url, wants, encoding, subject, token },
//                 { kind: 'ready', positions?, normals? } (the page can take a frame; it hands
//                 back the arrays of the last decoded frame for reuse).
// Worker -> page: { kind: 'meshInfo', meshInfo }, { kind: 'model', model },
//                 { kind: 'frame', buffer, positions?, normals?, withNormals? } (transferred;
//                 the arrays of a compressed frame, decoded in the mesh's order),
//                 { kind: 'log', line } (an error for the console, at most one a second),
//                 { kind: 'stats', ... } four times a second.
import { StreamConnection } from './stream_connection.js';
import { StreamReceiver } from './stream_receiver.js';
import { ProtocolError } from './protocol.js';
import { compressedDecoderReady } from './compressed_decoder.js';
import { ErrorLog } from './error_log.js';

const STATS_INTERVAL_MS = 250;
const wallClockMs = () => performance.timeOrigin + performance.now();

let pageReady = false;
let closeReason = '';
let retryAtMs = 0;
let connection = null;
// Lines for the console go to the page, which prints them: one console for the whole viewer.
const errors = new ErrorLog((line) => self.postMessage({ kind: 'log', line: `skinstream: ${line}` }));
// Arrays for decoded compressed frames, handed back and forth with the page.
const spareArrays = [];

const receiver = new StreamReceiver({
  onMeshInfo(meshInfo) {
    spareArrays.length = 0;
    self.postMessage({ kind: 'meshInfo', meshInfo });
  },
  onModel(model) {
    self.postMessage({ kind: 'model', model });
  },
  onRejected(message) {
    errors.add(`frame rejected: ${message}`, wallClockMs());
  },
});

function decodedArrays() {
  const size = 3 * receiver.meshInfo.vertexCount;
  const arrays = spareArrays.pop();
  if (arrays && arrays.positions.length === size) return arrays;
  return { positions: new Float32Array(size), normals: new Float32Array(size) };
}

function sendFrameIfReady() {
  if (!pageReady) return;
  const buffer = receiver.takePending();
  if (buffer === null) return;
  if (!receiver.isCompressed(buffer)) {
    pageReady = false;
    self.postMessage({ kind: 'frame', buffer }, [buffer]);
    return;
  }
  const arrays = decodedArrays();
  try {
    const withNormals = receiver.decodeCompressed(buffer, arrays.positions, arrays.normals);
    pageReady = false;
    const message = { kind: 'frame', buffer, positions: arrays.positions, normals: arrays.normals, withNormals };
    self.postMessage(message, [buffer, arrays.positions.buffer, arrays.normals.buffer]);
  } catch (error) {
    if (!(error instanceof ProtocolError)) throw error;
    spareArrays.push(arrays);
    receiver.reject(error);
  }
}

function postStats() {
  const now = wallClockMs();
  const status = receiver.status;
  self.postMessage({
    kind: 'stats',
    framesReceived: receiver.framesReceived,
    framesSkipped: receiver.framesSkipped,
    framesWithoutKey: receiver.framesWithoutKey,
    framesRejected: receiver.framesRejected,
    lastError: errors.last,
    errorCount: errors.count,
    lastReceivedFrameNumber: receiver.lastReceivedFrameNumber,
    arrivalLatencyMs: receiver.arrivalLatencyMs,
    frameNumbersWentBack: receiver.frameNumbersWentBack,
    sourceRateHz: receiver.rate.rateHz(),
    announcedRateHz: receiver.announcedRateHz(),
    sourceGone: receiver.sourceGone(now),
    status,
    connectionState: connection ? connection.state : 'closed',
    reconnects: connection ? connection.reconnects : 0,
    closeReason,
    retryInMs: Math.max(0, retryAtMs - now),
  });
}

async function start(message) {
  await compressedDecoderReady;
  connection = new StreamConnection(message.url, message.hello, {
    onOpen() {
      closeReason = '';
      receiver.onConnectionOpened();
    },
    onMessage(buffer) {
      receiver.onMessage(buffer, wallClockMs());
      connection.confirmHealthy();
      sendFrameIfReady();
    },
    onProtocolError(error) {
      errors.add(`${error.message}; closing the connection`, wallClockMs());
    },
    onClose(reason, retryInMs) {
      closeReason = reason;
      retryAtMs = wallClockMs() + retryInMs;
      postStats();
    },
  });
  connection.start();
  setInterval(postStats, STATS_INTERVAL_MS);
}

self.onmessage = (event) => {
  const message = event.data;
  if (message.kind === 'ready') {
    if (message.positions) spareArrays.push({ positions: message.positions, normals: message.normals });
    pageReady = true;
    sendFrameIfReady();
  } else if (message.kind === 'start' && connection === null) {
    start(message);
  }
};
