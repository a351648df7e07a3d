// The encoding the viewer asks the daemon for: ?encoding=parameters|compressed|quantised|float,
// parameters by default (about 12 kB a frame, evaluated on the GPU), and the panel's picker,
// which reloads the page with the choice in its address. The older ?quantised=0|1 still works.
import { Encoding, ENCODING_NAMES } from './protocol.js';

// Returns { encoding, problem }: problem is a one-line complaint about the address, or ''.
export function requestedEncoding(params) {
  const name = params.get('encoding');
  if (name !== null) {
    const encoding = ENCODING_NAMES.indexOf(name);
    if (encoding >= 0) return { encoding, problem: '' };
    return { encoding: Encoding.PARAMETERS, problem: `unknown encoding "${name}" in the address (one of ${ENCODING_NAMES.join(', ')}); asked for parameters` };
  }
  const quantised = params.get('quantised');
  if (quantised === '0') return { encoding: Encoding.FLOAT, problem: '' };
  if (quantised === '1') return { encoding: Encoding.QUANTISED, problem: '' };
  return { encoding: Encoding.PARAMETERS, problem: '' };
}

export function installEncodingPicker(select, current) {
  select.value = ENCODING_NAMES[current];
  select.addEventListener('change', () => {
    const url = new URL(window.location.href);
    url.searchParams.set('encoding', select.value);
    url.searchParams.delete('quantised');
    window.location.assign(url);
  });
}
