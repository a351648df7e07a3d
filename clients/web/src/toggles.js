// The display toggles: checkboxes in the panel, each also bound to a key.
const TOGGLES = [
  { key: 'mesh', id: 'toggle-mesh', hotkey: 'v' },
  { key: 'markers', id: 'toggle-markers', hotkey: 'm' },
  { key: 'parts', id: 'toggle-parts', hotkey: 'p' },
  { key: 'surface', id: 'toggle-surface', hotkey: 'w' },
];

// shown: the flags object to keep in sync; onChange: called after any flag changed.
export function installToggles(shown, onChange) {
  for (const t of TOGGLES) {
    const box = document.getElementById(t.id);
    box.checked = shown[t.key];
    box.addEventListener('change', () => {
      shown[t.key] = box.checked;
      onChange();
    });
  }
  window.addEventListener('keydown', (event) => {
    if (event.ctrlKey || event.metaKey || event.altKey) return;
    if (event.target instanceof HTMLInputElement) return;  // typing a token or a take's name
    const t = TOGGLES.find((x) => x.hotkey === event.key.toLowerCase());
    if (!t) return;
    const box = document.getElementById(t.id);
    box.checked = !box.checked;
    shown[t.key] = box.checked;
    onChange();
  });
}
