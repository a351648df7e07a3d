// The page's take controls in Chromium against the real daemon with a record_dir and a control
// token: a wrong token is refused (the answer says 403) and starts nothing; the right one starts
// a take named on the page and stops it, the panel follows the recording from /health, and the
// take's take.json says who started it. Typing the token does not toggle the display (its
// letters are the toggles' keys).
//
// node takes_panel_test.mjs --daemon skinstreamd --subject S --recording R --web-root DIR --out DIR
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { launchChromium } from './support/browser.mjs';
import { parseArguments, startDaemon, waitFor } from './support/test_run.mjs';

async function main() {
  const options = parseArguments(process.argv.slice(2), ['daemon', 'subject', 'recording', 'webRoot', 'out']);
  const out = path.join(options.out, `takes_panel_${process.pid}`);
  fs.rmSync(out, { recursive: true, force: true });
  fs.mkdirSync(out, { recursive: true });
  const takes = path.join(out, 'takes');
  const token = 'stage-token-vmpw-2026';  // v, m, p, w: the toggles' keys
  const tokenFile = path.join(out, 'control-token');
  fs.writeFileSync(tokenFile, `${token}\n`, { mode: 0o600 });
  const { daemon, ports, log } = await startDaemon(options.daemon, [
    '--subject', options.subject, '--replay', options.recording, '--loop', '--web-root', options.webRoot, '--record-dir', takes, '--control-token-file', tokenFile,
  ], out);

  let browser = null;
  try {
    browser = await launchChromium(options.chromium);
    const page = await browser.newPage({ viewport: { width: 800, height: 600 } });
    const pageErrors = [];
    page.on('pageerror', (error) => pageErrors.push(error.message));
    await page.goto(`http://127.0.0.1:${ports.http}/`);
    await page.click('#takes summary');
    const text = (id) => page.$eval(id, (element) => element.textContent);
    await waitFor('the panel never showed the idle recorder', async () => (await text('#take-recording')) === 'idle');

    // Somebody without the token.
    await page.fill('#control-token', 'not-the-stage-token-00');
    await page.click('#take-start');
    await waitFor('a wrong token was not refused on the page', async () => (await text('#take-answer')).startsWith('403'));
    assert.deepEqual(fs.readdirSync(takes), [], 'a refused start made a take');

    // The operator.
    await page.fill('#control-token', token);
    assert.equal(await page.isChecked('#toggle-mesh'), true, 'typing the token toggled the mesh');
    assert.equal(await page.isChecked('#toggle-markers'), true, 'typing the token toggled the markers');
    await page.fill('#take-name', 'page-take');
    await page.click('#take-start');
    await waitFor('the take did not start', async () => (await text('#take-answer')) === 'page-take: recording');
    await waitFor('the panel did not follow the recording', async () => {
      const shown = await text('#take-recording');
      const frames = /^recording page-take: (\d+) frames$/.exec(shown);
      return frames && Number(frames[1]) >= 60;
    });
    await page.click('#take-stop');
    await waitFor('the take did not stop', async () => (await text('#take-answer')) === 'page-take: closing');
    await waitFor('the recorder did not become idle', async () => (await text('#take-recording')).startsWith('idle'));
    const sidecar = JSON.parse(fs.readFileSync(path.join(takes, 'page-take', 'take.json'), 'utf8'));
    assert.equal(sidecar.state, 'closed');
    assert.equal(sidecar.started_by, 'control from 127.0.0.1 (web page)');
    assert.ok(sidecar.subjects[0].raw.frames >= 60, `${sidecar.subjects[0].raw.frames} frames recorded`);
    assert.deepEqual(pageErrors, [], 'errors on the page');
    assert.equal(log().includes(token), false, 'the token reached the log');
    console.log(`take page-take: ${sidecar.subjects[0].raw.frames} frames, started by ${sidecar.started_by}`);
  } finally {
    if (browser) await browser.close();
    daemon.kill('SIGTERM');
  }
}

main().then(() => console.log('ok'), (error) => {
  console.error(error.stack || String(error));
  process.exit(1);
});
