// The page's wording of the core's messages (web/js/wording.js) under
// Node: the messages likeness fit prints with flags come out without them,
// and the rest of each message is kept.
// Usage: node tests/browser/wording_node.mjs   (exit 0: every check passed)
import assert from 'node:assert/strict';
import { forPage, photoCount } from '../../web/js/wording.js';

const turned = 'the scan seems to face +x with +y up (there its closest-point error is 3.1x smaller than as given): ' +
               'turned it that way; pass --facing 0.74 0 -0.68 --up 0 1 0 to say so';
const t = forPage(turned);
assert.ok(!/--facing|--up|pass /.test(t), t);
assert.ok(t.startsWith('the scan seems to face +x with +y up (there its closest-point error is 3.1x smaller than as given)'), t);
assert.ok(/head was turned that way/.test(t), t);

const hint = 'the scan seems to face -z with +y up (there its closest-point error is 2x smaller than as given); try --facing 0 0 -1 --up 0 1 0';
const h = forPage(hint);
assert.ok(!/--facing|--up/.test(h) && /set the scan's axes under Fit head to up \+Y, face looks along −Z$/.test(h) && /seems to face -z/.test(h), h);
// Axes the controls cannot name (a turn off the axes): what to set, in words.
const tilted = forPage('the scan seems to face +x with +y up (2x); try --facing 0.74 0 -0.68 --up 0 1 0');
assert.ok(/; set the scan's axes under Fit head: which of its axes points to the top of the head/.test(tilted) && !/--/.test(tilted), tilted);

const refused = 'after alignment only 24.1% of the points lie within 2% of the diagonal of the head surface (need 60%); ' +
                'this does not look like a head scan (a head and shoulders lying down or facing away: pass --up and --facing, e.g. --up +z)';
const r = forPage(refused);
assert.ok(!/--up|--facing|pass /.test(r) && /lying down or facing away: set the scan's axes under Fit head: which of its axes points to the top of the head, and which one the face looks along\)$/.test(r), r);
assert.ok(r.startsWith('after alignment only 24.1% of the points'), r);

// The core named the axes that pass (FitHeadOptions::suggest_z_up): the page names its controls' values.
const named = 'after alignment only 1.48% of the points lie within 2% of the diagonal of the head surface (need 60%); ' +
              'this does not look like a head scan (with +z up and the face along -y, as Blender and CAD tools write ' +
              'scans, the alignment passes; try --facing 0 -1 0 --up 0 0 1)';
const n = forPage(named);
assert.ok(!/--/.test(n) && /the alignment passes; set the scan's axes under Fit head to up \+Z, face looks along −Y\)$/.test(n), n);

const faceOnly = 'face-only scan (its upper part is 0.4x as deep as wide; a whole head is 1x or more): aligned by closest points';
assert.equal(forPage(faceOnly), faceOnly, 'a message without command-line words is left alone');
assert.ok(!/bbox/.test(forPage('1.2 % of the bbox diagonal')));
assert.equal(photoCount(1), '1 photo');
assert.equal(photoCount(8), '8 photos');
assert.equal(photoCount(0), '0 photos');
console.log('wording: 13/13 checks passed');
