// The protocol's golden messages (tests/protocol/fixtures/subscriber/, written from the spec by
// make_v2_fixtures.py) and ways to damage a message for the bad-input tests.
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

export const repoRoot = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../../../..');
export const webSource = (name) => path.join(repoRoot, 'clients/web/src', name);
const fixtureDir = path.join(repoRoot, 'tests/protocol/fixtures/subscriber');

// A fixture as its own ArrayBuffer.
export function readFixture(name) {
  const bytes = fs.readFileSync(path.join(fixtureDir, name));
  return bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.length);
}

// The message cut (or grown with zero bytes) to `length` bytes, its header's payload size made to
// match, so that the damage reaches the decoder behind the header check.
export function resized(buffer, length) {
  const out = new Uint8Array(length);
  out.set(new Uint8Array(buffer, 0, Math.min(length, buffer.byteLength)));
  if (length >= 12) new DataView(out.buffer).setUint32(8, length - 12, true);
  return out.buffer;
}

// A copy with the bytes at `offset` replaced by `setter(view, offset)`.
export function patched(buffer, setter) {
  const copy = buffer.slice(0);
  setter(new DataView(copy));
  return copy;
}

// A small deterministic generator (xorshift32): fuzzing that fails reproducibly.
export function random(seed) {
  let state = seed >>> 0 || 1;
  return () => {
    state ^= state << 13;
    state >>>= 0;
    state ^= state >>> 17;
    state ^= state << 5;
    state >>>= 0;
    return state / 4294967296;
  };
}
