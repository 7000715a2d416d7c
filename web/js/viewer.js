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

// The attributes the viewer's SDL asks WebGL for without multisampling.
const SDL_ATTRIBUTES = { alpha: false, depth: true, stencil: false, antialias: false };

// Decides the viewer's multisampling before it starts, from the WebGL2
// renderer's name: none on a software WebGL (SwiftShader, llvmpipe: it
// doubles a level-3 frame's cost, docs/journal.md), 4 samples on a GPU;
// ?msaa=N overrides. The name is read from #canvas's own context, made
// with the attributes SDL asks for, which the viewer then gets as its own
// (a canvas has one context): a throw-away context cost 0.3-2.3 s of the
// start on SwiftShader. With multisampling the canvas is replaced by a
// fresh copy, so SDL makes its context with antialias. Called before
// anything listens on the canvas.
export function prepareCanvas() {
  let software = false;
  try {
    const gl = ui.canvas.getContext('webgl2', SDL_ATTRIBUTES);
    if (gl) {
      let name = String(gl.getParameter(gl.RENDERER));
      const info = gl.getExtension('WEBGL_debug_renderer_info');
      if (info) name += ' ' + gl.getParameter(info.UNMASKED_RENDERER_WEBGL);
      software = /swiftshader|llvmpipe|softpipe|software/i.test(name);
    }
  } catch (e) {
    software = false;
  }
  app.software = software;
  app.msaa = params.has('msaa') ? Math.max(0, Number(params.get('msaa')) || 0) : software ? 0 : 4;
  if (app.msaa > 0) {
    const fresh = ui.canvas.cloneNode(false);
    ui.canvas.replaceWith(fresh);
    ui.canvas = fresh;
  }
}

export async function startViewer() {
  await loadScript('likeness_viewer.js');
  const viewer = await LikenessViewer({
    canvas: ui.canvas,
    arguments: ['--msaa', String(app.msaa)],
    print: (t) => console.log('[viewer]', t),
    printErr: (t) => console.warn('[viewer]', t),
    onAbort: (what) => fatalStartup('The 3D viewer stopped: ' + what),
    onRuntimeInitialized: () => { app.timings.viewerRuntime = performance.now() - app.startedAt; },
  });
  app.viewer = viewer;
  app.timings.viewerModule = performance.now() - app.startedAt;
  await firstFrame(viewer);
  app.timings.firstFrame = performance.now() - app.startedAt;
  ui.overlay.hidden = true;
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
