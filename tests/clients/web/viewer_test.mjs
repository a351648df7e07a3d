// The browser live preview against the real daemon: starts skinstreamd replaying a recording in a
// loop, opens the page it serves in the system Chromium (headless, WebGL through SwiftShader),
// and checks that frames arrive, are drawn and move, that the status bar shows the source rate,
// that a page naming the subject (protocol version 2) is served it and one naming an unknown
// subject is told it was refused, and that stopping the daemon puts up the banner.
//
// node viewer_test.mjs --daemon BIN --subject FILE --recording FILE --web-root DIR --out DIR
//                      [--cli SKINSTREAM] [--chromium /usr/bin/chromium]
import assert from 'node:assert/strict';
import { spawn, execFileSync } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const repoRoot = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../..');

function parseArguments(argv) {
  const options = { chromium: '/usr/bin/chromium' };
  for (let i = 0; i < argv.length; i += 2) {
    const name = argv[i].replace(/^--/, '');
    if (i + 1 >= argv.length) throw new Error(`${argv[i]} needs a value`);
    options[name.replace(/-([a-z])/g, (_, c) => c.toUpperCase())] = argv[i + 1];
  }
  for (const required of ['daemon', 'subject', 'recording', 'webRoot', 'out']) {
    if (!options[required]) throw new Error(`missing --${required.replace(/[A-Z]/g, (c) => `-${c.toLowerCase()}`)}`);
  }
  return options;
}

// The page's decoder (clients/web/src/protocol.js, plain ES module) on the protocol's golden
// byte fixtures, which were written from the spec independently of both encoder and decoder.
async function checkGoldenFixtures() {
  const protocol = await import(path.join(repoRoot, 'clients/web/src/protocol.js'));
  const fixtureDir = path.join(repoRoot, 'tests/protocol/fixtures/subscriber');
  const read = (name) => {
    const bytes = fs.readFileSync(path.join(fixtureDir, name));
    return new DataView(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.length));
  };
  const close = (actual, expected, what) => assert.ok(
    actual.length === expected.length && expected.every((x, i) => Math.abs(actual[i] - x) <= 1e-4 * Math.max(1, Math.abs(x))),
    `${what}: ${Array.from(actual)} != ${expected}`);

  assert.deepEqual(new Uint8Array(protocol.encodeHello(protocol.Wants.NORMALS | protocol.Wants.MARKERS)),
    new Uint8Array(read('hello.bin').buffer), 'Hello bytes');

  const meshView = read('mesh_info.bin');
  assert.equal(protocol.readHeader(meshView), protocol.MessageType.MESH_INFO);
  const info = protocol.decodeMeshInfo(meshView);
  assert.equal(info.vertexCount, 4);
  assert.equal(info.sourceRateHz, 120);
  assert.deepEqual(Array.from(info.faces), [0, 1, 2, 0, 2, 3]);
  assert.deepEqual(Array.from(info.dominantPart), [0, 1, 255, 1]);
  assert.deepEqual(Array.from(info.markerTriangles), [0, 1, 2]);
  assert.deepEqual(info.markerNames, ['LSHO', 'RSHO', 'C7']);

  const positions = [0, 100, 5, 65535, 131170, 5, 0, 2100, 5];
  const normals = [1, 0, 0, 0, -1, 0, 0, 0, 1];
  const markers = [1.5, 2.5, 3.5, -4.0, 5.0, 6.25];
  for (const name of ['frame_float.bin', 'frame_quantised.bin', 'frame_markers_only.bin']) {
    const view = read(name);
    assert.equal(protocol.readHeader(view), protocol.MessageType.FRAME, name);
    const header = new protocol.FrameHeader();
    header.read(view);
    assert.equal(header.frameNumber, 1234, name);
    assert.ok(Math.abs(header.receiveTimeNs - 1.7e18) < 1e3, `${name}: receive time ${header.receiveTimeNs}`);
    assert.equal(header.markersFilled, 3, name);
    assert.equal(header.framesDroppedPipeline, 7, name);
    assert.equal(header.framesDroppedSubscriber, 2, name);
    const vertexCount = name === 'frame_markers_only.bin' ? 0 : 3;
    const out = { positions: new Float32Array(3 * vertexCount), normals: new Float32Array(3 * vertexCount),
      markers: new Float32Array(6), markerStatus: new Uint8Array(2) };
    protocol.decodeFrameArrays(view, header, out);
    if (vertexCount > 0) {
      close(out.positions, positions, `${name} positions`);
      close(out.normals, normals, `${name} normals`);
    }
    close(out.markers, markers, `${name} markers`);
    assert.deepEqual(Array.from(out.markerStatus), [0, 2], `${name} marker status`);
  }

  const status = protocol.decodeStatus(read('status.bin'));
  assert.equal(status.stateName, 'disconnected');
  assert.equal(status.framesReceived, 1000);
  assert.equal(status.detail, 'vicon 127.0.0.1:801: connection refused');

  // Version 2 (a page naming a subject): Hello, MeshInfo and Status with the subject, a Frame with
  // the timecode before its arrays.
  assert.deepEqual(new Uint8Array(protocol.encodeHello(protocol.Wants.NORMALS | protocol.Wants.MARKERS | protocol.Wants.PACED,
    { subject: 'Actor2', encoding: protocol.Encoding.PARAMETERS, token: 'stage-token' })),
  new Uint8Array(read('hello_v2.bin').buffer), 'version 2 Hello bytes');
  const infoV2 = protocol.decodeMeshInfo(read('mesh_info_v2.bin'));
  assert.equal(infoV2.subject, 'Actor2');
  assert.equal(infoV2.encoding, protocol.Encoding.COMPRESSED);
  assert.deepEqual(infoV2.markerNames, ['LSHO', 'RSHO', 'C7']);
  const statusV2 = protocol.decodeStatus(read('status_v2.bin'));
  assert.equal(statusV2.stateName, 'refused');
  assert.equal(statusV2.subject, 'Actor3');
  assert.equal(statusV2.subjectPresent, false);
  const frameV2 = read('frame_v2_float.bin');
  const headerV2 = new protocol.FrameHeader();
  headerV2.read(frameV2);
  assert.equal(headerV2.frameNumber, 1234);
  assert.equal(headerV2.framesDroppedSubscriber, 2);
  const outV2 = { positions: new Float32Array(9), normals: new Float32Array(0), markers: new Float32Array(6), markerStatus: new Uint8Array(2) };
  protocol.decodeFrameArrays(frameV2, headerV2, outV2);
  close(outV2.positions, positions, 'version 2 positions');
  close(outV2.markers, markers, 'version 2 markers');
  assert.deepEqual(Array.from(outV2.markerStatus), [0, 2], 'version 2 marker status');

  // A receiver rejects a corrupt header and a truncated message.
  const bad = read('frame_float.bin');
  bad.setUint8(0, 0x58);
  assert.throws(() => protocol.readHeader(bad), /magic/);
  const truncated = new DataView(read('frame_float.bin').buffer.slice(0, 100));
  assert.throws(() => protocol.readHeader(truncated), /payload/);
  console.log('decoder matches the golden fixtures');
}

// page.waitForFunction with a message that says what never happened.
async function waitUntil(page, what, predicate, argument = null, timeout = 30000) {
  try {
    await page.waitForFunction(predicate, argument, { timeout });
  } catch (error) {
    const state = await page.evaluate(() => window.skinstreamViewer && {
      framesReceived: window.skinstreamViewer.framesReceived, framesRendered: window.skinstreamViewer.framesRendered,
      connectionState: window.skinstreamViewer.connectionState, bannerText: window.skinstreamViewer.bannerText,
    }).catch(() => null);
    throw new Error(`${what} (after ${timeout} ms; viewer ${JSON.stringify(state)}): ${error.message.split('\n')[0]}`);
  }
}

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// Waits for the daemon's ports file; fails at once if the daemon exits first.
async function waitForPorts(daemon, portsFile, logFile) {
  for (let waited = 0; waited < 60000; waited += 100) {
    if (daemon.exitCode !== null || daemon.signalCode !== null) {
      throw new Error(`skinstreamd exited (${daemon.exitCode ?? daemon.signalCode}) before listening; log:\n${fs.readFileSync(logFile, 'utf8').slice(-2000)}`);
    }
    try {
      const ports = JSON.parse(fs.readFileSync(portsFile, 'utf8'));
      if (ports.http > 0) return ports;
    } catch { /* not written yet, or half written */ }
    await sleep(100);
  }
  throw new Error(`skinstreamd wrote no ports file ${portsFile} within 60 s`);
}

const viewer = (page) => page.evaluate(() => {
  const v = window.skinstreamViewer;
  return {
    framesReceived: v.framesReceived, framesRendered: v.framesRendered, framesSkipped: v.framesSkipped,
    lastFrameNumber: v.lastFrameNumber, vertexCount: v.vertexCount, markerCount: v.markerCount,
    sampleIsMarkers: v.sampleIsMarkers, samplePositions: v.samplePositions, sourceRateHz: v.sourceRateHz,
    announcedRateHz: v.announcedRateHz, connectionState: v.connectionState, webgl: v.webgl,
    webglVersion: v.webglVersion, bannerText: v.bannerText, latencyMs: v.latencyMs,
    arrivalLatencyMs: v.arrivalLatencyMs, clockSkewMs: v.clockSkewMs, quantised: v.quantised,
  };
});

// Two animation frames: one to apply a change, one to have drawn it.
const nextPaint = (page) => page.evaluate(() => new Promise((resolve) =>
  requestAnimationFrame(() => requestAnimationFrame(resolve))));

// Pixels of the WebGL canvas that are not the background colour.
const paintedPixels = (page) => page.evaluate(() => {
  const source = document.querySelector('#viewport canvas');
  const copy = document.createElement('canvas');
  copy.width = source.width;
  copy.height = source.height;
  const context = copy.getContext('2d');
  context.drawImage(source, 0, 0);
  const pixels = context.getImageData(0, 0, copy.width, copy.height).data;
  let count = 0;
  for (let i = 0; i < pixels.length; i += 4) {
    if (Math.abs(pixels[i] - 0x20) + Math.abs(pixels[i + 1] - 0x24) + Math.abs(pixels[i + 2] - 0x2b) > 60) ++count;
  }
  return count;
});

async function main() {
  const options = parseArguments(process.argv.slice(2));
  // The daemon calls a subject file given without a name by the file's stem.
  options.subjectName = path.parse(options.subject).name;
  await checkGoldenFixtures();
  if (!fs.existsSync(options.chromium)) {
    throw new Error(`chromium not found at ${options.chromium} (Debian 12: apt-get install chromium)`);
  }
  for (const file of [options.daemon, options.subject, options.recording, path.join(options.webRoot, 'index.html')]) {
    if (!fs.existsSync(file)) throw new Error(`missing input ${file}`);
  }
  fs.mkdirSync(options.out, { recursive: true });
  // playwright-core is pinned in clients/web/package.json and installed by clients/web/build.sh.
  const { chromium } = createRequire(path.join(repoRoot, 'clients/web/package.json'))('playwright-core');

  // The rate the recording was captured at, from the offline CLI when it is given.
  let expectedRateHz = 0;
  if (options.cli) {
    const info = JSON.parse(execFileSync(options.cli, ['info', options.recording, '--json'], { encoding: 'utf8' }));
    expectedRateHz = Number(info.rate_hz);
  }

  const portsFile = path.join(options.out, 'ports.json');
  const logFile = path.join(options.out, 'skinstreamd.log');
  fs.rmSync(portsFile, { force: true });
  const log = fs.openSync(logFile, 'w');
  const daemon = spawn(options.daemon, [
    '--subject', options.subject, '--replay', options.recording, '--loop',
    '--http-port', '0', '--sub-port', '0', '--ports-file', portsFile, '--web-root', options.webRoot,
  ], { stdio: ['ignore', log, log] });
  const daemonExit = new Promise((resolve) => daemon.on('exit', (code, signal) => resolve({ code, signal })));
  // ctest's timeout or a Ctrl-C must not leave the daemon running.
  for (const signal of ['SIGINT', 'SIGTERM']) {
    process.on(signal, () => {
      daemon.kill('SIGKILL');
      process.exit(1);
    });
  }

  let browser = null;
  try {
    const ports = await waitForPorts(daemon, portsFile, logFile);
    browser = await chromium.launch({
      executablePath: options.chromium,
      headless: true,
      args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
        '--disable-background-networking', '--disable-component-update', '--disable-sync',
        '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
    });
    const page = await browser.newPage({ viewport: { width: 800, height: 600 } });
    const pageErrors = [];
    page.on('pageerror', (error) => pageErrors.push(error.message));
    page.on('console', (message) => { if (message.type() === 'error') pageErrors.push(message.text()); });

    const url = `http://127.0.0.1:${ports.http}/`;
    const response = await page.goto(url);
    assert.equal(response.status(), 200, `GET ${url}`);
    await waitUntil(page, 'the page never set up window.skinstreamViewer', () => window.skinstreamViewer !== undefined);

    const start = await viewer(page);
    assert.ok(start.webgl, `no WebGL context was created (banner: ${start.bannerText})`);
    console.log(`WebGL ${start.webglVersion} context created`);

    await waitUntil(page, 'no frame was rendered', () => window.skinstreamViewer.framesRendered > 0);
    const first = await viewer(page);
    console.log(`first frame: ${first.vertexCount} vertices, ${first.markerCount} markers, frame ${first.lastFrameNumber}`);
    assert.ok(first.vertexCount > 0 || first.markerCount > 0, 'MeshInfo has neither vertices nor markers');
    assert.ok(first.samplePositions.every(Number.isFinite), `sample positions not finite: ${first.samplePositions}`);

    // Two later frames: the counters grow, the frame number advances, the body moves. A looped
    // recording may wrap between two snapshots, so a few pairs are tried.
    let advanced = false;
    let moved = false;
    let previous = first;
    for (let attempt = 0; attempt < 20 && !(advanced && moved); ++attempt) {
      await waitUntil(page, 'framesReceived and framesRendered stopped growing', ([rendered, received]) =>
        window.skinstreamViewer.framesRendered > rendered + 5 && window.skinstreamViewer.framesReceived > received,
      [previous.framesRendered, previous.framesReceived]);
      const current = await viewer(page);
      if (current.lastFrameNumber > previous.lastFrameNumber) advanced = true;
      if (current.samplePositions.some((x, i) => Math.abs(x - previous.samplePositions[i]) > 1e-3)) moved = true;
      previous = current;
    }
    assert.ok(advanced, 'the rendered frame number never increased');
    assert.ok(moved, `the sampled ${previous.sampleIsMarkers ? 'marker' : 'vertex'} positions never changed`);
    console.log(`frames received ${previous.framesReceived}, rendered ${previous.framesRendered}, skipped ${previous.framesSkipped}`);

    // The status bar's rate. It counts frame numbers per second of arrival, so it settles on the
    // source rate once the path to the page is in a steady state (a loaded machine may first
    // build a backlog in the socket buffers): poll until it is near, for up to 30 s.
    let after = await viewer(page);
    const sourceHz = expectedRateHz > 0 ? expectedRateHz : after.announcedRateHz;
    assert.ok(sourceHz > 0, 'the source rate is unknown (neither the CLI nor MeshInfo/Status gave it)');
    let rateText = '';
    let shownHz = 0;
    for (let waited = 0; waited <= 30000; waited += 500) {
      [rateText, shownHz] = await page.evaluate(() => {
        const field = document.getElementById('status-rate');
        return [field.textContent, Number(field.dataset.hz)];
      });
      if (Math.abs(shownHz - sourceHz) < 0.2 * sourceHz) break;
      await sleep(500);
    }
    after = await viewer(page);
    console.log(`status bar rate "${rateText}" (${shownHz} Hz), source ${sourceHz} Hz`);
    // Over 5 s: how many frames arrived and were drawn, and the latency from the daemon's receive
    // to the page's draw (its level is not asserted: a loaded machine stretches it).
    const latencies = [];
    const arrivals = [];
    const windowStart = await viewer(page);
    const windowStartMs = Date.now();
    const trend = []; // [seconds into the window, latency of the frame drawn last]
    for (let i = 0; i < 20; ++i) {
      await sleep(250);
      const sample = await viewer(page);
      latencies.push(sample.latencyMs);
      arrivals.push(sample.arrivalLatencyMs);
      trend.push([(Date.now() - windowStartMs) / 1000, sample.latencyMs]);
    }
    const windowEnd = await viewer(page);
    latencies.sort((a, b) => a - b);
    arrivals.sort((a, b) => a - b);
    // No backlog: the page draws the newest frame and drops the rest, so the latency of what it
    // draws stays level. A page that queued frames would fall further behind every second (at
    // 120 Hz in and ~12 frames/s drawn, by ~900 ms per second).
    const meanT = trend.reduce((a, [t]) => a + t, 0) / trend.length;
    const meanL = trend.reduce((a, [, l]) => a + l, 0) / trend.length;
    const slope = trend.reduce((a, [t, l]) => a + (t - meanT) * (l - meanL), 0) /
      trend.reduce((a, [t]) => a + (t - meanT) ** 2, 0);
    console.log(`over 5 s: ${((windowEnd.framesReceived - windowStart.framesReceived) / 5).toFixed(1)} frames/s received, ` +
      `${((windowEnd.framesRendered - windowStart.framesRendered) / 5).toFixed(1)} drawn, ` +
      `${windowEnd.framesSkipped - windowStart.framesSkipped} skipped by the page; daemon receive -> page draw median ` +
      `${latencies[10].toFixed(1)} ms (max ${latencies[19].toFixed(1)}, trend ${slope.toFixed(1)} ms per s), ` +
      `daemon publish -> worker arrival median ${arrivals[10].toFixed(1)} ms (max ${arrivals[19].toFixed(1)}); ` +
      `page clock - system clock ${windowEnd.clockSkewMs.toFixed(1)} ms`);
    assert.ok(slope < 100, `the drawn frames fall behind by ${slope.toFixed(0)} ms every second: a backlog`);
    assert.match(rateText, /Hz/);
    assert.ok(Math.abs(shownHz - sourceHz) < 0.2 * sourceHz, `status bar shows ${shownHz} Hz, the source runs at ${sourceHz} Hz`);

    // What is drawn: hiding the mesh (or, markers only, the markers) must remove many pixels.
    const hideKey = after.vertexCount > 0 ? 'v' : 'm';
    await nextPaint(page);
    const shown = await paintedPixels(page);
    await page.keyboard.press(hideKey);
    await nextPaint(page);
    const hidden = await paintedPixels(page);
    await page.keyboard.press(hideKey);
    await nextPaint(page);
    console.log(`painted pixels: ${shown} with the ${hideKey === 'v' ? 'mesh' : 'markers'}, ${hidden} without`);
    assert.ok(shown > hidden + 200, `toggling ${hideKey === 'v' ? 'the mesh' : 'the markers'} changes only ${shown - hidden} pixels`);

    const screenshot = path.join(options.out, 'viewer.png');
    await page.screenshot({ path: screenshot });
    assert.deepEqual([...fs.readFileSync(screenshot).subarray(0, 4)], [0x89, 0x50, 0x4e, 0x47], 'screenshot is not a PNG');
    console.log(`screenshot ${screenshot}`);

    // The float encoding on a second page (the viewer asks for the quantised one by default).
    assert.ok(after.quantised, 'the viewer did not ask for the quantised encoding by default');
    const floatPage = await browser.newPage({ viewport: { width: 480, height: 360 } });
    floatPage.on('pageerror', (error) => pageErrors.push(`float page: ${error.message}`));
    await floatPage.goto(`${url}?quantised=0`);
    await waitUntil(floatPage, 'the float page rendered no frame', () => window.skinstreamViewer && window.skinstreamViewer.framesRendered > 2);
    const float = await viewer(floatPage);
    assert.equal(float.quantised, false);
    assert.equal(float.vertexCount, after.vertexCount);
    assert.ok(float.samplePositions.every(Number.isFinite), 'float sample positions not finite');
    await floatPage.close();

    // A page naming the subject speaks version 2 and shows its subject in the menu; a name the
    // daemon does not serve is refused, and the page says so.
    const named = await browser.newPage({ viewport: { width: 480, height: 360 } });
    named.on('pageerror', (error) => pageErrors.push(`named page: ${error.message}`));
    await named.goto(`${url}?subject=${encodeURIComponent(options.subjectName)}`);
    await waitUntil(named, 'the page naming its subject rendered no frame', () => window.skinstreamViewer && window.skinstreamViewer.framesRendered > 2);
    assert.equal(await named.evaluate(() => window.skinstreamViewer.subject), options.subjectName);
    assert.equal(await named.evaluate(() => document.getElementById('subject').value), options.subjectName);
    await named.goto(`${url}?subject=Nobody`);
    await waitUntil(named, 'no refusal shown for an unknown subject', () => /refused/.test(window.skinstreamViewer.bannerText));
    console.log(`unknown subject: "${await named.evaluate(() => window.skinstreamViewer.bannerText)}"`);
    await named.close();

    assert.deepEqual(pageErrors, [], 'errors on the page');

    // Stop the daemon: the page must say the connection (or source) is gone.
    daemon.kill('SIGTERM');
    const exit = await daemonExit;
    assert.equal(exit.code, 0, `skinstreamd did not exit cleanly on SIGTERM (${exit.code ?? exit.signal})`);
    await waitUntil(page, 'no banner after the daemon stopped', () => /closed|gone/i.test(window.skinstreamViewer.bannerText), null, 10000);
    assert.ok(await page.isVisible('#banner'), 'banner not visible');
    const gone = await viewer(page);
    console.log(`banner after SIGTERM: "${gone.bannerText}" (connection ${gone.connectionState})`);
    assert.notEqual(gone.connectionState, 'open');
    await page.screenshot({ path: path.join(options.out, 'viewer_disconnected.png') });
  } finally {
    if (browser) await browser.close();
    if (daemon.exitCode === null && daemon.signalCode === null) daemon.kill('SIGKILL');
    fs.closeSync(log);
  }
}

main().then(() => {
  console.log('viewer_test: PASS');
}, (error) => {
  console.error(`viewer_test: FAIL: ${error.message}`);
  process.exitCode = 1;
});
