// Automatic face landmarks on a dropped photo (issue 37, stage 1): MediaPipe
// Face Mesh (npm @mediapipe/face_mesh, Apache-2.0), whose package ships its
// models and wasm; the build copies them to vendor/face_mesh/ beside the page,
// so the detector loads from the page's own origin and nothing is fetched
// elsewhere. It is loaded once, when the first photo is dropped, and runs on
// the main thread (it draws with WebGL). It gives 468 points per face; their
// index is the detector's landmark index, which
// core/head/data/mediapipe_landmark_map.json maps onto the generic head.
const BASE = 'vendor/face_mesh/';
export const DETECTOR = 'mediapipe-face-mesh';
export const POINT_COUNT = 468;
// The refined model's iris centres (its points 468-472 and 473-477 are the
// two irises, each centre first).
const IRIS_CENTRES = [468, 473];

let loading = null;   // Promise of {mesh, results}: one detector for the page
let queue = Promise.resolve();

// Where the detector's networks run: 'cpu' (TFLite on XNNPACK, the wasm's
// SIMD) or 'gpu' (WebGL, the solution's default off Apple devices). On a
// software WebGL (SwiftShader, llvmpipe: machines without a GPU, headless
// Chromium) the CPU is 3-4 times faster and its first photo 2 s sooner,
// with the same points to 0.4 px (docs/design/photos.md, "The detector on
// the CPU"); with a GPU the default is kept (not measured here).
// ?detector=cpu|gpu forces it.
let chosenInference = '';
export function detectorInference() {
  if (!chosenInference) {
    const forced = new URLSearchParams(location.search).get('detector');
    chosenInference = forced === 'cpu' || forced === 'gpu' ? forced : softwareWebGL() ? 'cpu' : 'gpu';
  }
  return chosenInference;
}

function softwareWebGL() {
  try {
    const gl = document.createElement('canvas').getContext('webgl');
    if (!gl) return true;  // no WebGL to speak of: the CPU it is
    const info = gl.getExtension('WEBGL_debug_renderer_info');
    const renderer = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
    const lose = gl.getExtension('WEBGL_lose_context');
    if (lose) lose.loseContext();
    return /swiftshader|llvmpipe|softpipe|software|basic render/i.test(renderer);
  } catch (e) {
    return false;
  }
}

function loadScript(src) {
  return new Promise((resolve, reject) => {
    const s = document.createElement('script');
    s.src = src;
    s.onload = resolve;
    s.onerror = () => reject(new Error('the face detector (' + src + ') is missing from this site'));
    document.head.append(s);
  });
}

function detector() {
  if (!loading) {
    loading = (async () => {
      if (!window.FaceMesh) await loadScript(BASE + 'face_mesh.js');
      const mesh = new window.FaceMesh({ locateFile: (file) => BASE + file });
      // Two faces at most, so a second person is noticed. No
      // minDetectionConfidence: in this release setting it breaks the face
      // detector's options ("RET_CHECK failure ... has_num_classes()",
      // google-ai-edge/mediapipe#3504); the default (0.5) is kept. The JS
      // solution has no static-image mode: see the blank frame below.
      mesh.setOptions({ maxNumFaces: 2, refineLandmarks: false, useCpuInference: detectorInference() === 'cpu' });
      const blank = document.createElement('canvas');
      blank.width = blank.height = 64;
      blank.getContext('2d').fillRect(0, 0, 64, 64);
      const holder = { mesh, results: null, blank };
      mesh.onResults((r) => { holder.results = r; });
      await mesh.initialize();
      return holder;
    })();
    loading.catch(() => { loading = null; });  // a later photo may try again
  }
  return loading;
}

// Starts loading the detector (its wasm and models, a few seconds) while
// the dropped photos are still being checked; a failure is left for the
// first detection to report.
export function preloadDetector() {
  queue = queue.then(() => detector()).catch(() => {});
}

// Landmarks of the face in `image` (an ImageBitmap, image or canvas of
// width x height pixels): {faces, points} where points are [x, y] pixels
// (origin top-left) of the first face, index = the detector's landmark
// index, or null when no face was found. One detection at a time.
export function detectLandmarks(image, width, height) {
  const run = queue.then(async () => {
    const d = await detector();
    // A video graph: it would track the face from the previous photo's
    // landmarks and misplace this one's. A blank frame first loses that
    // face, so each photo is detected afresh: the same points as after
    // reset(), in a fifth of the time (docs/design/photos.md).
    await d.mesh.send({ image: d.blank });
    d.results = null;
    await d.mesh.send({ image });
    const faces = (d.results && d.results.multiFaceLandmarks) || [];
    const first = faces[0];
    const points = first ? first.slice(0, POINT_COUNT).map((p) => [p.x * width, p.y * height]) : null;
    return { faces: faces.length, points };
  });
  // A detector that aborted (e.g. a damaged model file) is not reused: the
  // next photo loads a fresh one.
  queue = run.catch(() => { loading = null; });
  return run.catch((e) => {
    const why = e && e.message ? e.message : String(e);
    throw new Error(/^the face detector/.test(why) ? why : 'the face detector failed (' + why + ')');
  });
}

// Follow my face's tracker: a detector of its own with refineLandmarks
// (the attention model: it follows the eyelids, which the plain model's
// points hardly do; on our own renders a closed eye moved its lid points
// by 7 % with the plain model, 34-80 % with this one), one face, made when
// the camera starts and closed when it stops. The photos' detector keeps
// its options (the photo fit's numbers were measured with them).
let tracking = null;  // Promise of {mesh, results}
function tracker() {
  if (!tracking) {
    tracking = (async () => {
      if (!window.FaceMesh) await loadScript(BASE + 'face_mesh.js');
      const mesh = new window.FaceMesh({ locateFile: (file) => BASE + file });
      mesh.setOptions({ maxNumFaces: 1, refineLandmarks: true, useCpuInference: detectorInference() === 'cpu' });
      const holder = { mesh, results: null };
      mesh.onResults((r) => { holder.results = r; });
      await mesh.initialize();
      return holder;
    })();
    tracking.catch(() => { tracking = null; });
  }
  return tracking;
}

// Ends the tracker (Follow my face stopped); the next start makes another.
export function closeTracker() {
  const t = tracking;
  tracking = null;
  if (t) queue = queue.then(() => t.then((d) => d.mesh.close(), () => {})).catch(() => {});
}

// Landmarks of the face in a video frame (Follow my face): as
// detectLandmarks (the first 468 points), but on the tracker and without
// the blank frame first, so it tracks the face from frame to frame as its
// video graph is meant to; with the refined model's two iris centres
// (points 468 and 473, in its order) as `iris`, null without them.
export function trackLandmarks(video, width, height) {
  const run = queue.then(async () => {
    const d = await tracker();
    d.results = null;
    await d.mesh.send({ image: video });
    const faces = (d.results && d.results.multiFaceLandmarks) || [];
    const first = faces[0];
    const px = (p) => [p.x * width, p.y * height];
    return { faces: faces.length, points: first ? first.slice(0, POINT_COUNT).map(px) : null,
             iris: first && first.length >= IRIS_CENTRES[1] + 1 ? IRIS_CENTRES.map((i) => px(first[i])) : null };
  });
  queue = run.catch(() => { tracking = null; });
  return run.catch((e) => {
    const why = e && e.message ? e.message : String(e);
    throw new Error(/^the face detector/.test(why) ? why : 'the face detector failed (' + why + ')');
  });
}

// The points file of a photo, the format the native CLI reads
// (docs/design/photos.md): pixels, index = landmark index, null = missing.
export function landmarksJson(name, width, height, points) {
  const round = (v) => Math.round(v * 100) / 100;
  return {
    format: 'likeness-landmarks', version: 1,
    image: { name, width, height },
    detector: DETECTOR,
    points: points.map((p) => (p && Number.isFinite(p[0]) && Number.isFinite(p[1]) ? [round(p[0]), round(p[1])] : null)),
  };
}
