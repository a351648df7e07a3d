// The browser live preview against the real daemon: starts skinstreamd replaying a recording in a
// loop, opens the page it serves in the system Chromium (headless, WebGL through SwiftShader),
// and checks that frames arrive, are drawn and move, that the status bar shows the source rate,
// that a page naming the subject is served it and one naming an unknown subject is told it was
// refused, and that stopping the daemon puts up the banner. The page asks for parameters by default and
// evaluates the mesh on the GPU: its positions and normals, read back, are compared with the
// daemon's float buffers of the same frames (a second subscriber from node), as are those of the
// float, quantised and compressed encodings; the bytes a frame takes per encoding and these
// accuracies are printed as one JSON line. With SKINSTREAM_WEB_FRAME_COST=1 it also measures the
// page's main-thread time and frames per second per encoding (not asserted: timing is the
// machine's; 3 x 13 s of watching alone, so not in every test run):
//   SKINSTREAM_WEB_FRAME_COST=1 ctest --test-dir build -R web.viewer -V
//
// node viewer_test.mjs --daemon BIN --subject FILE --recording FILE --web-root DIR --out DIR
//                      [--cli SKINSTREAM] [--chromium /usr/bin/chromium]
import assert from 'node:assert/strict';
import { spawn, execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { launchChromium, waitUntil, sleep, readDrawnFrame } from './support/browser.mjs';
import { worstDistance, worstAngleDegrees } from './support/comparisons.mjs';
import { ReferenceSubscriber } from './support/reference_subscriber.mjs';

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
    arrivalLatencyMs: v.arrivalLatencyMs, clockSkewMs: v.clockSkewMs, encoding: v.encoding,
    framesRejected: v.framesRejected, gpuEvaluation: v.gpuEvaluation,
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

// The page's drawn positions and normals against the daemon's float buffers of the same frames,
// matched by frame number: the worst distance (mm), angle (degrees) and normal difference (length
// of the difference vector) over `count` frames.
async function compareWithDaemon(page, reference, count = 3) {
  const result = { frames: [], worstMm: 0, worstNormalDegrees: 0, worstNormalDifference: 0 };
  const seen = new Set();
  const deadline = Date.now() + 120000;
  for (let attempt = 0; attempt < 300 && result.frames.length < count && Date.now() < deadline; ++attempt) {
    const latest = await page.evaluate(() => window.skinstreamViewer.lastFrameKey);
    if (!latest || seen.has(latest)) {
      await sleep(50);
      continue;
    }
    // The reference's copy is taken as soon as the page's frame is known: null when the reference
    // never held it (it gave way to newer frames before the page drew it).
    let expected = null;
    const drawn = await readDrawnFrame(page, async (key) => {
      seen.add(key);
      expected = await reference.waitForFrame(key);
      return expected !== null;
    });
    if (drawn === null) continue;
    result.frames.push(drawn.frameNumber);
    result.worstMm = Math.max(result.worstMm, worstDistance(drawn.positions, expected.positions).worst);
    result.worstNormalDegrees = Math.max(result.worstNormalDegrees, worstAngleDegrees(drawn.normals, expected.normals));
    result.worstNormalDifference = Math.max(result.worstNormalDifference, worstDistance(drawn.normals, expected.normals).worst);
  }
  if (result.frames.length < count) {
    throw new Error(`only ${result.frames.length} of the page's frames were among the ${reference.frames.size} the reference subscriber held (errors: ${reference.errors.join('; ') || 'none'})`);
  }
  return result;
}

// Bytes a frame takes in each encoding (with normals and markers, as the page asks), and the
// Model's size: from subscribers in node, over one second each.
async function bytesPerFrame(httpPort) {
  const out = {};
  const wants = 1 | 4; // normals, markers
  for (const [name, encoding] of [['parameters', 3], ['compressed', 2], ['quantised', 1], ['float', 0]]) {
    const subscriber = new ReferenceSubscriber(`ws://127.0.0.1:${httpPort}/stream`, { encoding, wants, keep: 0 });
    await subscriber.opened;
    await sleep(1000);
    subscriber.close();
    const sizes = subscriber.frameBytes;
    out[name] = sizes.length > 0 ? Math.round(sizes.reduce((a, b) => a + b, 0) / sizes.length) : 0;
    if (name === 'parameters') out.model_message = subscriber.modelBytes;
  }
  return out;
}

// One page alone asking for `encoding`: after a warm-up, over a window, its frames per second
// and its main thread's time per frame drawn, from Chrome's own counters (Performance.getMetrics:
// TaskDuration, ScriptDuration) and from the page's (frameWorkMs: taking a frame in and drawing).
async function measureFrameCost(browser, url, encoding, { warmupMs = 3000, windowMs = 10000 } = {}) {
  const page = await browser.newPage({ viewport: { width: 800, height: 600 } });
  const cdp = await page.context().newCDPSession(page);
  await cdp.send('Performance.enable');
  await page.goto(`${url}?encoding=${encoding}`);
  await waitUntil(page, `the ${encoding} page rendered no frame`, () => window.skinstreamViewer && window.skinstreamViewer.framesRendered > 2, null, 60000);
  await sleep(warmupMs);
  const sample = async () => {
    const metrics = Object.fromEntries((await cdp.send('Performance.getMetrics')).metrics.map((m) => [m.name, m.value]));
    const v = await page.evaluate(() => ({ frames: window.skinstreamViewer.framesRendered, work: window.skinstreamViewer.frameWorkMs,
      received: window.skinstreamViewer.framesReceived }));
    return { ...v, task: metrics.TaskDuration, script: metrics.ScriptDuration, atMs: Date.now() };
  };
  const before = await sample();
  await sleep(windowMs);
  const after = await sample();
  await page.close();
  const frames = after.frames - before.frames;
  const seconds = (after.atMs - before.atMs) / 1000;
  const perFrame = (value) => (frames > 0 ? Number((value / frames).toFixed(2)) : null);
  return {
    encoding, frames_drawn: frames, frames_per_second: Number((frames / seconds).toFixed(2)),
    frames_received_per_second: Number(((after.received - before.received) / seconds).toFixed(1)),
    main_thread_task_ms_per_frame: perFrame(1000 * (after.task - before.task)),
    script_ms_per_frame: perFrame(1000 * (after.script - before.script)),
    page_frame_work_ms_per_frame: perFrame(after.work - before.work),
  };
}

// Seconds since the test started, on each phase's line: where its minutes go.
const startedMs = Date.now();
const phase = (what) => console.log(`[${((Date.now() - startedMs) / 1000).toFixed(1)} s] ${what}`);

async function main() {
  const options = parseArguments(process.argv.slice(2));
  // The daemon calls a subject file given without a name by the file's stem.
  options.subjectName = path.parse(options.subject).name;
  for (const file of [options.daemon, options.subject, options.recording, path.join(options.webRoot, 'index.html')]) {
    if (!fs.existsSync(file)) throw new Error(`missing input ${file}`);
  }
  fs.mkdirSync(options.out, { recursive: true });

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
    phase('daemon listening');
    browser = await launchChromium(options.chromium);
    let page = await browser.newPage({ viewport: { width: 800, height: 600 } });
    const pageErrors = [];
    page.on('pageerror', (error) => pageErrors.push(error.message));
    page.on('console', (message) => { if (message.type() === 'error') pageErrors.push(message.text()); });

    const url = `http://127.0.0.1:${ports.http}/`;
    const response = await page.goto(url);
    assert.equal(response.status(), 200, `GET ${url}`);
    await waitUntil(page, 'the page never set up window.skinstreamViewer', () => window.skinstreamViewer !== undefined);

    phase('page loaded');
    const start = await viewer(page);
    assert.ok(start.webgl, `no WebGL context was created (banner: ${start.bannerText})`);
    assert.equal(start.webglVersion, 2, 'the GPU evaluation needs WebGL2');
    console.log(`WebGL ${start.webglVersion} context created`);

    await waitUntil(page, 'no frame was rendered', () => window.skinstreamViewer.framesRendered > 0);
    const first = await viewer(page);
    console.log(`first frame: ${first.vertexCount} vertices, ${first.markerCount} markers, frame ${first.lastFrameNumber}`);
    assert.ok(first.vertexCount > 0 || first.markerCount > 0, 'MeshInfo has neither vertices nor markers');
    assert.ok(first.samplePositions.every(Number.isFinite), `sample positions not finite: ${first.samplePositions}`);

    phase('first frame drawn');
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

    phase('frames advance and move');
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
    phase('status bar rate settled');
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

    phase('latency window done');
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

    phase('pixels and screenshot');
    // Parameters by default, evaluated on the GPU: against the daemon's float buffers.
    assert.equal(after.encoding, 'parameters', 'the viewer did not ask for parameters by default');
    assert.ok(after.gpuEvaluation, 'parameters arrived but the GPU evaluation was not set up');
    const reference = new ReferenceSubscriber(`ws://127.0.0.1:${ports.http}/stream`);
    await reference.opened;
    const accuracy = { parameters: await compareWithDaemon(page, reference) };
    phase('parameters compared');
    // What each encoding costs the page, one page at a time (the default page closed first).
    const bytes = await bytesPerFrame(ports.http);
    await page.screenshot({ path: path.join(options.out, 'viewer_parameters.png') });
    await page.close();
    phase('bytes per frame');
    // The other encodings, each on a page of its own, the default page closed: two pages drawing
    // on the CPU draw each frame seconds late.
    for (const encoding of ['float', 'quantised', 'compressed']) {
      const other = await browser.newPage({ viewport: { width: 480, height: 360 } });
      other.on('pageerror', (error) => pageErrors.push(`${encoding} page: ${error.message}`));
      await other.goto(`${url}?encoding=${encoding}`);
      await waitUntil(other, `the ${encoding} page rendered no frame`, () => window.skinstreamViewer && window.skinstreamViewer.framesRendered > 2, null, 60000);
      assert.equal((await viewer(other)).encoding, encoding);
      accuracy[encoding] = await compareWithDaemon(other, reference);
      await other.close();
    }
    phase('other encodings compared');
    reference.close();
    for (const [encoding, a] of Object.entries(accuracy)) {
      console.log(`${encoding}: frames ${a.frames.join(', ')} within ${a.worstMm.toExponential(2)} mm and ${a.worstNormalDegrees.toFixed(3)} degrees of the daemon's float buffers`);
    }
    // The GPU evaluates in float as the daemon does; 0.1 mm is the issue's bound.
    assert.ok(accuracy.parameters.worstMm < 0.1, `GPU positions ${accuracy.parameters.worstMm} mm from the daemon's`);
    assert.ok(accuracy.parameters.worstNormalDegrees < 0.5, `GPU normals ${accuracy.parameters.worstNormalDegrees} degrees from the daemon's`);
    assert.equal(accuracy.float.worstMm, 0, 'float vertices are drawn as they were sent');
    assert.equal(accuracy.float.worstNormalDifference, 0, 'float normals are drawn as they were sent');
    // Half a grid step: 2,300 mm over 65,535 steps for the compressed key grid, the body's
    // extent for quantised; normals within the spec's 1.5 degrees (octahedral, 8 bits).
    assert.ok(accuracy.compressed.worstMm < 0.025, `compressed positions ${accuracy.compressed.worstMm} mm off`);
    assert.ok(accuracy.compressed.worstNormalDegrees < 1.5, `compressed normals ${accuracy.compressed.worstNormalDegrees} degrees off`);
    assert.ok(accuracy.quantised.worstMm < 0.025, `quantised positions ${accuracy.quantised.worstMm} mm off`);

    phase('accuracy asserted');
    const costs = [];
    if (process.env.SKINSTREAM_WEB_FRAME_COST === '1') {
      for (const encoding of ['parameters', 'float', 'compressed']) costs.push(await measureFrameCost(browser, url, encoding));
      phase('frame cost measured');
    }
    console.log(JSON.stringify({
      benchmark: 'web_viewer_frame_cost',
      renderer: 'headless Chromium, WebGL2 on SwiftShader (the CPU): GPU work is CPU time in the GPU process',
      viewport: '800x600', bytes_per_frame: bytes, model_message_bytes: bytes.model_message,
      gpu_evaluation: after.gpuEvaluation, accuracy, modes: costs.length > 0 ? costs : 'not measured (SKINSTREAM_WEB_FRAME_COST=1 measures them)',
    }));

    // A page naming the subject is served it and shows it in the menu; a name the daemon does not
    // serve is refused, and the page says so.
    const named = await browser.newPage({ viewport: { width: 480, height: 360 } });
    named.on('pageerror', (error) => pageErrors.push(`named page: ${error.message}`));
    await named.goto(`${url}?subject=${encodeURIComponent(options.subjectName)}`);
    await waitUntil(named, 'the page naming its subject rendered no frame', () => window.skinstreamViewer && window.skinstreamViewer.framesRendered > 2, null, 60000);
    assert.equal(await named.evaluate(() => window.skinstreamViewer.subject), options.subjectName);
    await waitUntil(named, 'no subject menu', () => document.getElementById('subject') !== null);
    assert.equal(await named.evaluate(() => document.getElementById('subject').value), options.subjectName);
    await named.goto(`${url}?subject=Nobody`);
    await waitUntil(named, 'no refusal shown for an unknown subject', () => /refused/.test(window.skinstreamViewer.bannerText));
    console.log(`unknown subject: "${await named.evaluate(() => window.skinstreamViewer.bannerText)}"`);
    await named.close();

    assert.deepEqual(pageErrors, [], 'errors on the page');

    phase('subject pages');
    // Stop the daemon: the page must say the connection (or source) is gone.
    page = await browser.newPage({ viewport: { width: 800, height: 600 } });
    await page.goto(url);
    await waitUntil(page, 'the page opened again rendered no frame', () => window.skinstreamViewer && window.skinstreamViewer.framesRendered > 0, null, 60000);
    daemon.kill('SIGTERM');
    const exit = await daemonExit;
    assert.equal(exit.code, 0, `skinstreamd did not exit cleanly on SIGTERM (${exit.code ?? exit.signal})`);
    await waitUntil(page, 'no banner after the daemon stopped', () => /closed|gone/i.test(window.skinstreamViewer.bannerText), null, 10000);
    assert.ok(await page.isVisible('#banner'), 'banner not visible');
    const gone = await viewer(page);
    console.log(`banner after SIGTERM: "${gone.bannerText}" (connection ${gone.connectionState})`);
    assert.notEqual(gone.connectionState, 'open');
    await page.screenshot({ path: path.join(options.out, 'viewer_disconnected.png') });
    phase('banner after the daemon stopped');
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
