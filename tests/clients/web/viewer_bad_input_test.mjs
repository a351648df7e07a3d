// The viewer page in Chromium against a scripted stand-in for the daemon (a real WebSocket server
// in this process) that sends a small subject written byte by byte from the spec, then bad
// messages among good ones. Checks that:
// - the page asks for the parameter encoding in a version 2 Hello by default;
// - the GPU's evaluation of parameters (read back) equals the spec's evaluation in double, and
//   a compressed stream decodes to its grid points;
// - a bad Frame (truncated, oversized, a part count that does not match, not finite) is rejected
//   with a one-line error in the status bar and the console, counted, and the next good frame
//   is drawn; a burst of them is logged at most once a second;
// - a bad Model or MeshInfo, or a message of another version, is shown the same way, the
//   connection is closed and opened again, and the page goes on drawing once it gets good data.
//
// node viewer_bad_input_test.mjs --web-root DIR [--chromium /usr/bin/chromium]
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import path from 'node:path';
import { launchChromium, waitUntil, readDrawnFrame } from './support/browser.mjs';
import { worstDistance, worstAngleDegrees } from './support/comparisons.mjs';
import { ScriptedServer } from './support/scripted_server.mjs';
import { repoRoot, resized, patched, readFixture } from './support/fixtures.mjs';
import {
  Encoding, makeSheetSubject, makeParameters, evaluateAsSpecified, vertexNormals, onGrid,
  encodeMeshInfo, encodeModel, encodeParameterFrame, encodeCompressedFrame,
} from './support/spec_stream.mjs';

function parseArguments(argv) {
  const options = { chromium: '/usr/bin/chromium' };
  for (let i = 0; i + 1 < argv.length; i += 2) options[argv[i].replace(/^--/, '').replace(/-([a-z])/g, (_, c) => c.toUpperCase())] = argv[i + 1];
  if (!options.webRoot) throw new Error('missing --web-root');
  return options;
}

const viewerState = (page) => page.evaluate(() => {
  const v = window.skinstreamViewer;
  const error = document.getElementById('status-error');
  return { lastFrameNumber: v.lastFrameNumber, framesRejected: v.framesRejected, encoding: v.encoding, bannerText: v.bannerText,
    statusError: error.textContent, statusErrorShown: !error.parentElement.hidden, connectionState: v.connectionState };
});

async function main() {
  const options = parseArguments(process.argv.slice(2));
  const { MeshoptEncoder } = await import(createRequire(path.join(repoRoot, 'clients/web/package.json')).resolve('meshoptimizer/encoder'));
  await MeshoptEncoder.ready;
  const subject = makeSheetSubject();
  const server = new ScriptedServer(options.webRoot);
  const port = await server.listen();
  const browser = await launchChromium(options.chromium);
  const pageErrors = [];
  const consoleErrors = [];
  try {
    const page = await browser.newPage({ viewport: { width: 640, height: 480 } });
    page.on('pageerror', (error) => pageErrors.push(error.message));
    page.on('console', (message) => { if (message.type() === 'error') consoleErrors.push(message.text()); });
    await page.goto(`http://127.0.0.1:${port}/`);

    // The Hello: version 2, parameters by default, normals, markers, pacing and packed MeshInfo and Model wanted.
    let connection = await server.nextConnection();
    const hello = new DataView(connection.hello);
    assert.equal(hello.getUint16(4, true), 2, 'the page speaks version 2');
    assert.equal(hello.getUint32(12, true), 1 | 4 | 16 | 32, 'wants: normals, markers, paced, packed');
    assert.equal(hello.getUint32(16, true), Encoding.PARAMETERS, 'the page asks for parameters by default');

    let frameNumber = 0;
    const goodFrame = async (what) => {
      const n = ++frameNumber;
      const parameters = makeParameters(subject, 0.1 * n);
      connection.send(encodeParameterFrame(n, parameters));
      await waitUntil(page, `good frame ${n} after ${what} was not drawn`, (k) => window.skinstreamViewer.lastFrameNumber === k, n);
      return parameters;
    };
    const start = async () => {
      connection.send(encodeMeshInfo(subject));
      connection.send(encodeModel(subject));
      return goodFrame('connecting');
    };

    // The GPU's evaluation against the spec's, in double.
    const parameters = await start();
    const drawn = await readDrawnFrame(page);
    const expected = evaluateAsSpecified(subject, parameters);
    const distance = worstDistance(drawn.positions, expected);
    const angle = worstAngleDegrees(drawn.normals, vertexNormals(expected, subject.faces));
    console.log(`GPU against the spec's evaluation in double: worst ${distance.worst.toExponential(2)} mm (vertex ${distance.at}), normals ${angle.toFixed(4)} degrees`);
    assert.ok(distance.worst < 1e-3, `GPU positions ${distance.worst} mm from the specified evaluation`);
    assert.ok(angle < 0.01, `GPU normals ${angle} degrees from the faces' area-weighted normals`);
    assert.equal((await viewerState(page)).encoding, 'parameters');

    // Bad frames: each rejected alone with its reason; the stream goes on.
    const threeParts = makeParameters(subject, 0);
    threeParts.parts.push(threeParts.parts[0]);
    const notFinite = makeParameters(subject, 0);
    notFinite.weights[4] = NaN;
    const badFrames = [
      ['truncated', resized(encodeParameterFrame(900, makeParameters(subject, 0)), 300), /Frame 900 is 300 bytes, its flags and counts need/],
      ['oversized', resized(encodeParameterFrame(901, makeParameters(subject, 0)), 700), /Frame 901 is 700 bytes/],
      ['a part count that does not match', encodeParameterFrame(902, threeParts), /parameters of 3 parts and 9 members, the Model 2 and 9/],
      ['a weight that is not finite', encodeParameterFrame(903, notFinite), /RBF weight that is not finite/],
    ];
    let rejected = 0;
    for (const [what, buffer, reason] of badFrames) {
      connection.send(buffer);
      await waitUntil(page, `the ${what} frame was not rejected`, (k) => window.skinstreamViewer.framesRejected === k, ++rejected);
      await waitUntil(page, `the status bar does not show why the ${what} frame was rejected`,
        (pattern) => new RegExp(pattern).test(document.getElementById('status-error').textContent), reason.source);
      const state = await viewerState(page);
      assert.ok(state.statusErrorShown && !state.statusError.includes('\n'), `one visible line: "${state.statusError}"`);
      await goodFrame(`the ${what} frame`);
    }
    // A burst: every frame counted, the console not flooded.
    const consoleBefore = consoleErrors.length;
    for (let i = 0; i < 40; ++i) connection.send(encodeParameterFrame(950 + i, notFinite));
    rejected += 40;
    await waitUntil(page, 'the burst of bad frames was not all rejected', (k) => window.skinstreamViewer.framesRejected === k, rejected);
    const burstLines = consoleErrors.length - consoleBefore;
    console.log(`a burst of 40 bad frames: ${burstLines} console lines`);
    assert.ok(burstLines <= 2, `${burstLines} console lines for a burst of 40 bad frames`);
    await goodFrame('the burst');

    // A Frame of another version: the connection is closed, and opened again.
    connection.send(patched(encodeParameterFrame(990, makeParameters(subject, 0)), (v) => v.setUint16(4, 1, true)));
    await waitUntil(page, 'no error shown for a version 1 Frame',
      () => /protocol version 1, expected 2/.test(document.getElementById('status-error').textContent));
    connection = await server.nextConnection();
    await start();

    // Bad Models and MeshInfo: shown, the connection closed and opened again.
    const badSessions = [
      ['a truncated Model', () => [encodeMeshInfo(subject), resized(encodeModel(subject), 400)], /Model counts .* say \d+ bytes, the payload holds 388/],
      ['a part count that does not match MeshInfo', () => [encodeMeshInfo(subject, { partCount: 3 }), encodeModel(subject)], /Model has 2 parts, MeshInfo said 3/],
      ['an influence of a part past the count', () => [encodeMeshInfo(subject), encodeModel(subject, { partOf: (k, part) => (k === 7 ? 2 : part) })],
        /influenced by part 2 of 2/],
      ['a Model of version 1', () => [encodeMeshInfo(subject), encodeModel(subject, { version: 1 })], /protocol version 1, expected 2/],
      ['a Packed MeshInfo whose stream is corrupt', () => [patched(readFixture('packed_mesh_info_v2.bin'), (v) => v.setUint8(43, v.getUint8(43) ^ 0xff))],
        /Packed: the deflated stream is corrupt/],
      ['a compressed vertex order past the vertex count', () => [encodeMeshInfo(subject, { encoding: Encoding.COMPRESSED,
        order: Uint32Array.from({ length: subject.vertexCount }, (_, i) => (i === 5 ? subject.vertexCount : i)) })], /names vertex 96 \(V = 96\)/],
    ];
    for (const [what, messages, reason] of badSessions) {
      for (const buffer of messages()) connection.send(buffer);
      await waitUntil(page, `no error shown for ${what}`, (pattern) => new RegExp(pattern).test(document.getElementById('status-error').textContent), reason.source);
      const state = await viewerState(page);
      assert.ok(!state.statusError.includes('\n'), `${what}: one line`);
      connection = await server.nextConnection(); // the page closed the connection and opened a new one
    }

    // The compressed encoding from the same stand-in: a key and a delta, then a damaged delta.
    const order = Uint32Array.from({ length: subject.vertexCount }, (_, i) => (i * 37) % subject.vertexCount);
    connection.send(encodeMeshInfo(subject, { encoding: Encoding.COMPRESSED, order }));
    const frames = [0.5, 0.6, 0.7].map((t) => {
      const positions = Float32Array.from(evaluateAsSpecified(subject, makeParameters(subject, t)));
      return { positions, normals: Float32Array.from(vertexNormals(positions, subject.faces)) };
    });
    const key = encodeCompressedFrame(MeshoptEncoder, 2000, frames[0].positions, frames[0].normals, order);
    connection.send(key.buffer);
    await waitUntil(page, 'the compressed key frame was not drawn', () => window.skinstreamViewer.lastFrameNumber === 2000);
    const delta = encodeCompressedFrame(MeshoptEncoder, 2001, frames[1].positions, frames[1].normals, order, key.key);
    connection.send(delta.buffer);
    await waitUntil(page, 'the compressed delta frame was not drawn', () => window.skinstreamViewer.lastFrameNumber === 2001);
    const compressed = await readDrawnFrame(page);
    const onKeyGrid = worstDistance(compressed.positions, Float32Array.from(onGrid(frames[1].positions, key.key)));
    const compressedAngle = worstAngleDegrees(compressed.normals, frames[1].normals);
    console.log(`compressed: ${onKeyGrid.worst} mm from the grid points coded, normals within ${compressedAngle.toFixed(2)} degrees`);
    assert.equal(onKeyGrid.worst, 0, 'compressed positions are the grid points coded');
    assert.ok(compressedAngle < 1.5, `compressed normals ${compressedAngle} degrees off`);
    const rejectedBefore = (await viewerState(page)).framesRejected;
    const damaged = encodeCompressedFrame(MeshoptEncoder, 2002, frames[2].positions, frames[2].normals, order, key.key);
    connection.send(patched(damaged.buffer, (v) => { for (let i = 0; i < 24; ++i) v.setUint8(80 + 32 + i, 0xff); }));
    await waitUntil(page, 'the damaged compressed frame was not rejected', (k) => window.skinstreamViewer.framesRejected === k, rejectedBefore + 1);
    await waitUntil(page, 'the status bar does not show why the compressed frame was rejected',
      () => /vertex codec refused the compressed positions/.test(document.getElementById('status-error').textContent));
    connection.send(encodeCompressedFrame(MeshoptEncoder, 2003, frames[2].positions, frames[2].normals, order, key.key).buffer);
    await waitUntil(page, 'the page stopped drawing after a damaged compressed frame', () => window.skinstreamViewer.lastFrameNumber === 2003);

    assert.ok(consoleErrors.some((line) => /^skinstream: frame rejected: Frame 900 is 300 bytes/.test(line)), 'a rejected frame reaches the console');
    assert.ok(consoleErrors.some((line) => /^skinstream: .*; closing the connection/.test(line)), 'a closed connection reaches the console');
    assert.deepEqual(pageErrors, [], 'the page threw');
    console.log(`${rejected + 1} bad frames and ${badSessions.length + 1} bad sessions shown and survived; ${consoleErrors.length} console error lines`);
  } finally {
    await browser.close();
    await server.close();
  }
}

main().then(() => {
  console.log('viewer_bad_input_test: PASS');
}, (error) => {
  console.error(`viewer_bad_input_test: FAIL: ${error.message}`);
  process.exitCode = 1;
});
