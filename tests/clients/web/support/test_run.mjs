// What the web tests that run the real daemon share: their command line, waiting for a
// condition, and starting skinstreamd on free ports with its log kept for the failure message.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { sleep } from './browser.mjs';

// "--web-root DIR --out DIR" -> { webRoot, out, chromium: '/usr/bin/chromium' }; every name in
// `required` must be given.
export function parseArguments(argv, required) {
  const options = { chromium: '/usr/bin/chromium' };
  for (let i = 0; i < argv.length; i += 2) {
    if (i + 1 >= argv.length) throw new Error(`${argv[i]} needs a value`);
    options[argv[i].replace(/^--/, '').replace(/-([a-z])/g, (_, c) => c.toUpperCase())] = argv[i + 1];
  }
  for (const name of required)
    if (!options[name]) throw new Error(`missing --${name.replace(/[A-Z]/g, (c) => `-${c.toLowerCase()}`)}`);
  return options;
}

// Polls `check` every 100 ms until it returns something truthy (returned); throws `what` after
// `timeoutMs`.
export async function waitFor(what, check, timeoutMs = 30000) {
  for (let waited = 0; waited < timeoutMs; waited += 100) {
    const value = await check();
    if (value) return value;
    await sleep(100);
  }
  throw new Error(`${what} (after ${timeoutMs} ms)`);
}

// skinstreamd with `args` on ports of its own choosing, its output in `dir`/skinstreamd.log:
// { daemon, ports: { http, sub }, log() } once it listens. Killed with the test on SIGINT/SIGTERM.
export async function startDaemon(program, args, dir) {
  const portsFile = path.join(dir, 'ports.json');
  const logFile = path.join(dir, 'skinstreamd.log');
  fs.rmSync(portsFile, { force: true });
  const daemon = spawn(program, [...args, '--http-port', '0', '--sub-port', '0', '--ports-file', portsFile],
    { stdio: ['ignore', fs.openSync(logFile, 'w'), fs.openSync(logFile, 'a')] });
  for (const signal of ['SIGINT', 'SIGTERM']) process.on(signal, () => { daemon.kill('SIGKILL'); process.exit(1); });
  const log = () => fs.readFileSync(logFile, 'utf8');
  const ports = await waitFor(`skinstreamd wrote no ports file ${portsFile}`, () => {
    if (daemon.exitCode !== null || daemon.signalCode !== null)
      throw new Error(`skinstreamd exited (${daemon.exitCode ?? daemon.signalCode}) before listening; log:\n${log().slice(-2000)}`);
    try {
      const written = JSON.parse(fs.readFileSync(portsFile, 'utf8'));
      return written.http > 0 ? written : null;
    } catch {
      return null;  // not written yet
    }
  }, 60000);
  return { daemon, ports, log };
}
