// The subject to show, on a daemon serving several actors: ?subject=NAME in the page's address
// (none: the daemon's first) goes into the Hello; a menu of the daemon's subjects (from /health,
// with those absent from the stream marked) reloads the page on the one chosen.
const HEALTH_URL = '/health';

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
