// The bridge to likeness_viewer.js (SDL2 + WebGL2 on #canvas, its embind
// calls listed in docs/design/web.md): starting it, and the view controls of the
// toolbar and the keyboard. What is shown comes from the other modules.
import { app, params, ui, fatalStartup, clearError, setStatus } from './state.js';
import { stopAnimation } from './animation.js';
import { markShown } from './head_view.js';

function loadScript(src) {
  return new Promise((resolve, reject) => {
    const s = document.createElement('script');
    s.src = src;
    s.onload = resolve;
    s.onerror = () => reject(new Error('could not load ' + src));
    document.head.appendChild(s);
  });
}

// Resolves once the viewer has drawn at least one frame with the head.
function firstFrame(viewer) {
  return new Promise((resolve, reject) => {
    const poll = () => {
      const why = viewer.startup_error();
      if (why) reject(new Error('the 3D viewer could not start: ' + why));
      else if (viewer.frames_drawn() > 0) resolve();
      else requestAnimationFrame(poll);
    };
    poll();
  });
}

// The renderer's name of a WebGL2 context (unmasked where the browser allows).
function rendererName(gl) {
  let name = String(gl.getParameter(gl.RENDERER));
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  if (info) name += ' ' + gl.getParameter(info.UNMASKED_RENDERER_WEBGL);
  return name;
}
const isSoftware = (name) => /swiftshader|llvmpipe|softpipe|software/i.test(name);

// True when WebGL2 is drawn on the CPU (SwiftShader, llvmpipe): no GPU;
// null when no WebGL2 context could be made (the viewer will say so).
// Making this throw-away context costs 0.4-2.4 s on SwiftShader (measured,
// docs/design/page.md), so the answer is kept for the next start.
function softwareWebGL() {
  try {
    const gl = document.createElement('canvas').getContext('webgl2');
    if (!gl) return null;
    const name = rendererName(gl);
    const lose = gl.getExtension('WEBGL_lose_context');
    if (lose) lose.loseContext();
    return isSoftware(name);
  } catch (e) {
    return null;
  }
}

// The verdict of the last start (localStorage), checked again on the
// viewer's own context once it draws: null when unknown (a first visit).
const SOFTWARE_KEY = 'likeness.softwareWebGL';
function rememberedSoftware() {
  try {
    const v = localStorage.getItem(SOFTWARE_KEY);
    return v === '1' ? true : v === '0' ? false : null;
  } catch (e) {
    return null;
  }
}

// Keeps a verdict (true: software) for the next start.
function storeSoftware(software) {
  try {
    localStorage.setItem(SOFTWARE_KEY, software ? '1' : '0');
  } catch (e) { /* no storage: the probe runs at every start */ }
}

// A remembered verdict is checked after the first frame, when the page is
// idle, on the viewer's own context (no new one): a changed GPU or driver
// corrects it for the next start.
function rememberSoftware() {
  const check = () => {
    const gl = ui.canvas.getContext('webgl2');
    if (gl) storeSoftware(isSoftware(rendererName(gl)));
  };
  if (window.requestIdleCallback) requestIdleCallback(check, { timeout: 5000 }); else setTimeout(check, 1000);
}

export async function startViewer() {
  await loadScript('likeness_viewer.js');
  app.timings.viewerScript = performance.now() - app.startedAt;
  // The viewer's wasm is fetched and compiled off the main thread as soon
  // as the module is made; its main runs only once that is done, so the
  // arguments are filled in meanwhile (Emscripten reads Module.arguments,
  // this same array, when it calls main). Before, the probe below ran
  // first and the wasm's fetch waited for it.
  const args = ['--msaa', '0'];
  const made = LikenessViewer({
    canvas: ui.canvas,
    arguments: args,
    print: (t) => console.log('[viewer]', t),
    printErr: (t) => console.warn('[viewer]', t),
    onAbort: (what) => fatalStartup('The 3D viewer stopped: ' + what),
    onRuntimeInitialized: () => { app.timings.viewerRuntime = performance.now() - app.startedAt; },
  });
  // Multisampling doubles SwiftShader's cost of a level-3 frame (measured:
  // docs/journal.md), so a software WebGL gets none; ?msaa=N overrides.
  const remembered = rememberedSoftware();
  if (remembered !== null) {
    app.software = remembered;
  } else {
    const t0 = performance.now();
    const software = softwareWebGL();
    app.timings.softwareProbeMs = performance.now() - t0;
    app.software = !!software;
    if (software !== null) storeSoftware(software);
  }
  app.msaa = params.has('msaa') ? Math.max(0, Number(params.get('msaa')) || 0) : app.software ? 0 : 4;
  args[1] = String(app.msaa);
  const viewer = await made;
  app.viewer = viewer;
  app.timings.viewerModule = performance.now() - app.startedAt;
  await firstFrame(viewer);
  app.timings.firstFrame = performance.now() - app.startedAt;
  ui.overlay.hidden = true;
  if (remembered !== null) rememberSoftware();
  return viewer;
}

// The toolbar (Reset view, Generic head, Wireframe, Point size) and the
// keyboard on the focused canvas.
export function wireViewer() {
  ui.reset.addEventListener('click', () => app.viewer && app.viewer.reset_view());
  ui.generic.addEventListener('click', () => {
    if (!app.viewer) return;
    stopAnimation();
    app.viewer.show_generic_head();
    app.viewer.set_overlay_points(new Float32Array(0), null, null);
    app.viewer.set_components_visible(false);
    markShown(null);
    app.model = null;
    clearError();
    setStatus('Showing the generic head model.');
  });
  // Keyboard control of the focused canvas. Only the view keys are taken;
  // Tab and everything else keep their usual meaning.
  ui.canvas.addEventListener('keydown', (e) => {
    const v = app.viewer;
    if (!v || e.ctrlKey || e.metaKey || e.altKey) return;
    const step = 40;  // pixels of drag per key press
    const arrows = { ArrowLeft: [-step, 0], ArrowRight: [step, 0], ArrowUp: [0, -step], ArrowDown: [0, step] };
    if (arrows[e.key]) {
      const [dx, dy] = arrows[e.key];
      if (e.shiftKey) v.pan(dx, dy); else v.orbit(dx, dy);
    } else if (e.key === '+' || e.key === '=') v.zoom(120);
    else if (e.key === '-' || e.key === '_') v.zoom(-120);
    else if (e.key === 'r' || e.key === 'R') v.reset_view();
    else return;
    e.preventDefault();
  });
  ui.wireframe.addEventListener('change', () => app.viewer && app.viewer.set_wireframe(ui.wireframe.checked));
  ui.pointSize.addEventListener('input', () => app.viewer && app.viewer.set_point_size(Number(ui.pointSize.value)));
}
