// Worker entry: receives the stream off the page's main thread, so a slow renderer (a tablet,
// software WebGL) never stops the socket from being drained. The daemon's queue then stays
// short and the page always gets the newest frame instead of a backlog seconds old.
//
// Page -> worker: { kind: 'start', url, wants, version2 }, { kind: 'ready' } (the page can take a
// frame); version2: null, or the subject and encoding of a version 2 Hello.
// Worker -> page: { kind: 'meshInfo', meshInfo }, { kind: 'frame', buffer } (transferred),
//                 { kind: 'stats', ... } four times a second.
import { StreamConnection } from './stream_connection.js';
import { StreamReceiver } from './stream_receiver.js';

const STATS_INTERVAL_MS = 250;
const wallClockMs = () => performance.timeOrigin + performance.now();

let pageReady = false;
let closeReason = '';
let retryAtMs = 0;
let connection = null;

const receiver = new StreamReceiver({
  onMeshInfo(meshInfo) {
    self.postMessage({ kind: 'meshInfo', meshInfo });
  },
});

function sendFrameIfReady() {
  if (!pageReady) return;
  const buffer = receiver.takePending();
  if (buffer === null) return;
  pageReady = false;
  self.postMessage({ kind: 'frame', buffer }, [buffer]);
}

function postStats() {
  const now = wallClockMs();
  const status = receiver.status;
  self.postMessage({
    kind: 'stats',
    framesReceived: receiver.framesReceived,
    framesSkipped: receiver.framesSkipped,
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

self.onmessage = (event) => {
  const message = event.data;
  if (message.kind === 'ready') {
    pageReady = true;
    sendFrameIfReady();
  } else if (message.kind === 'start' && connection === null) {
    connection = new StreamConnection(message.url, message.wants, {
      onOpen() {
        closeReason = '';
        receiver.onConnectionOpened();
      },
      onMessage(buffer) {
        receiver.onMessage(buffer, wallClockMs());
        connection.confirmHealthy();
        sendFrameIfReady();
      },
      onClose(reason, retryInMs) {
        closeReason = reason;
        retryAtMs = wallClockMs() + retryInMs;
        postStats();
      },
    }, message.version2 || null);
    connection.start();
    setInterval(postStats, STATS_INTERVAL_MS);
  }
};
