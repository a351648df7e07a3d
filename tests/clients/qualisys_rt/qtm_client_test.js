// The npm package qualisys-rt (a JavaScript QTM RT client, MIT), unmodified, reads
// `skinstream-replay --protocol qtm` streaming several recordings, and everything it receives is
// compared with the recordings (their TRC conversions, read here):
//   - the 3D parameters name every labelled marker of every recording, in order, prefixed by the
//     recording (as qualisys-rt reports names: camel-cased by its own helper);
//   - every frame arrives, in order, numbered from the first recording's first frame;
//   - each 3D position equals the recording's at that frame (float32 precision); a missing one,
//     or one past the end of a shorter recording, arrives as null (NaN on the wire);
//   - the 3D no labels component holds exactly the present unlabelled points, by id;
//   - the stream ends with NoMoreData ('end').
// Usage: node qtm_client_test.js REPLAY_BINARY RECORDING.c3d:RECORDING.trc ...
'use strict';
const { spawn } = require('child_process');
const fs = require('fs');
const path = require('path');
const Api = require('qualisys-rt').Api;
const { toCamelCase } = require('qualisys-rt/src/helpers');

const TOLERANCE_MM = 1e-3;  // float32 of a coordinate below 10 m is within 0.5 um of the double
const ID_STRIDE = 1000000;  // protocol/qtm/qtm_capture_encoder.h: the n-th recording's unlabelled ids

function fail(message) {
  console.error('FAIL: ' + message);
  process.exit(1);
}

function readTrc(file) {
  const lines = fs.readFileSync(file, 'utf8').split(/\r?\n/);
  const rate = Number(lines[2].split('\t')[0]);
  const names = lines[3].split('\t').slice(2).filter((_, i) => i % 3 === 0).map((s) => s.trim());
  const rows = [];
  for (const line of lines.slice(5)) {
    if (!line.trim()) continue;
    const cells = line.split('\t');
    const frame = Number(cells[0]);
    const points = names.map((_, c) => {
      const xyz = cells.slice(2 + 3 * c, 5 + 3 * c);
      return xyz.some((v) => v === undefined || v.trim() === '') ? null : xyz.map(Number);
    });
    rows.push({ frame, points });
  }
  return { rate, names, rows };
}

const isUnlabelled = (name) => name === '' || /^\*\d*$/.test(name);
const prefix = (stem) => stem.replace(/_/g, '-');

const [replayBinary, ...pairs] = process.argv.slice(2);
if (!replayBinary || pairs.length === 0) fail('usage: qtm_client_test.js REPLAY RECORDING.c3d:RECORDING.trc ...');
const recordings = pairs.map((pair) => {
  const [c3d, trc] = pair.split(':');
  return { c3d, stem: path.basename(c3d, path.extname(c3d)), ...readTrc(trc) };
});

// What the stream must hold: labels in order, with where each one's positions come from.
const expectedLabels = [];
recordings.forEach((r, s) =>
  r.names.forEach((name, c) => {
    if (!isUnlabelled(name)) expectedLabels.push({ label: prefix(r.stem) + '_' + name, recording: s, channel: c });
  }));
const frameCount = Math.max(...recordings.map((r) => r.rows.length));
const firstFrame = recordings[0].rows[0].frame;

const replay = spawn(replayBinary, ['--protocol', 'qtm', '--port', '0', '--speed', '4', '--max-queued', '1000',
                                    ...recordings.map((r) => r.c3d)], { stdio: ['ignore', 'pipe', 'inherit'] });
const watchdog = setTimeout(() => { replay.kill(); fail('timed out'); }, 60000);
let portText = '';
replay.stdout.on('data', (chunk) => {
  portText += chunk;
  const match = portText.match(/\{"port": (\d+)\}/);
  if (match && !api) run(Number(match[1]));
});

let api = null;
let received = 0;
let checkedPositions = 0, checkedNulls = 0, checkedUnlabelled = 0;
let lastFrame = -1;

function checkFrame(frame) {
  if (frame.frame <= lastFrame) fail(`frame ${frame.frame} after ${lastFrame}`);
  if (lastFrame >= 0 && frame.frame !== lastFrame + 1) fail(`frame ${frame.frame} follows ${lastFrame}: frames were lost`);
  lastFrame = frame.frame;
  const index = frame.frame - firstFrame;
  const threeD = frame.components['3d'];
  if (!threeD || threeD.markers.length !== expectedLabels.length)
    fail(`frame ${frame.frame}: ${threeD ? threeD.markers.length : 'no'} 3D markers, expected ${expectedLabels.length}`);
  expectedLabels.forEach((e, i) => {
    const row = recordings[e.recording].rows[index];
    const want = row ? row.points[e.channel] : null;
    const got = threeD.markers[i];
    if (want === null) {
      if (got.x !== null || got.y !== null || got.z !== null)
        fail(`frame ${frame.frame} ${e.label}: expected a missing marker, got ${JSON.stringify(got)}`);
      ++checkedNulls;
      return;
    }
    const diff = Math.max(Math.abs(got.x - want[0]), Math.abs(got.y - want[1]), Math.abs(got.z - want[2]));
    if (!(diff <= TOLERANCE_MM)) fail(`frame ${frame.frame} ${e.label}: got ${JSON.stringify(got)}, expected ${want}`);
    ++checkedPositions;
  });
  const noLabels = frame.components['3dNoLabels'];
  const wantUnlabelled = new Map();
  recordings.forEach((r, s) => {
    const row = r.rows[index];
    r.names.forEach((name, c) => {
      if (!isUnlabelled(name) || !row || row.points[c] === null) return;
      wantUnlabelled.set(Number(name.slice(1)) + s * ID_STRIDE, row.points[c]);
    });
  });
  const gotUnlabelled = noLabels ? noLabels.markers : [];
  if (gotUnlabelled.length !== wantUnlabelled.size)
    fail(`frame ${frame.frame}: ${gotUnlabelled.length} unlabelled points, expected ${wantUnlabelled.size}`);
  for (const m of gotUnlabelled) {
    const want = wantUnlabelled.get(m.id);
    if (!want) fail(`frame ${frame.frame}: unexpected unlabelled id ${m.id}`);
    const diff = Math.max(Math.abs(m.x - want[0]), Math.abs(m.y - want[1]), Math.abs(m.z - want[2]));
    if (!(diff <= TOLERANCE_MM)) fail(`frame ${frame.frame} unlabelled ${m.id}: got ${JSON.stringify(m)}, expected ${want}`);
    ++checkedUnlabelled;
  }
  ++received;
}

function run(port) {
  api = new Api({ debug: false, frequency: 'AllFrames' });
  api.on('frame', (frame) => {
    try { checkFrame(frame); } catch (e) { fail(e.stack); }
  });
  api.on('end', () => {
    clearTimeout(watchdog);
    if (received !== frameCount) fail(`${received} frames received, expected ${frameCount}`);
    if (checkedNulls === 0 || checkedUnlabelled === 0) fail('the recordings exercised no missing or unlabelled marker');
    console.log(`qualisys-rt received ${received} frames of ${expectedLabels.length} labels from ${recordings.length} ` +
                `recordings: ${checkedPositions} positions, ${checkedNulls} missing, ${checkedUnlabelled} unlabelled ` +
                'points as recorded');
    api.disconnect();
    replay.kill('SIGTERM');
    process.exit(0);
  });
  api.connect(port, '127.0.0.1')
    .then(() => api.getState())
    .then((state) => { if (state.id !== 8) fail(`GetState: ${JSON.stringify(state)}, expected RT from file started`); })
    .then(() => api.getParameters('3D'))
    .then((parameters) => {
      const labels = [].concat(parameters.the3d.labels || []).map((l) => String(l.name));
      const want = expectedLabels.map((e) => toCamelCase(e.label));
      if (labels.length !== want.length) fail(`${labels.length} labels, expected ${want.length}`);
      labels.forEach((l, i) => { if (l !== want[i]) fail(`label ${i} is ${l}, expected ${want[i]}`); });
    })
    .then(() => api.streamFrames({ components: ['3D', '3DNoLabels'], frequency: 'AllFrames' }))
    .catch((e) => fail(String(e && e.stack || e)));
}
