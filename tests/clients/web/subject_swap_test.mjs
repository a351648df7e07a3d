// The page across a subject swapped at run time, in Chromium against the real daemon: skinstreamd
// serves one subject file and the control API (POST /subjects/NAME/file) swaps in another (two
// fits of one body to two takes, tests/support/make_swap_subjects.sh). The page that was open all
// along keeps drawing without reconnecting, shows no error and rejects no frame, and what it
// draws after the swap is the new subject: its positions, evaluated on the GPU from the new
// Model, are the daemon's own float buffers of the same frames (a float subscriber from node).
// Then a page asking for the compressed encoding across a swap back to the first file: its
// decoder starts again from the new MeshInfo's key frame, and it draws the daemon's vertices.
//
// node subject_swap_test.mjs --daemon BIN --first FILE --second FILE --recording C3D
//                            --web-root DIR --out DIR [--chromium /usr/bin/chromium]
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { launchChromium, waitUntil, sleep, readDrawnFrame } from './support/browser.mjs';
import { parseArguments, startDaemon, waitFor } from './support/test_run.mjs';
import { worstDistance } from './support/comparisons.mjs';
import { ReferenceSubscriber } from './support/reference_subscriber.mjs';

const NAME = 'body';
const TOKEN = 'swap-page-token-0123456789';

async function control(port, method, route, body) {
  const response = await fetch(`http://127.0.0.1:${port}${route}`, {
    method, headers: { Authorization: `Bearer ${TOKEN}`, 'Content-Type': 'application/json' },
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  const text = await response.text();
  assert.ok(response.ok, `${method} ${route}: ${response.status} ${text}`);
  return JSON.parse(text);
}

// POST /subjects/NAME/file, then GET /subjects/NAME until the change is done; returns the
// daemon's system clock (ns) when it was seen done: frames it received later are the new subject's.
async function swap(port, file) {
  await control(port, 'POST', `/subjects/${NAME}/file`, { file });
  const subject = await waitFor(`the swap to ${file} did not finish`, async () => {
    const state = await control(port, 'GET', `/subjects/${NAME}`);
    return ['done', 'failed'].includes(state.change.state) ? state : null;
  }, 60000);
  assert.equal(subject.change.state, 'done', JSON.stringify(subject));
  assert.equal(subject.file, file);
  return BigInt(Date.now()) * 1000000n;
}

const viewer = (page) => page.evaluate(() => {
  const v = window.skinstreamViewer;
  return {
    framesReceived: v.framesReceived, framesRendered: v.framesRendered, framesRejected: v.framesRejected,
    lastFrameNumber: v.lastFrameNumber, lastFrameKey: v.lastFrameKey, vertexCount: v.vertexCount, markerCount: v.markerCount,
    encoding: v.encoding, subject: v.subject, connectionState: v.connectionState, reconnects: v.reconnects,
    bannerText: v.bannerText, lastError: v.lastError, gpuEvaluation: v.gpuEvaluation, frameNumbersWentBack: v.frameNumbersWentBack,
  };
});

// Seconds since the test started, on each phase's line: where its time goes.
const startedMs = Date.now();
const phase = (what) => console.log(`[${((Date.now() - startedMs) / 1000).toFixed(1)} s] ${what}`);

const receiveTime = (key) => BigInt(key.split('@')[1]);

// The page's drawn positions against the daemon's float buffers of the same frames, for `count`
// frames the daemon received after `afterNs`: the worst distance (mm).
async function compareAfter(page, reference, afterNs, count = 3) {
  const seen = new Set();
  let worst = 0;
  let compared = 0;
  const deadline = Date.now() + 60000;
  while (compared < count && Date.now() < deadline) {
    const latest = await page.evaluate(() => window.skinstreamViewer.lastFrameKey);
    if (seen.has(latest) || receiveTime(latest) <= afterNs) {
      await sleep(50);
      continue;
    }
    let expected = null;
    const drawn = await readDrawnFrame(page, async (key) => {
      seen.add(key);
      expected = receiveTime(key) > afterNs ? await reference.waitForFrame(key) : null;
      return expected !== null;
    });
    if (drawn === null) continue;
    worst = Math.max(worst, worstDistance(drawn.positions, expected.positions).worst);
    ++compared;
  }
  assert.equal(compared, count, `only ${compared} of the page's frames after the swap were held by the reference (errors: ${reference.errors.join('; ') || 'none'})`);
  return worst;
}

// The page goes on from `before` (its counters just after the swap): frames drawn and received
// keep counting; it never reconnected, shows no error and no banner.
async function expectCarriesOn(page, before, what) {
  await waitUntil(page, `${what}: the page stopped drawing after the swap`, ([rendered, received]) =>
    window.skinstreamViewer.framesRendered > rendered + 10 && window.skinstreamViewer.framesReceived > received + 10,
  [before.framesRendered, before.framesReceived], 60000);
  const after = await viewer(page);
  assert.equal(after.connectionState, 'open', `${what}: ${JSON.stringify(after)}`);
  assert.equal(after.reconnects, 0, `${what}: the page reconnected`);
  assert.equal(after.framesRejected, 0, `${what}: frames rejected: ${after.lastError}`);
  assert.equal(after.lastError, '', `${what}: an error on the page`);
  assert.equal(after.bannerText, '', `${what}: a banner`);
  assert.equal(after.subject, NAME);
  return after;
}

async function main() {
  const options = parseArguments(process.argv.slice(2), ['daemon', 'first', 'second', 'recording', 'webRoot', 'out']);
  const out = path.join(options.out, `subject_swap_${process.pid}`);
  fs.rmSync(out, { recursive: true, force: true });
  fs.mkdirSync(out, { recursive: true });
  const tokenFile = path.join(out, 'control-token');
  fs.writeFileSync(tokenFile, `${TOKEN}\n`, { mode: 0o600 });
  // Half speed: the page on SwiftShader draws a fraction of the frames either way.
  const { daemon, ports } = await startDaemon(options.daemon, [
    '--subject', `${NAME}=${options.first}`, '--replay', options.recording, '--replay-subject', NAME, '--loop', '--speed', '0.5',
    '--web-root', options.webRoot,
    '--control-token-file', tokenFile,
  ], out);

  let browser = null;
  let reference = null;
  try {
    phase('daemon listening');
    browser = await launchChromium(options.chromium);
    const pageErrors = [];
    const openPage = async (query) => {
      const page = await browser.newPage({ viewport: { width: 480, height: 360 } });
      page.on('pageerror', (error) => pageErrors.push(error.message));
      page.on('console', (message) => { if (message.type() === 'error') pageErrors.push(message.text()); });
      await page.goto(`http://127.0.0.1:${ports.http}/${query}`);
      await waitUntil(page, `the page ${query} drew no frame`, () => window.skinstreamViewer && window.skinstreamViewer.framesRendered > 5, null, 60000);
      return page;
    };
    reference = new ReferenceSubscriber(`ws://127.0.0.1:${ports.http}/stream`);
    await reference.opened;

    // The default page: parameters, evaluated on the GPU.
    const page = await openPage('');
    phase('parameters page drawing');
    const before = await viewer(page);
    assert.equal(before.encoding, 'parameters');
    assert.ok(before.gpuEvaluation, 'no GPU evaluation before the swap');
    const worstBefore = await compareAfter(page, reference, 0n, 1);
    const swappedNs = await swap(ports.http, options.second);
    phase('swapped');
    const after = await expectCarriesOn(page, await viewer(page), 'parameters');
    assert.equal(after.vertexCount, before.vertexCount);
    assert.ok(after.gpuEvaluation, 'no GPU evaluation after the swap');
    // Drawn from the new Model: the daemon's vertices of the new subject.
    const worstAfter = await compareAfter(page, reference, swappedNs);
    phase('parameters page compared after the swap');
    console.log(`parameters: ${after.framesRendered - before.framesRendered} frames drawn across the swap; drawn positions ` +
      `within ${worstBefore.toExponential(2)} mm of the daemon's before it, ${worstAfter.toExponential(2)} mm after`);
    assert.ok(worstAfter < 0.1, `after the swap the page draws ${worstAfter} mm from the daemon's vertices`);

    // A compressed page across the swap back to the first file (alone: two pages drawing on
    // SwiftShader take turns for the CPU).
    await page.close();
    const compressed = await openPage('?encoding=compressed');
    phase('compressed page drawing');
    const compressedBefore = await viewer(compressed);
    assert.equal(compressedBefore.encoding, 'compressed');
    const backNs = await swap(ports.http, options.first);
    phase('swapped back');
    await expectCarriesOn(compressed, await viewer(compressed), 'compressed');
    const compressedWorst = await compareAfter(compressed, reference, backNs, 2);
    phase('compressed page compared after the swap back');
    console.log(`swapped back: the compressed page draws within ${compressedWorst.toExponential(2)} mm of the daemon's vertices`);
    assert.ok(compressedWorst < 0.025, `the compressed page draws ${compressedWorst} mm from the daemon's vertices`);
    assert.deepEqual(reference.errors, [], 'the float subscriber');
    assert.deepEqual(pageErrors, [], 'errors on the pages');
  } finally {
    if (reference) reference.close();
    if (browser) await browser.close();
    daemon.kill('SIGTERM');
  }
}

main().then(() => console.log('subject_swap_test: PASS'), (error) => {
  console.error(`subject_swap_test: FAIL: ${error.stack || error}`);
  process.exit(1);
});
