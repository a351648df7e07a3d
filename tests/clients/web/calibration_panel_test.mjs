// The page's live calibration against the real daemon: a CMU capture replayed in a loop, its
// subject fitted to the body template. With the control token, "calibrate" records 3 s of the
// shown subject's range of motion, the daemon builds (skinstream build-subject in its own
// process), checks and swaps the new subject in; the panel follows it to "swapped in", the page
// takes the new MeshInfo and keeps drawing. A calibration the builder refuses (1 s of an actor
// barely moving is not asked here: a mesh that does not exist is refused at once) shows why.
//
// node calibration_panel_test.mjs --daemon skinstreamd --subject S --capture C3D --mesh OBJ --web-root DIR --out DIR
// (S: a subject built from C3D with the mesh OBJ, the swap_subjects fixture's first)
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { launchChromium } from './support/browser.mjs';
import { parseArguments, startDaemon, waitFor } from './support/test_run.mjs';

async function main() {
  const options = parseArguments(process.argv.slice(2), ['daemon', 'subject', 'capture', 'mesh', 'webRoot', 'out']);
  const out = path.join(options.out, `calibration_panel_${process.pid}`);
  fs.rmSync(out, { recursive: true, force: true });
  fs.mkdirSync(out, { recursive: true });
  const subject = options.subject;
  const token = 'stage-token-calibrate-2026';
  const tokenFile = path.join(out, 'control-token');
  fs.writeFileSync(tokenFile, `${token}\n`, { mode: 0o600 });
  const configFile = path.join(out, 'config.json');
  fs.writeFileSync(configFile, JSON.stringify({ calibration_dir: path.join(out, 'calibrations'), deform_threads: 1 }));
  const { daemon, ports } = await startDaemon(options.daemon, [
    '--config', configFile, '--subject', subject, '--replay', options.capture, '--loop', '--web-root', options.webRoot, '--control-token-file', tokenFile,
  ], out);

  let browser = null;
  try {
    browser = await launchChromium(options.chromium);
    const page = await browser.newPage({ viewport: { width: 800, height: 600 } });
    const pageErrors = [];
    page.on('pageerror', (error) => pageErrors.push(error.message));
    await page.goto(`http://127.0.0.1:${ports.http}/?encoding=float`);
    await page.click('#takes summary');
    const text = (id) => page.$eval(id, (element) => element.textContent);
    // Frames drawn, not the frame number shown: the take loops every 810 frames, so a number
    // taken within 60 of the end never grows by 60 (the test failed so once in a run).
    const framesDrawn = () => page.evaluate(() => window.skinstreamViewer.framesRendered);
    await waitFor('the page drew no frame', async () => (await framesDrawn()) > 0);
    await waitFor('the panel never showed the subject', async () => (await text('#calibrate-state')) === 'no calibration yet');
    await page.fill('#control-token', token);

    // A body the daemon cannot find: refused at once, nothing starts.
    await page.fill('#calibrate-seconds', '3');
    await page.fill('#calibrate-mesh', '/no/such/body.obj');
    await page.click('#calibrate');
    await waitFor('a missing mesh was not refused', async () => (await text('#calibrate-answer')).startsWith('400: mesh'));

    await page.fill('#calibrate-mesh', options.mesh);
    await page.click('#calibrate');
    await waitFor('the calibration did not start', async () => (await text('#calibrate-answer')).endsWith(': recording'));
    await waitFor('the panel did not follow the recording', async () => /^recording the range of motion: \d+ of 360 frames$/.test(await text('#calibrate-state')));
    const swapped = await waitFor('the subject was not swapped in', async () => {
      const shown = await text('#calibrate-state');
      if (shown.startsWith('failed')) throw new Error(shown);
      return shown.startsWith('swapped in') ? shown : null;
    }, 120000);
    const health = await (await fetch(`http://127.0.0.1:${ports.http}/health`)).json();
    assert.equal(health.subjects[0].model_epoch, 1);
    assert.notEqual(health.subjects[0].file, subject, 'the daemon still serves the first subject file');
    // The page took the new MeshInfo and draws on.
    const before = await framesDrawn();
    await waitFor('the page stopped drawing after the swap', async () => (await framesDrawn()) >= before + 60);
    assert.deepEqual(pageErrors, [], 'errors on the page');
    const banner = await page.$eval('body', (body) => body.innerText);
    assert.equal(/protocol error/i.test(banner), false, 'the page shows a protocol error');
    console.log(`calibrated on the page: ${swapped}`);
  } finally {
    if (browser) await browser.close();
    daemon.kill('SIGTERM');
  }
}

main().then(() => console.log('ok'), (error) => {
  console.error(error.stack || String(error));
  process.exit(1);
});
