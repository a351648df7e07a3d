// The system Chromium, headless, driven by playwright-core (pinned in clients/web/package.json):
// WebGL2 through SwiftShader, on the CPU.
import fs from 'node:fs';
import path from 'node:path';
import { createRequire } from 'node:module';
import { repoRoot } from './fixtures.mjs';

export async function launchChromium(executablePath = '/usr/bin/chromium') {
  if (!fs.existsSync(executablePath)) throw new Error(`chromium not found at ${executablePath} (Debian 12: apt-get install chromium)`);
  const { chromium } = createRequire(path.join(repoRoot, 'clients/web/package.json'))('playwright-core');
  return chromium.launch({
    executablePath,
    headless: true,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  });
}

// page.waitForFunction with a message that says what never happened.
export async function waitUntil(page, what, predicate, argument = null, timeout = 30000) {
  try {
    await page.waitForFunction(predicate, argument, { timeout });
  } catch (error) {
    const state = await page.evaluate(() => window.skinstreamViewer && {
      framesReceived: window.skinstreamViewer.framesReceived, framesRendered: window.skinstreamViewer.framesRendered,
      lastFrameNumber: window.skinstreamViewer.lastFrameNumber, framesRejected: window.skinstreamViewer.framesRejected,
      connectionState: window.skinstreamViewer.connectionState, bannerText: window.skinstreamViewer.bannerText,
      lastError: window.skinstreamViewer.lastError,
    }).catch(() => null);
    throw new Error(`${what} (after ${timeout} ms; viewer ${JSON.stringify(state)}): ${error.message.split('\n')[0]}`);
  }
}

export const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// The page's drawn frame (window.skinstreamViewer.readDrawnFrame) as Float32Arrays, moved as
// base64 (a JSON array of 320,000 numbers took seconds). Copied in the page first, its key
// (frame number @ daemon receive time) known at once: `whenKeyKnown(key)` is awaited before the
// seconds the copy takes to move, so that a reference can take its own copy of that frame
// before newer frames push it out; when it returns false, the copy is not moved (null).
export async function readDrawnFrame(page, whenKeyKnown = null) {
  const key = await page.evaluate(() => {
    const drawn = window.skinstreamViewer.readDrawnFrame();
    window.skinstreamTestDrawnFrame = drawn;
    return `${drawn.frameNumber}@${drawn.receiveTimeNs}`;
  });
  if (whenKeyKnown && (await whenKeyKnown(key)) === false) return null;
  const frame = await page.evaluate(() => {
    const drawn = window.skinstreamTestDrawnFrame;
    const base64 = (array) => {
      const bytes = new Uint8Array(array.buffer, array.byteOffset, array.byteLength);
      let text = '';
      for (let i = 0; i < bytes.length; i += 0x8000) text += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
      return btoa(text);
    };
    return { frameNumber: drawn.frameNumber, positions: base64(drawn.positions), normals: base64(drawn.normals) };
  });
  const floats = (text) => {
    const bytes = Buffer.from(text, 'base64');
    return new Float32Array(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.length));
  };
  return { ...frame, key, positions: floats(frame.positions), normals: floats(frame.normals) };
}
