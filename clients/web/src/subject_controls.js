// The operator's live calibration (docs/control-api.md): the subject shown records N seconds of
// its range of motion from the stream; the daemon builds it in a separate process, checks it and
// swaps it in, and this page follows by itself (the new MeshInfo rebuilds the body). Its progress
// and a failure's reason come from /health (the subject's "change").
import { postControl, refusal } from './control_call.js';

const HEALTH_INTERVAL_MS = 1000;

export function describeChange(change) {
  if (!change) return 'no calibration yet';
  switch (change.state) {
    case 'recording':
      return `recording the range of motion: ${change.frames_recorded} of ${change.frames_wanted} frames`;
    case 'building':
      return 'building the subject (a separate process)';
    case 'loading':
    case 'swapping':
      return `${change.state} the new subject`;
    case 'done':
      return `swapped in ${change.finished}: ${change.markers} markers (build ${change.build_seconds.toFixed(1)} s)`;
    case 'failed':
      return `failed: ${change.reason}`;
    default:
      return change.state;
  }
}

// `shownSubject()`: the name of the subject the page shows (its MeshInfo's).
export function installSubjectControls(shownSubject) {
  const seconds = document.getElementById('calibrate-seconds');
  const mesh = document.getElementById('calibrate-mesh');
  const answer = document.getElementById('calibrate-answer');
  const state = document.getElementById('calibrate-state');

  document.getElementById('calibrate').addEventListener('click', async () => {
    const subject = shownSubject();
    if (!subject) {
      answer.textContent = 'no subject shown yet';
      answer.className = 'error';
      return;
    }
    const body = { seconds: Number(seconds.value) };
    if (mesh.value) body.mesh = mesh.value;
    const result = await postControl(`/subjects/${encodeURIComponent(subject)}/calibration`, body);
    answer.textContent = result.ok ? `${subject}: ${result.reply.state}` : refusal(result);
    answer.className = result.ok ? '' : 'error';
  });

  const poll = async () => {
    try {
      const health = await (await fetch('/health', { cache: 'no-store' })).json();
      const subject = (health.subjects || []).find((s) => s.name === shownSubject());
      state.textContent = subject ? describeChange(subject.change) : '';
      state.className = subject && subject.change && subject.change.state === 'failed' ? 'error' : '';
    } catch {
      state.textContent = 'no /health';
    }
  };
  poll();
  setInterval(poll, HEALTH_INTERVAL_MS);
}
