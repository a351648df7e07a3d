// The operator's take controls (docs/control-api.md, docs/takes.md): start and stop a take
// through the daemon's control API with its token, and the recording's state as /health says it.
// The token stays in this tab's sessionStorage (a reload keeps it, closing the tab forgets it) and
// goes only to the daemon that served the page.
const TOKEN_KEY = 'skinstream.controlToken';
const HEALTH_INTERVAL_MS = 1000;
const OPERATOR = 'web page';

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
  const token = document.getElementById('control-token');
  const name = document.getElementById('take-name');
  const answer = document.getElementById('take-answer');
  const recording = document.getElementById('take-recording');
  token.value = sessionStorage.getItem(TOKEN_KEY) || '';

  const call = async (path, body) => {
    sessionStorage.setItem(TOKEN_KEY, token.value);
    const headers = { Authorization: `Bearer ${token.value}`, 'X-Skinstream-Operator': OPERATOR };
    if (body) headers['Content-Type'] = 'application/json';
    try {
      const response = await fetch(path, { method: 'POST', headers, body: body ? JSON.stringify(body) : undefined, cache: 'no-store' });
      const reply = await response.json().catch(() => ({}));
      answer.textContent = response.ok ? `${reply.take}: ${reply.state}` : `${response.status}: ${reply.error || response.statusText}`;
      answer.className = response.ok ? '' : 'error';
    } catch (error) {
      answer.textContent = `the control API did not answer: ${error.message}`;
      answer.className = 'error';
    }
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
