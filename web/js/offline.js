// Offline after the first visit (issue 39): registers sw.js, asks it to bring
// its copy of the app up to date once the page has started, and says in the
// header whether this browser can run Likeness without the network.
// ?no_sw=1 leaves the service worker out (tests that intercept requests).
import { app, params } from './state.js';

const badge = () => document.getElementById('offline-badge');

function show(text, cls) {
  const b = badge();
  if (!b) return;
  b.hidden = false;
  b.textContent = text;
  b.className = 'offline-badge ' + (cls || '');
}

export function wireOffline() {
  app.offline = { supported: 'serviceWorker' in navigator && params.get('no_sw') !== '1', ready: false };
  if (!app.offline.supported) return;
  navigator.serviceWorker.addEventListener('message', (event) => {
    const m = event.data || {};
    if (m.type === 'offline-ready') {
      Object.assign(app.offline, { ready: true, files: m.files, bytes: m.bytes, fetched: m.fetched, version: m.version,
                                   notUpdated: m.notUpdated || null });
      show(navigator.onLine && !m.notUpdated ? 'Works offline' : 'Offline: running from this browser\'s copy', 'ready');
      badge().title = 'This browser keeps a copy of Likeness (' + m.files + ' files, ' +
                      (m.bytes / 1048576).toFixed(1) + ' MB): it works with the network off.' +
                      (m.notUpdated ? ' The copy could not be updated now (' + m.notUpdated + ').' : '');
    } else if (m.type === 'offline-failed') {
      Object.assign(app.offline, { ready: false, failed: m.message });
      show('Online only', 'failed');
      badge().title = 'Could not keep a copy of Likeness for offline use: ' + m.message;
    }
  });
}

// After start-up (so the copy never competes with the page's own loading).
export async function keepOfflineCopy() {
  if (!app.offline || !app.offline.supported) return;
  try {
    const reg = await navigator.serviceWorker.register('sw.js');
    const sw = reg.active || reg.waiting || reg.installing;
    const ask = (w) => w.postMessage({ type: 'offline-update' });
    if (sw && sw.state === 'activated') ask(sw);
    else if (sw) sw.addEventListener('statechange', () => { if (sw.state === 'activated') ask(sw); });
  } catch (e) {
    Object.assign(app.offline, { ready: false, failed: e && e.message ? e.message : String(e) });
    show('Online only', 'failed');
  }
}
