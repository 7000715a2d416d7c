// Which way a scan is turned, as the page's "Scan's up" and "face looks
// along" controls name it: one of the six axis directions each (the core's
// FitHeadOptions::up and ::facing, `likeness fit --up --facing`). Plain
// functions (tested in Node by tests/browser/axes_node.mjs).

export const AXES = ['+y', '-y', '+z', '-z', '+x', '-x'];

export function axisVector(name) {
  const sign = name[0] === '-' ? -1 : 1;
  const k = { x: 0, y: 1, z: 2 }[name[1]];
  const v = [0, 0, 0];
  v[k] = sign;
  return v;
}

export const parallel = (a, b) => a[1] === b[1];

// The face's direction when only up is chosen: +z for a +y-up scan (most
// scanners, glTF), -y for a +z-up one (Blender, 3ds Max, CAD: the front view
// looks along +y at a face looking along -y), else the first axis across up.
export function defaultFacing(up) {
  if (up === '+y') return '+z';
  if (up === '-y') return '-z';
  if (up === '+z') return '-y';
  if (up === '-z') return '+y';
  return '+z';
}

// The axis a unit vector lies along, if it is within maxDeg of one, else null.
export function snapAxis(v, maxDeg = 10) {
  const len = Math.hypot(v[0], v[1], v[2]);
  if (!(len > 0)) return null;
  let k = 0;
  for (let i = 1; i < 3; ++i) if (Math.abs(v[i]) > Math.abs(v[k])) k = i;
  if (Math.abs(v[k]) / len < Math.cos((maxDeg * Math.PI) / 180)) return null;
  return (v[k] > 0 ? '+' : '-') + 'xyz'[k];
}

// Two <select>s (or anything with value and options[].value/.disabled) show
// up and facing, axis names; nothing changes when either is null or they
// are parallel. The facing choices along up are disabled.
export function showAxes(upSelect, facingSelect, up, facing) {
  if (up && facing && !parallel(up, facing)) {
    upSelect.value = up;
    facingSelect.value = facing;
  }
  for (const opt of facingSelect.options) opt.disabled = parallel(opt.value, upSelect.value);
}
