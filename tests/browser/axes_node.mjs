// The page's "Scan's axes" controls (web/js/axes.js) under Node: the axis
// names become the vectors the worker passes as FitHeadOptions::up and
// ::facing, every up has a facing across it, a fitted head's frame snaps
// back to names only near an axis, and a facing along up cannot be chosen.
// Usage: node tests/browser/axes_node.mjs   (exit 0: every check passed)
import assert from 'node:assert/strict';
import { AXES, axisVector, defaultFacing, parallel, showAxes, snapAxis } from '../../web/js/axes.js';

let checks = 0;
const ok = (cond, what) => { assert.ok(cond, what); ++checks; };

ok(JSON.stringify(axisVector('+y')) === '[0,1,0]' && JSON.stringify(axisVector('-z')) === '[0,0,-1]' &&
   JSON.stringify(axisVector('-x')) === '[-1,0,0]', 'axis names become unit vectors');
ok(AXES.every((a) => snapAxis(axisVector(a)) === a), 'each axis snaps back to its own name');
// Blender and 3ds Max: +z up, the face toward -y; the usual scanner: +y up, face +z.
ok(defaultFacing('+z') === '-y' && defaultFacing('+y') === '+z', 'the usual facing for +z up is -y, for +y up +z');
ok(AXES.every((u) => !parallel(u, defaultFacing(u))), 'every up has a default facing across it');
const tilt = (deg) => [0, Math.cos((deg * Math.PI) / 180), Math.sin((deg * Math.PI) / 180)];
ok(snapAxis(tilt(9)) === '+y' && snapAxis(tilt(11)) === null, 'a frame 9 degrees off +y snaps to it, 11 degrees off does not');
ok(snapAxis([0, 0, 0]) === null && snapAxis([0, 0, -3]) === '-z', 'a zero vector has no axis; length does not matter');

// Fake selects: value and options with value/disabled.
const select = (value) => ({ value, options: AXES.map((a) => ({ value: a, disabled: false })) });
const up = select('+y'), facing = select('+z');
showAxes(up, facing, '+z', '-y');
ok(up.value === '+z' && facing.value === '-y', 'showAxes sets both');
ok(facing.options.filter((o) => o.disabled).map((o) => o.value).sort().join() === '+z,-z', 'the facings along up are disabled');
showAxes(up, facing, '+x', '+x');
ok(up.value === '+z' && facing.value === '-y', 'parallel axes are refused: both stay');
showAxes(up, facing, null, '+z');
ok(up.value === '+z' && facing.value === '-y', 'an axis that did not snap leaves both as they are');
console.log(`scan axes: ${checks}/${checks} checks passed`);
