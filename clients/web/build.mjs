// Bundles the page into a static folder the daemon serves (--web-root): index.html, app.js and
// worker.js.
// Usage: node build.mjs [OUT_DIR]   (default: dist/ beside this file)
import { build } from 'esbuild';
import { copyFile, mkdir } from 'node:fs/promises';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const outDir = path.resolve(process.argv[2] || path.join(here, 'dist'));

await mkdir(outDir, { recursive: true });
await build({
  // The page and the worker that receives the stream (main.js loads it as ./worker.js).
  entryPoints: [
    { in: path.join(here, 'src/main.js'), out: 'app' },
    { in: path.join(here, 'src/stream_worker.js'), out: 'worker' },
  ],
  outdir: outDir,
  bundle: true,
  format: 'esm',
  target: ['es2020'],
  minify: true,
  legalComments: 'eof', // keeps three.js's MIT notice in the bundle
  logLevel: 'warning',
});
await copyFile(path.join(here, 'index.html'), path.join(outDir, 'index.html'));
console.log(`web bundle written to ${outDir}`);
