// Distinct colours for body parts: golden-angle hues, so neighbouring part indices differ.
// Vertices without a dominant part (255) stay neutral grey.
import { NO_PART } from './protocol.js';

const NEUTRAL = [0.72, 0.72, 0.72];

function hslToRgb(h, s, l) {
  const k = (n) => (n + h * 12) % 12;
  const a = s * Math.min(l, 1 - l);
  const f = (n) => l - a * Math.max(-1, Math.min(k(n) - 3, Math.min(9 - k(n), 1)));
  return [f(0), f(8), f(4)];
}

export function partColour(part) {
  if (part === NO_PART) return NEUTRAL;
  const hue = (part * 0.381966) % 1; // golden-angle steps
  return hslToRgb(hue, 0.55, 0.6);
}

// Fills an RGB float array (3 per vertex) from the dominant part of each vertex.
export function fillPartColours(dominantPart, out) {
  for (let v = 0; v < dominantPart.length; ++v) {
    const c = partColour(dominantPart[v]);
    out[3 * v] = c[0];
    out[3 * v + 1] = c[1];
    out[3 * v + 2] = c[2];
  }
}
