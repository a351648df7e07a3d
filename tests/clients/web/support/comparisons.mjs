// How far the page's vertices and normals are from the expected ones.

// Largest distance between two position arrays (3 per vertex), and where.
export function worstDistance(actual, expected) {
  let worst = 0;
  let at = -1;
  for (let v = 0; 3 * v < expected.length; ++v) {
    const d = Math.hypot(actual[3 * v] - expected[3 * v], actual[3 * v + 1] - expected[3 * v + 1], actual[3 * v + 2] - expected[3 * v + 2]);
    if (!(d <= worst)) {
      worst = d;
      at = v;
    }
  }
  return { worst, at };
}

// Largest angle in degrees between two normal arrays (3 per vertex, each made unit here).
export function worstAngleDegrees(actual, expected) {
  let worst = 0;
  for (let v = 0; v < expected.length; v += 3) {
    const la = Math.hypot(actual[v], actual[v + 1], actual[v + 2]);
    const lb = Math.hypot(expected[v], expected[v + 1], expected[v + 2]);
    const cosine = (actual[v] * expected[v] + actual[v + 1] * expected[v + 1] + actual[v + 2] * expected[v + 2]) / (la * lb);
    const angle = (Math.acos(Math.min(1, Math.max(-1, cosine))) * 180) / Math.PI;
    if (!(angle <= worst)) worst = angle;
  }
  return worst;
}
