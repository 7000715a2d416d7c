// Likeness web app: wires the page to two WebAssembly modules.
//   likeness_viewer.js  (main thread) draws on #canvas with WebGL2 via SDL2.
//   worker.js -> likeness_worker.js  (Web Worker) runs the core's jobs.
// Files are read locally and transferred to the worker; nothing is fetched
// from anywhere but this page's own origin.
//
// The page's modules, one concern each:
//   page_state.js     the page's states and what each allows (one owner: jobs, errors, Dismiss, Cancel)
//   state.js          URL parameters, elements, window.likeness, the states applied to the page, status
//   worker_client.js  the worker: start-up, jobs as promises, Cancel, the warm-up worker
//   viewer.js         the 3D viewer's start-up and view controls
//   files.js          received files: size limit, file list, sorting a drop
//   scan.js           loading a scan and the built-in samples (a scan, photos)
//   photos.js         photos and their points; photo_roles.js: eye and smile photos
//   capture.js        Take photos (the camera) and the views still wanted (views.js)
//   clicker.js        landmark clicks on a photo
//   fit.js            Fit head and the Pipeline rows; checks.js: the fitted head's checks
//   photos_head.js    a head from the photos' face points, when no scan is loaded
//   head_view.js      which mesh of the fit is drawn, and how
//   texture.js        the Texture stage
//   animation.js      animation and adaptive detail
//   expressions.js    Expressions: presets, shape sliders, Talk (the muscle layer's baked shapes)
//   export.js         downloads
//   project.js        Save project / Open project (.likeness.glb)
//   keep.js           the head kept in IndexedDB (keep_store.js), offered back after a reload
//   offline.js        the service worker (sw.js): a copy of the app for offline use
import { app, page, params, ui, clearError, fatalStartup, setStatus } from './state.js';
import { cancelJobs, startWorker, warmUp } from './worker_client.js';
import { startViewer, wireViewer } from './viewer.js';
import { wireFiles } from './files.js';
import { loadSample, loadPhotosSample } from './scan.js';
import { wireClicker } from './clicker.js';
import { wireCapture } from './capture.js';
import { wireFit } from './fit.js';
import { wirePhotosHead } from './photos_head.js';
import { wireHeadView } from './head_view.js';
import { wireTexture } from './texture.js';
import { wireAnimation } from './animation.js';
import { wireExpressions } from './expressions.js';
import { wireFollowFace } from './follow_face.js';
import { wireExport } from './export.js';
import { wireProject } from './project.js';
import { offerRestore, wireKeep } from './keep.js';
import { keepOfflineCopy, wireOffline } from './offline.js';

function wire() {
  // ?autofit=0 starts with Auto-run off (load scans without fitting them).
  if (params.get('autofit') === '0') ui.autoFit.checked = false;
  wireFiles();
  ui.dismiss.addEventListener('click', clearError);
  ui.sample.addEventListener('click', loadSample);
  ui.samplePhotos.addEventListener('click', loadPhotosSample);
  ui.cancel.addEventListener('click', () => page.cancel());
  app.cancelJobs = cancelJobs;
  wireViewer();
  wireFit();
  wirePhotosHead();
  wireHeadView();
  wireAnimation();
  wireExpressions();
  wireFollowFace();
  wireExport();
  wireProject();
  wireTexture();
  wireClicker();
  wireCapture();
  wireKeep();
  wireOffline();
}

// Said when the page could have run the threaded core but it did not start
// (worker.js fell back to one thread): the fit is slower, its result the same.
function threadsNote() {
  const why = app.workerThreads && app.workerThreads.fallback;
  return why ? ' Note: the multi-threaded core could not start in this browser (' + why +
               '), so the core runs on one thread: slower, same results.' : '';
}

async function start() {
  wire();
  setStatus('Starting the viewer and the core…');
  let coreFailed = null;
  try {
    const workerUp = startWorker().catch((e) => { coreFailed = e; throw e; });
    workerUp.catch(() => {});  // handled below, after the viewer
    const viewer = await startViewer();
    await workerUp;
    viewer.set_point_size(Number(ui.pointSize.value));
    // ?profile=1: the viewer waits for each draw to finish (glFinish) so
    // animation.profile can split a frame's time; it slows drawing down.
    if (params.get('profile') === '1') viewer.set_profiling(true);
    app.loadMs = performance.now() - app.startedAt;
    warmUp(app.workerThreads.variant).catch(() => {});
    page.started();
    offerRestore().catch(() => {});  // a browser without storage: nothing to offer
    keepOfflineCopy();
    // On a touch screen the camera is the way in (Take photos, capture.js).
    const start = matchMedia('(pointer: coarse)').matches ? 'Take photos of your head, or choose a head scan, to begin.'
      : 'Drop a head scan, or photos of a head, to begin.';
    setStatus('Ready. Showing the generic head. ' + start + threadsNote());
  } catch (e) {
    const why = e && e.message ? e.message : String(e);
    if (coreFailed) {
      // The viewer may be fine; the core (WebAssembly in a Web Worker) is not.
      fatalStartup('The core of Likeness could not start: ' + why + '. Reload the page to try again' +
                   ' (if it keeps failing, the site is missing files: scripts/build makes them).');
    } else {
      fatalStartup('Could not start Likeness: ' + why + '. This app needs WebGL 2 and WebAssembly.');
    }
  }
}

if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', start);
else start();
