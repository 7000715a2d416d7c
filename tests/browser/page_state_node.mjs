// The page's state machine (web/js/page_state.js) under Node, without a
// browser: every transition, and for every job of the page its success,
// its error and its Cancel, from a page with and without a head shown; the
// path that stranded the page in "working" (issue 39: a bad scan, then
// Dismiss or "Try the sample"); and what each state enables.
// Usage: node tests/browser/page_state_node.mjs   (exit 0: every check passed)
import assert from 'node:assert/strict';
import { controlsFor, PageState } from '../../web/js/page_state.js';

const JOBS = ['scan', 'fit', 'texture', 'photos', 'points', 'eye photo', 'smile photo', 'project', 'sample'];
let checks = 0;
function test(name, fn) {
  fn();
  checks++;
  console.log('PASS  ' + name);
}

// A machine whose rest state follows `shown` (what the page shows), with a
// log of the states it went through and of the cancelled jobs.
function machine(shown = false) {
  const log = [], cancelled = [];
  const world = { shown };
  const m = new PageState({ rest: () => (world.shown ? 'done' : 'ready'), onChange: (s) => log.push(s.state),
                            onCancel: (job) => cancelled.push(job.name) });
  return { m, log, cancelled, world };
}

test('starts in loading; nothing begins before start-up', () => {
  const { m } = machine();
  assert.equal(m.state, 'loading');
  assert.equal(m.begin('fit'), null);
  m.started();
  assert.equal(m.state, 'ready');
});

test('a failed start-up is a fatal error: no job begins, Dismiss keeps it', () => {
  const { m } = machine();
  m.startFailed('no WebGL 2');
  assert.equal(m.state, 'error');
  assert.equal(m.begin('scan'), null);
  m.dismiss();
  assert.equal(m.state, 'error');
  assert.equal(m.snapshot().banner, false);
  m.started();  // too late: stays failed
  assert.equal(m.state, 'error');
});

for (const shown of [false, true]) {
  const rest = shown ? 'done' : 'ready';
  for (const name of JOBS) {
    test(`${name} (${rest}): success goes back to rest`, () => {
      const { m } = machine(shown);
      m.started();
      const job = m.begin(name);
      assert.ok(job);
      assert.equal(m.state, 'working');
      assert.equal(m.snapshot().job, name);
      assert.equal(m.begin('fit'), null, 'one job at a time');
      assert.equal(m.end(job), true);
      assert.equal(m.state, rest);
      assert.equal(m.end(job), false, 'ending twice changes nothing');
    });
    test(`${name} (${rest}): an error, then Dismiss, goes back to rest and the next job starts`, () => {
      const { m } = machine(shown);
      m.started();
      const job = m.begin(name);
      m.fail(name + ' failed');
      assert.equal(m.state, 'error');
      assert.equal(m.snapshot().message, name + ' failed');
      assert.equal(m.snapshot().banner, true);
      assert.equal(m.isLive(job), false);
      assert.equal(m.end(job), false, 'the failed job ending later changes nothing');
      assert.equal(m.state, 'error');
      m.dismiss();
      assert.equal(m.state, rest);
      assert.equal(m.snapshot().banner, false);
      assert.ok(m.begin('sample'));
    });
    test(`${name} (${rest}): an error, then a new job without Dismiss, starts it and hides the banner`, () => {
      const { m } = machine(shown);
      m.started();
      m.begin(name);
      m.fail('bad');
      const next = m.begin('sample');
      assert.ok(next);
      assert.equal(m.state, 'working');
      assert.equal(m.snapshot().banner, false);
      m.end(next);
      assert.equal(m.state, rest);
    });
    test(`${name} (${rest}): Cancel ends the job at once, calls onCancel, and the job's late end is ignored`, () => {
      const { m, cancelled } = machine(shown);
      m.started();
      const job = m.begin(name);
      assert.equal(m.cancel(), true);
      assert.equal(m.state, rest);
      assert.deepEqual(cancelled, [name]);
      assert.equal(job.cancelled, true);
      assert.equal(m.isLive(job), false);
      const next = m.begin('fit');  // the user goes on before the old job noticed
      assert.equal(m.end(job), false);
      assert.equal(m.state, 'working', "the cancelled job's end does not end the new one");
      m.end(next);
      assert.equal(m.state, rest);
    });
  }
}

test('issue 39: a scan that fails to parse, then Dismiss, leaves the page usable', () => {
  const { m, log } = machine(true);
  m.started();
  const job = m.begin('scan');
  m.fail('notes.ply: not a PLY file');
  m.dismiss();
  assert.equal(m.state, 'done');
  assert.ok(!log.slice(log.indexOf('error')).includes('working'), 'never back to working: ' + log.join(' '));
  assert.equal(m.end(job), false);
  assert.ok(m.begin('sample'), '"Try the sample" starts');
});

test('issue 39: a bad scan, then "Try the sample" straight away (no Dismiss), runs the sample', () => {
  const { m } = machine(false);
  m.started();
  m.begin('scan');
  m.fail('notes.ply: not a PLY file');
  const sample = m.begin('sample');
  assert.ok(sample);
  m.end(sample);
  const scan = m.begin('scan');
  assert.ok(scan);
});

test('the rest state is read when the job ends: a scan loaded makes it done, a head lost makes it ready', () => {
  const { m, world } = machine(false);
  m.started();
  const job = m.begin('scan');
  world.shown = true;
  m.end(job);
  assert.equal(m.state, 'done');
  world.shown = false;
  m.refresh();
  assert.equal(m.state, 'ready');
});

test('an error outside a job (a refused file) and Dismiss', () => {
  const { m } = machine(true);
  m.started();
  m.fail('too large');
  assert.equal(m.state, 'error');
  m.fail('another');
  assert.equal(m.snapshot().message, 'another');
  m.dismiss();
  assert.equal(m.state, 'done');
  m.dismiss();  // twice: nothing
  assert.equal(m.state, 'done');
});

test('Cancel with nothing running does nothing; refresh keeps working and error', () => {
  const { m, cancelled } = machine(true);
  m.started();
  assert.equal(m.cancel(), false);
  assert.deepEqual(cancelled, []);
  const job = m.begin('fit');
  m.refresh();
  assert.equal(m.state, 'working');
  m.fail('x');
  m.refresh();
  assert.equal(m.state, 'error');
  assert.equal(m.isLive(job), false);
});

// ---- what each state enables ------------------------------------------------
const ALWAYS_WITH_HEAD = ['exportObj', 'exportPly', 'exportGlb', 'animate', 'expressions', 'level', 'saveProject', 'showPoints', 'showComponents'];
test('loading and a failed start-up enable nothing (Cancel neither)', () => {
  for (const s of [{ state: 'loading' }, { state: 'error', fatal: true, fit: true, scanFile: true }]) {
    const c = controlsFor(s);
    assert.deepEqual(Object.keys(c).filter((k) => c[k]), [], JSON.stringify(s));
  }
});
test('working: only Cancel and the view controls; no export, no new job', () => {
  const c = controlsFor({ state: 'working', fit: true, scanFile: true, texture: true, photos: 2, distance: true });
  assert.deepEqual(Object.keys(c).filter((k) => c[k]).sort(), ['cancel', 'pointSize', 'reset', 'wireframe']);
});
for (const state of ['ready', 'done', 'error']) {
  test(`${state}: inputs on, Cancel hidden; a head is exportable exactly when there is one`, () => {
    const none = controlsFor({ state });
    assert.ok(none.files && none.sample && none.openProject && !none.cancel && !none.fit);
    for (const k of ALWAYS_WITH_HEAD) assert.equal(none[k], false, k);
    const head = controlsFor({ state, fit: true, scanFile: true });
    for (const k of ALWAYS_WITH_HEAD) assert.equal(head[k], true, k);
    assert.ok(head.fit && !head.texture && !head.exportTextured && !head.exportMap);
    const all = controlsFor({ state, fit: true, scanFile: false, texture: true, photos: 1, distance: true });
    assert.ok(all.texture && all.exportTextured && all.exportMap && !all.fit, 'a head from a project: no scan file to fit');
  });
}

test('Make head from photos: at rest, with no scan loaded, once a photo has face points', () => {
  for (const state of ['ready', 'done', 'error']) {
    assert.equal(controlsFor({ state, facePoints: 2 }).photosHead, true, state);
    assert.equal(controlsFor({ state, facePoints: 0 }).photosHead, false, state + ', no face points');
    assert.equal(controlsFor({ state, facePoints: 2, scan: true, scanFile: true }).photosHead, false, state + ', a scan loaded');
  }
  for (const state of ['loading', 'working']) assert.equal(controlsFor({ state, facePoints: 2 }).photosHead, false, state);
  assert.equal(controlsFor({ state: 'ready', facePoints: 2, fatal: true }).photosHead, false, 'fatal');
});

console.log(`page state: ${checks}/${checks} checks passed`);
