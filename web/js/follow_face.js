// "Follow my face" (issue 38, in the page): the webcam drives the head's
// ARKit shapes through the face-mesh detector (landmarks.js). Off by
// default; on, the camera's frames go only to the detector in this page:
// nothing is recorded, stored or sent, and a visible indicator shows while
// the camera is on. It stops (and the camera's tracks end) when toggled off,
// when another head or job takes over (the expressions are cleared), when a
// preset, a slider or Talk is used, and when the camera goes away.
//
// Per detected frame (at most ~12 per second) the landmarks give a few
// measures, each divided by a length of the face so that distance to the
// camera does not matter: each eye's lid gap over its width, the lips' gap,
// each mouth corner's height along the face's up (chin to forehead) from
// the eyes' outer corners and the mouth's width over the distance between the
// eyes' outer corners, the inner and outer brows' heights above the eyes.
// The first frames with a face (CALIBRATION_FRAMES) are taken as the
// neutral face; the shapes' weights are the measures' changes from it over
// a full-motion span (SPAN), clamped to [0, 1] and smoothed over time. The
// spans are guesses except jawOpen's, set from the detector on our own
// jawOpen render (the generic head's full jawOpen opens the lips by 0.22 of
// the eye-corner distance; a person's wide-open mouth, more, clamps at 1);
// none is calibrated per person.
import { app, ui } from './state.js';
import { trackLandmarks } from './landmarks.js';
import { driveWeights, setDriver } from './expressions.js';
import { stopAnimation } from './animation.js';

const CALIBRATION_FRAMES = 8;
const FRAME_MS = 80;          // detector at most every 80 ms
const SMOOTHING_MS = 90;      // exponential smoothing's time constant

// MediaPipe Face Mesh indices (the subject's left is the image's right).
const P = {
  eyeL: { top: 386, bottom: 374, inner: 362, outer: 263 },
  eyeR: { top: 159, bottom: 145, inner: 133, outer: 33 },
  lipTop: 13, lipBottom: 14, cornerL: 291, cornerR: 61,
  browInnerL: 336, browInnerR: 107, browOuterL: 300, browOuterR: 70,
  forehead: 10, chin: 152,
};

// Change from neutral (in the measure's units) that makes a weight of 1.
const SPAN = {
  blink: 0.75,      // of the neutral lid gap: 75 % closed is a full blink
  jawOpen: 0.25,    // lip gap over eye-corner distance
  smile: 0.07,      // corner lift over eye-corner distance
  smileWide: 0.12,  // mouth width gain over eye-corner distance
  brow: 0.07,       // brow lift over eye-corner distance
  pucker: 0.18,     // mouth width loss over eye-corner distance
};

const sub = (a, b) => [a[0] - b[0], a[1] - b[1]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1];
const len = (a) => Math.hypot(a[0], a[1]);
const clamp01 = (x) => Math.min(1, Math.max(0, x));

// The face's measures from its landmarks ([x, y] pixels).
export function faceMeasures(pts) {
  const at = (i) => pts[i];
  const scale = len(sub(at(P.eyeL.outer), at(P.eyeR.outer)));
  const upRaw = sub(at(P.forehead), at(P.chin));
  const up = [upRaw[0] / len(upRaw), upRaw[1] / len(upRaw)];
  const height = (i, ref) => dot(sub(at(i), at(ref)), up) / scale;
  const eye = (e) => len(sub(at(e.top), at(e.bottom))) / len(sub(at(e.inner), at(e.outer)));
  // Corner heights from the eyes' outer corners (the rigid upper face), so
  // that the jaw dropping (corners down) does not read as a smile.
  const eyes = [(at(P.eyeL.outer)[0] + at(P.eyeR.outer)[0]) / 2, (at(P.eyeL.outer)[1] + at(P.eyeR.outer)[1]) / 2];
  return {
    eyeL: eye(P.eyeL), eyeR: eye(P.eyeR),
    lipGap: len(sub(at(P.lipTop), at(P.lipBottom))) / scale,
    cornerL: dot(sub(at(P.cornerL), eyes), up) / scale,
    cornerR: dot(sub(at(P.cornerR), eyes), up) / scale,
    mouthWidth: len(sub(at(P.cornerL), at(P.cornerR))) / scale,
    browInner: (height(P.browInnerL, P.eyeL.inner) + height(P.browInnerR, P.eyeR.inner)) / 2,
    browOuterL: height(P.browOuterL, P.eyeL.outer), browOuterR: height(P.browOuterR, P.eyeR.outer),
  };
}

// ARKit weights from the measures m against the neutral ones n.
export function faceWeights(m, n) {
  const jaw = clamp01((m.lipGap - n.lipGap) / SPAN.jawOpen);
  const wide = (m.mouthWidth - n.mouthWidth) / SPAN.smileWide;
  const narrow = clamp01((n.mouthWidth - m.mouthWidth) / SPAN.pucker);
  const smile = (c, c0) => clamp01(0.5 * ((c - c0) / SPAN.smile) + 0.5 * wide);
  return {
    eyeBlinkLeft: clamp01((1 - m.eyeL / n.eyeL) / SPAN.blink),
    eyeBlinkRight: clamp01((1 - m.eyeR / n.eyeR) / SPAN.blink),
    jawOpen: jaw,
    mouthSmileLeft: smile(m.cornerL, n.cornerL),
    mouthSmileRight: smile(m.cornerR, n.cornerR),
    browInnerUp: clamp01((m.browInner - n.browInner) / SPAN.brow),
    browOuterUpLeft: clamp01((m.browOuterL - n.browOuterL) / SPAN.brow),
    browOuterUpRight: clamp01((m.browOuterR - n.browOuterR) / SPAN.brow),
    mouthPucker: narrow * (1 - jaw),
    mouthFunnel: narrow * jaw,
  };
}

let session = null;  // {stream, video, timer, neutral, samples, weights, last, generation}
let generation = 0;

const follow = app.follow = {
  on: false,
  state: 'off',        // off | starting | calibrating | following | no-face | error
  frames: 0,           // frames sent to the detector
  faces: 0,            // frames in which a face was found
  weights: {},         // the last weights applied (smoothed)
  raw: {},             // the last frame's weights (unsmoothed)
  message: '',
  tracks: () => (session && session.stream ? session.stream.getTracks().map((t) => t.readyState) : []),
  lastStream: null,    // the last stream opened (tests: its tracks end when stopped)
};

function say(state, message) {
  follow.state = state;
  follow.message = message;
  ui.followStatus.textContent = message;
  ui.cameraOn.hidden = !(session && session.stream);
}

function cameraError(e) {
  const name = e && e.name;
  if (name === 'NotAllowedError' || name === 'SecurityError')
    return 'The camera was refused. To follow your face, allow the camera for this page in the browser\'s site settings.';
  if (name === 'NotFoundError' || name === 'OverconstrainedError' || name === 'DevicesNotFoundError')
    return 'No camera was found on this device.';
  if (name === 'NotReadableError' || name === 'TrackStartError')
    return 'The camera could not start: another program may be using it.';
  return 'The camera could not start (' + (e && e.message ? e.message : String(e)) + ').';
}

async function start() {
  if (session) return;
  if (app.animation.running) stopAnimation(false);
  if (!app.fit) { ui.follow.checked = false; say('error', 'Fit or open a head first: Follow my face moves the fitted head.'); return; }
  if (!navigator.mediaDevices || !navigator.mediaDevices.getUserMedia) {
    ui.follow.checked = false;
    say('error', 'This browser gives the page no camera (a camera needs a secure page: https or localhost).');
    return;
  }
  const my = ++generation;
  follow.on = true;
  follow.frames = follow.faces = 0;
  follow.weights = {};
  follow.raw = {};
  say('starting', 'Opening the camera…');
  let stream;
  try {
    stream = await navigator.mediaDevices.getUserMedia({ video: { facingMode: 'user', width: { ideal: 640 } }, audio: false });
  } catch (e) {
    if (my !== generation) return;
    follow.on = false;
    ui.follow.checked = false;
    say('error', cameraError(e));
    return;
  }
  if (my !== generation) { stream.getTracks().forEach((t) => t.stop()); return; }
  const video = ui.followVideo;
  video.srcObject = stream;
  follow.lastStream = stream;
  session = { stream, video, timer: 0, neutral: null, samples: [], last: performance.now() };
  // The camera unplugged or taken away: stop.
  for (const t of stream.getTracks()) t.addEventListener('ended', () => { if (my === generation) stop('The camera stopped.'); });
  setDriver(() => stop('', false));  // the page took the head over: it resets the weights itself
  try {
    await video.play();
  } catch (e) {
    if (my === generation) stop('The camera\'s video could not play (' + (e && e.message ? e.message : e) + ').');
    return;
  }
  if (my !== generation) return;
  say('calibrating', 'Camera on. Look at the camera with a neutral face…');
  tick(my);
}

function tick(my) {
  if (my !== generation || !session) return;
  const s = session, v = s.video;
  const t0 = performance.now();
  const next = () => { if (my === generation && session) session.timer = setTimeout(() => tick(my), Math.max(0, FRAME_MS - (performance.now() - t0))); };
  if (!v.videoWidth) { next(); return; }
  follow.frames++;
  trackLandmarks(v, v.videoWidth, v.videoHeight).then((r) => {
    if (my !== generation || !session) return;
    if (!r.points) {
      say(s.neutral ? 'no-face' : 'calibrating', 'Camera on. No face found: look at the camera.');
      next();
      return;
    }
    follow.faces++;
    const m = faceMeasures(r.points);
    if (!s.neutral) {
      s.samples.push(m);
      if (s.samples.length >= CALIBRATION_FRAMES) {
        s.neutral = {};
        for (const k of Object.keys(m)) s.neutral[k] = s.samples.reduce((a, x) => a + x[k], 0) / s.samples.length;
      }
      say('calibrating', 'Camera on. Hold a neutral face (' + s.samples.length + ' of ' + CALIBRATION_FRAMES + ')…');
      next();
      return;
    }
    const raw = faceWeights(m, s.neutral);
    const now = performance.now();
    const a = 1 - Math.exp(-(now - s.last) / SMOOTHING_MS);
    s.last = now;
    const w = {};
    for (const [k, x] of Object.entries(raw)) {
      const y = (follow.weights[k] || 0) + a * (x - (follow.weights[k] || 0));
      if (y > 0.01) w[k] = Math.round(y * 1000) / 1000;
    }
    follow.raw = raw;
    follow.weights = w;
    say('following', 'Camera on: following your face (nothing is recorded or sent).');
    driveWeights(w).catch(() => {});
    next();
  }, (e) => {
    if (my === generation) stop('The face detector failed: ' + (e && e.message ? e.message : e));
  });
}

// Stops the camera (every track) and the loop; `reset`: the head back to
// rest. `why`: a message to leave (an error), else the plain "off".
export function stop(why = '', reset = true) {
  const had = session;
  generation++;
  follow.on = false;
  if (had) {
    clearTimeout(had.timer);
    had.stream.getTracks().forEach((t) => t.stop());
    had.video.srcObject = null;
  }
  session = null;
  setDriver(null);
  ui.follow.checked = false;
  say(why ? 'error' : 'off', why || 'Camera off.');
  if (had && reset) driveWeights({}).catch(() => {});
}

export function wireFollowFace() {
  ui.follow.addEventListener('change', () => (ui.follow.checked ? start().catch((e) => stop(String(e))) : stop()));
}
