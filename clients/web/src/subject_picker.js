// The subject to show, on a daemon serving several actors: ?subject=NAME in the page's address
// (none: the daemon's first, over protocol version 1 as before), and a menu of the daemon's
// subjects (from /health, with those absent from the stream marked) that reloads the page on the
// one chosen.
import { Encoding } from './protocol.js';

const HEALTH_URL = '/health';

// null: version 1, the first subject; else the version 2 Hello's subject and encoding.
export function chosenSubject(params, quantised) {
  const subject = params.get('subject');
  return subject === null ? null : { subject, encoding: quantised ? Encoding.QUANTISED : Encoding.FLOAT };
}

// Adds the menu to `panel` once /health has listed more than one subject (or one is chosen).
export async function installSubjectPicker(panel, params) {
  let subjects;
  try {
    const response = await fetch(HEALTH_URL, { cache: 'no-store' });
    subjects = (await response.json()).subjects || [];
  } catch {
    return; // a page served from elsewhere: no menu
  }
  const chosen = params.get('subject');
  if (subjects.length < 2 && chosen === null) return;
  const label = document.createElement('label');
  label.textContent = 'subject ';
  const menu = document.createElement('select');
  menu.id = 'subject';
  for (const [index, s] of subjects.entries()) {
    const option = new Option(s.present ? s.name : `${s.name} (absent)`, s.name);
    option.selected = chosen === null ? index === 0 : s.name === chosen;
    menu.add(option);
  }
  menu.addEventListener('change', () => {
    params.set('subject', menu.value);
    window.location.search = params.toString();
  });
  label.append(menu);
  panel.prepend(label);
}
