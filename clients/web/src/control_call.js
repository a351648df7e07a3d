// The operator's control API from the page (docs/control-api.md): the token typed in the control
// panel, kept in this tab's sessionStorage (a reload keeps it, closing the tab forgets it), sent
// only to the daemon that served the page.
const TOKEN_KEY = 'skinstream.controlToken';
const OPERATOR = 'web page';

export function restoreControlToken() {
  document.getElementById('control-token').value = sessionStorage.getItem(TOKEN_KEY) || '';
}

// POST `path` with the token: { ok, status, reply } (reply: the daemon's JSON), or { ok: false,
// status: 0, reply: { error } } when the daemon did not answer.
export async function postControl(path, body) {
  const token = document.getElementById('control-token').value;
  sessionStorage.setItem(TOKEN_KEY, token);
  const headers = { Authorization: `Bearer ${token}`, 'X-Skinstream-Operator': OPERATOR };
  if (body) headers['Content-Type'] = 'application/json';
  try {
    const response = await fetch(path, { method: 'POST', headers, body: body ? JSON.stringify(body) : undefined, cache: 'no-store' });
    const reply = await response.json().catch(() => ({}));
    return { ok: response.ok, status: response.status, reply: response.ok ? reply : { error: reply.error || response.statusText } };
  } catch (error) {
    return { ok: false, status: 0, reply: { error: `the control API did not answer: ${error.message}` } };
  }
}

// One line for an answer that refused: "403: wrong token".
export function refusal(answer) {
  return answer.status ? `${answer.status}: ${answer.reply.error}` : answer.reply.error;
}
