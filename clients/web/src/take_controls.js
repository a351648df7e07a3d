// The operator's take controls (docs/control-api.md, docs/takes.md): start and stop a take
// through the daemon's control API with its token (control_call.js), and the recording's state as
// /health says it.
import { postControl, refusal, restoreControlToken } from './control_call.js';

const HEALTH_INTERVAL_MS = 1000;

function describeRecording(recording) {
  switch (recording.state) {
    case undefined:
    case 'off':
      return 'recording off (no record_dir)';
    case 'recording': {
      const subjects = Object.values(recording.subjects || {});
      const frames = subjects.length ? Math.min(...subjects.map((s) => s.received_frames)) : 0;
      return `recording ${recording.take}: ${frames} frames`;
    }
    case 'failed':
      return `failed: ${recording.error}`;
    default:
      return recording.take ? `${recording.state} (last: ${recording.take})` : recording.state;
  }
}

export function installTakeControls() {
  const name = document.getElementById('take-name');
  const answer = document.getElementById('take-answer');
  const recording = document.getElementById('take-recording');
  restoreControlToken();

  const call = async (path, body) => {
    const result = await postControl(path, body);
    answer.textContent = result.ok ? `${result.reply.take}: ${result.reply.state}` : refusal(result);
    answer.className = result.ok ? '' : 'error';
  };
  document.getElementById('take-start').addEventListener('click', () => call('/takes', name.value ? { name: name.value } : null));
  document.getElementById('take-stop').addEventListener('click', () => call('/takes/stop', null));

  const poll = async () => {
    try {
      const health = await (await fetch('/health', { cache: 'no-store' })).json();
      recording.textContent = describeRecording(health.recording || {});
    } catch {
      recording.textContent = 'no /health';
    }
  };
  poll();
  setInterval(poll, HEALTH_INTERVAL_MS);
}
