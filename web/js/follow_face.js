// "Follow my face" (issue 38, in the page): the webcam drives the head's
// ARKit shapes through the face-mesh detector (landmarks.js). Off by
// default; on, the camera's frames go only to the detector in this page:
// nothing is recorded, stored or sent, and a visible indicator shows while
// the camera is on. It stops (and the camera's tracks end) when toggled off,
// when another head or job takes over (the expressions are cleared), when a
// preset, a slider or Talk is used, and when the camera goes away.
//
// Per detected frame (at most ~12 per second; the tracker is
// landmarks.js's refined detector, which follows the eyelids) the
// landmarks give a few measures, each divided by a length of the face so
// that distance to the camera does not matter: each eye's lid gaps over its
// width, the lips' gap, each mouth corner's height along the face's up
// (chin to forehead) from the eyes' outer corners and its distance out from
// the face's middle, the mouth's width, the inner and outer brows' heights
// above the eyes, the nose tip's place across and along the face (the
// head's yaw and pitch), and each iris centre's place across and up the
// face from its eye's corners (the gaze: across per eye, up and down both
// eyes together). The first frames with a face (CALIBRATION_FRAMES)
// are taken as the neutral face; the shapes' weights are the measures'
// changes from it over a full-motion span (SPAN, set from the tracker on
// our own renders of each shape), clamped to [0, 1] and smoothed over time;
// the head's turn turns the view. None is calibrated per person beyond the
// neutral face, and none was tried on a real face.
import { app, ui } from './state.js';
import { closeTracker, trackLandmarks } from './landmarks.js';
import { driveWeights, setDriver } from './expressions.js';
import { stopAnimation } from './animation.js';

const CALIBRATION_FRAMES = 8;
const FRAME_MS = 80;          // detector at most every 80 ms
const SMOOTHING_MS = 90;      // exponential smoothing's time constant

// MediaPipe Face Mesh indices (the subject's left is the image's right).
const P = {
  // Three upper/lower lid pairs per eye, inner to outer.
  eyeL: { lids: [[385, 380], [386, 374], [387, 373]], inner: 362, outer: 263 },
  eyeR: { lids: [[158, 153], [159, 145], [160, 144]], inner: 133, outer: 33 },
  lipTop: 13, lipBottom: 14, cornerL: 291, cornerR: 61,
  browInnerL: 336, browInnerR: 107, browOuterL: 300, browOuterR: 70,
  forehead: 10, chin: 152, noseTip: 1, faceL: 454, faceR: 234,
};

// The nose tip's depth in front of the eyes' outer corners, over the
// distance between those corners: a head turned by a angle moves the tip
// by NOSE_DEPTH * sin(a) of that distance across the face (yaw) or along
// it (pitch). Set from the detector on our own renders (flow follow-face:
// the generic head seen 20 degrees from the side and 15 from above).
const NOSE_DEPTH = { yaw: 0.55, pitch: 0.34 };
const EYE_OVER_FACE_WIDTH = 0.647;
const MAX_TURN_DEG = 45;

// Change from neutral (in the measure's units) that makes a weight of 1,
// set from the tracker on our own renders of each shape at full weight
// (the generic head, flow follow-face; docs/design/page.md has the
// figures); checked on no real face.
const SPAN = {
  blink: 0.5,       // of the neutral lid opening (renders: 34 % and 80 % closed)
  jawOpen: 0.25,    // lip gap over eye-corner distance (render: 0.33)
  smile: 0.1,       // corner lift over eye-corner distance (renders: 0.095-0.127)
  smileOut: 0.05,   // corner drawn out from the face's middle (renders: 0.049-0.070)
  brow: 0.05,       // brow lift over eye-corner distance (render: 0.038)
  pucker: 0.06,     // mouth width loss over eye-corner distance (render: 0.044)
  // The iris centre's move across the face, one eye (renders of 25
  // degrees: 0.030-0.040; the detector reads the lids' coupling and the
  // head's turn as up to 0.011 of gaze), and both irises' mean move up and
  // down (renders of both eyes 25 degrees up: 0.015, the right iris read
  // at less than half the left's; down: 0.011, the upper lid covering the
  // iris's top; other shapes and the turned head: up to 0.007): dead
  // zones below LOOK_DEAD and LOOK_DEAD_UP.
  lookAcross: 0.035,
  lookUp: 0.017,
  lookDown: 0.012,
};
const LOOK_DEAD = 0.008, LOOK_DEAD_UP = 0.007;
// The iris lies in front of its eye's corners: a head turned by a yaw moves
// it across their midpoint in the image by about LOOK_DEPTH * sin(yaw)
// (over the eye-corner distance) with the eyes still in the head (our
// render turned 20 degrees: the near eye 0.008, the far eye 0.023; their
// mean over sin 20 degrees). Taken off before the gaze is read.
const LOOK_DEPTH = 0.045;
const BLINK_DEAD = 0.1;

const sub = (a, b) => [a[0] - b[0], a[1] - b[1]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1];
const len = (a) => Math.hypot(a[0], a[1]);
const clamp01 = (x) => Math.min(1, Math.max(0, x));

// The face's measures from its landmarks ([x, y] pixels) and, when the
// tracker gives them, the two iris centres (either order).
export function faceMeasures(pts, iris = null) {
  const at = (i) => pts[i];
  // The unit of length: the face's width at the eyes (its outline, 234 to
  // 454) times the generic head's eye-corner distance over it (0.647), so
  // the spans read as fractions of the eye-corner distance. Not the eyes'
  // corners themselves: a closing lid moves its eye's outer corner (4 %
  // wider on our right-blink render, read as a pucker).
  const scale = EYE_OVER_FACE_WIDTH * len(sub(at(P.faceL), at(P.faceR)));
  const upRaw = sub(at(P.forehead), at(P.chin));
  const up = [upRaw[0] / len(upRaw), upRaw[1] / len(upRaw)];
  const height = (i, ref) => dot(sub(at(i), at(ref)), up) / scale;
  // The eye's opening: its lid gaps' mean over its width.
  const eye = (e) => e.lids.reduce((a, [t, b]) => a + len(sub(at(t), at(b))), 0) / (e.lids.length * len(sub(at(e.inner), at(e.outer))));
  // Corner heights from the eyes' outer corners (the rigid upper face), so
  // that the jaw dropping (corners down) does not read as a smile.
  const eyes = [(at(P.eyeL.outer)[0] + at(P.eyeR.outer)[0]) / 2, (at(P.eyeL.outer)[1] + at(P.eyeR.outer)[1]) / 2];
  // Across the face, towards the subject's left (the image's right on a
  // camera that does not mirror).
  const acrossRaw = sub(at(P.eyeL.outer), at(P.eyeR.outer));
  const across = [acrossRaw[0] / len(acrossRaw), acrossRaw[1] / len(acrossRaw)];
  const nose = sub(at(P.noseTip), eyes);
  // Each eye's gaze: its iris centre (the one nearer the eye) from the
  // midpoint of its corners, across and up the face; NaN without irises.
  const gaze = (e) => {
    if (!iris || iris.length < 2) return [NaN, NaN];
    const mid = [(at(e.inner)[0] + at(e.outer)[0]) / 2, (at(e.inner)[1] + at(e.outer)[1]) / 2];
    const c = len(sub(iris[0], mid)) <= len(sub(iris[1], mid)) ? iris[0] : iris[1];
    return [dot(sub(c, mid), across) / scale, dot(sub(c, mid), up) / scale];
  };
  const [lookAcrossL, lookUpL] = gaze(P.eyeL), [lookAcrossR, lookUpR] = gaze(P.eyeR);
  return {
    lookAcrossL, lookUpL, lookAcrossR, lookUpR,
    noseAcross: dot(nose, across) / scale, noseUp: dot(nose, up) / scale,
    eyeL: eye(P.eyeL), eyeR: eye(P.eyeR),
    lipGap: len(sub(at(P.lipTop), at(P.lipBottom))) / scale,
    cornerL: dot(sub(at(P.cornerL), eyes), up) / scale,
    cornerR: dot(sub(at(P.cornerR), eyes), up) / scale,
    mouthWidth: len(sub(at(P.cornerL), at(P.cornerR))) / scale,
    // Each corner's distance from the face's middle (the eyes' midpoint), across the face.
    cornerOutL: dot(sub(at(P.cornerL), eyes), across) / scale,
    cornerOutR: -dot(sub(at(P.cornerR), eyes), across) / scale,
    browInner: (height(P.browInnerL, P.eyeL.inner) + height(P.browInnerR, P.eyeR.inner)) / 2,
    browOuterL: height(P.browOuterL, P.eyeL.outer), browOuterR: height(P.browOuterR, P.eyeR.outer),
  };
}

// The head's turn (degrees) from the measures m against the neutral ones
// n: yaw + towards the head's own left, pitch + chin up (the nose tip moves
// across or up the face by NOSE_DEPTH * sin of the turn).
export function headTurn(m, n) {
  const deg = (x, depth) => Math.max(-MAX_TURN_DEG, Math.min(MAX_TURN_DEG, (Math.asin(Math.max(-1, Math.min(1, x / depth))) * 180) / Math.PI));
  return { yaw: deg(m.noseAcross - n.noseAcross, NOSE_DEPTH.yaw), pitch: deg(m.noseUp - n.noseUp, NOSE_DEPTH.pitch) };
}

// ARKit weights from the measures m against the neutral ones n.
export function faceWeights(m, n) {
  const jaw = clamp01((m.lipGap - n.lipGap) / SPAN.jawOpen);
  const narrow = clamp01((n.mouthWidth - m.mouthWidth) / SPAN.pucker);
  // A smile lifts its corner and draws it out, each side on its own (the
  // mouth's whole width raised both sides for a one-sided smile); the
  // product keeps either alone (the jaw dropping draws the corners out, a
  // closing lid shifts the eyes' corners) from reading as a smile.
  const smile = (c, c0, o, o0) => clamp01((c - c0) / SPAN.smile) * clamp01((o - o0) / SPAN.smileOut);
  // A blink: the share of the neutral opening closed, past BLINK_DEAD (the
  // detector narrows the lids' gaps by 16 % on an eye looking up).
  const closed = (e, e0) => clamp01((1 - e / e0 - BLINK_DEAD) / (SPAN.blink - BLINK_DEAD));
  const blinkL = closed(m.eyeL, n.eyeL), blinkR = closed(m.eyeR, n.eyeR);
  // The eyes' gaze: each iris's move from neutral past a dead zone (the
  // detector's jitter and couplings, SPAN above); towards the face's left
  // is the left eye looking out and the right eye looking in. A closing lid
  // hides the iris (its points wander): the gaze fades once the blink
  // passes 0.5 (looking up narrows the lids' gaps to a blink of about 0.3).
  const look = {};
  const gazeKeys = ['lookAcrossL', 'lookUpL', 'lookAcrossR', 'lookUpR'];
  if (gazeKeys.every((k) => Number.isFinite(m[k]) && Number.isFinite(n[k]))) {
    const past = (d, span, dead = LOOK_DEAD) => clamp01((d - dead) / (span - dead));
    const openL = clamp01(2 * (1 - blinkL)), openR = clamp01(2 * (1 - blinkR));
    // The eyes turn up and down together (people cannot look up with one
    // eye): the vertical gaze is both irises' mean move, each by how open
    // its eye is, so one eye's misread (the detector's, on a head tilted
    // 15 degrees: -0.010 on one eye, +0.006 on the other) is halved and a
    // closed eye's wandering iris does not count.
    const both = openL + openR;
    const y = both > 0 ? (openL * (m.lookUpL - n.lookUpL) + openR * (m.lookUpR - n.lookUpR)) / both : 0;
    const side = (open, x, towardsLeft, awayFromLeft, suffix) => {
      look[towardsLeft + suffix] = open * past(x, SPAN.lookAcross);
      look[awayFromLeft + suffix] = open * past(-x, SPAN.lookAcross);
      look['eyeLookUp' + suffix] = open * past(y, SPAN.lookUp, LOOK_DEAD_UP);
      look['eyeLookDown' + suffix] = open * past(-y, SPAN.lookDown, LOOK_DEAD_UP);
    };
    const turned = LOOK_DEPTH * Math.sin((headTurn(m, n).yaw * Math.PI) / 180);
    side(openL, m.lookAcrossL - n.lookAcrossL - turned, 'eyeLookOut', 'eyeLookIn', 'Left');
    side(openR, m.lookAcrossR - n.lookAcrossR - turned, 'eyeLookIn', 'eyeLookOut', 'Right');
  }
  return {
    eyeBlinkLeft: blinkL,
    eyeBlinkRight: blinkR,
    ...look,
    jawOpen: jaw,
    mouthSmileLeft: smile(m.cornerL, n.cornerL, m.cornerOutL, n.cornerOutL),
    mouthSmileRight: smile(m.cornerR, n.cornerR, m.cornerOutR, n.cornerOutR),
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
  head: { yaw: 0, pitch: 0 },   // the last head turn applied to the view (degrees, smoothed)
  rawHead: { yaw: 0, pitch: 0 },
  // Tests: probe(video) is called as a frame is sent and again when its
  // landmarks come back; with it set, each frame's {tag, tagAfter, raw,
  // head} goes to log (the flow reads a mark in its video's corner).
  probe: null,
  log: [],
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
  follow.head = { yaw: 0, pitch: 0 };
  follow.rawHead = { yaw: 0, pitch: 0 };
  follow.log = [];
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
  session = { stream, video, timer: 0, neutral: null, samples: [], last: performance.now(), turned: { yaw: 0, pitch: 0 } };
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
  const tag = follow.probe ? follow.probe(v) : undefined;
  trackLandmarks(v, v.videoWidth, v.videoHeight).then((r) => {
    if (my !== generation || !session) return;
    if (follow.probe && s.neutral && r.points) {
      const m = faceMeasures(r.points, r.iris);
      follow.log.push({ tag, tagAfter: follow.probe(v), raw: faceWeights(m, s.neutral), head: headTurn(m, s.neutral), m });
    }
    if (!r.points) {
      say(s.neutral ? 'no-face' : 'calibrating', 'Camera on. No face found: look at the camera.');
      next();
      return;
    }
    follow.faces++;
    const m = faceMeasures(r.points, r.iris);
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
    const turn = headTurn(m, s.neutral);
    follow.rawHead = turn;
    // A degenerate face (points on top of each other) gives NaN: the view keeps its last turn.
    if (Number.isFinite(turn.yaw) && Number.isFinite(turn.pitch))
      follow.head = { yaw: follow.head.yaw + a * (turn.yaw - follow.head.yaw), pitch: follow.head.pitch + a * (turn.pitch - follow.head.pitch) };
    say('following', 'Camera on: following your face (nothing is recorded or sent).');
    driveWeights(w).then(() => { if (my === generation && session) turnView(session, follow.head); }, () => {});
    next();
  }, (e) => {
    if (my === generation) stop('The face detector failed: ' + (e && e.message ? e.message : e));
  });
}

// The view turned as the head turns: the head on screen turns as the face
// in the camera does (the camera's yaw and pitch the opposite of the
// head's), by the difference from what was applied so far, so the user's
// own orbiting is kept. OrbitCamera::orbit turns by 180 degrees per canvas
// height: yaw -= dx, pitch += dy.
function turnView(s, head) {
  const v = app.viewer;
  if (!v || !v.orbit) return;
  const h = document.getElementById('canvas').height || 1;
  const want = { yaw: -head.yaw, pitch: -head.pitch };
  const dYaw = want.yaw - s.turned.yaw, dPitch = want.pitch - s.turned.pitch;
  if (Math.abs(dYaw) < 0.05 && Math.abs(dPitch) < 0.05) return;
  v.orbit((-dYaw * h) / 180, (dPitch * h) / 180);
  s.turned = want;
}

// Stops the camera (every track) and the loop; `reset`: the head back to
// rest. `why`: a message to leave (an error), else the plain "off".
export function stop(why = '', reset = true) {
  const had = session;
  generation++;
  follow.on = false;
  if (had) {
    turnView(had, { yaw: 0, pitch: 0 });  // the view as it was before following
    clearTimeout(had.timer);
    had.stream.getTracks().forEach((t) => t.stop());
    had.video.srcObject = null;
  }
  session = null;
  if (had) closeTracker();
  setDriver(null);
  ui.follow.checked = false;
  say(why ? 'error' : 'off', why || 'Camera off.');
  if (had && reset) driveWeights({}).catch(() => {});
}

export function wireFollowFace() {
  ui.follow.addEventListener('change', () => (ui.follow.checked ? start().catch((e) => stop(String(e))) : stop()));
}
