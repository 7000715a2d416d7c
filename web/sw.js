// The page's service worker: after the first visit Likeness works with the
// network off (issue 39), and the browser can install it as an app.
//
// What it keeps: every file the build lists in offline.json (the page, its
// modules, the wasm cores, the landmark model, the sample when installed),
// with a content hash each, in one Cache Storage cache. On install, and each
// time a page asks (after it started), it fetches the list and (re)fetches
// only the files whose hash changed; files no longer listed are dropped.
// Requests go to the network first, so an online page is always the served
// one; the cache answers only when the network does not. Nothing here ever
// asks another origin: only same-origin GETs are handled.
'use strict';
const CACHE = 'likeness-offline';
const LIST = 'offline.json';
const KEPT_LIST = '__kept_offline.json';  // the last list fully cached, stored in the cache itself

let updating = null;  // the running update, shared by concurrent asks

async function update() {
  const r = await fetch(LIST, { cache: 'no-store' });
  if (!r.ok) throw new Error(LIST + ': HTTP ' + r.status);
  const list = await r.json();
  if (!list || !Array.isArray(list.files)) throw new Error(LIST + ' holds no file list');
  const cache = await caches.open(CACHE);
  const keptResponse = await cache.match(KEPT_LIST);
  const kept = keptResponse ? await keptResponse.json() : { files: [] };
  const keptHash = new Map(kept.files.map((f) => [f.path, f.sha256]));
  let fetched = 0, bytes = 0;
  for (const f of list.files) {
    bytes += f.size;
    const url = new URL(f.path, self.registration.scope).href;
    if (keptHash.get(f.path) === f.sha256 && await cache.match(url)) continue;
    const got = await fetch(url, { cache: 'no-store' });
    if (!got.ok) throw new Error(f.path + ': HTTP ' + got.status);
    await cache.put(url, got);
    fetched++;
  }
  const listed = new Set(list.files.map((f) => new URL(f.path, self.registration.scope).href));
  for (const req of await cache.keys()) {
    if (!listed.has(req.url) && !req.url.endsWith('/' + KEPT_LIST)) await cache.delete(req);
  }
  await cache.put(KEPT_LIST, new Response(JSON.stringify(list), { headers: { 'content-type': 'application/json' } }));
  return { version: list.version, files: list.files.length, bytes, fetched };
}

// The copy already kept, when every file of its list is there (the network
// being off is no reason to say the app cannot run offline).
async function keptCopy() {
  const cache = await caches.open(CACHE);
  const keptResponse = await cache.match(KEPT_LIST);
  if (!keptResponse) return null;
  const list = await keptResponse.json();
  for (const f of list.files) if (!await cache.match(new URL(f.path, self.registration.scope).href)) return null;
  return { version: list.version, files: list.files.length, bytes: list.files.reduce((n, f) => n + f.size, 0), fetched: 0 };
}

function updateOnce() {
  if (!updating) updating = update().finally(() => { updating = null; });
  return updating;
}

async function tell(message) {
  for (const client of await self.clients.matchAll({ type: 'window' })) client.postMessage(message);
}

self.addEventListener('install', (event) => {
  self.skipWaiting();
  // A failed first copy is said to the page, not fatal: the page works online.
  event.waitUntil(updateOnce().catch(() => {}));
});

self.addEventListener('activate', (event) => { event.waitUntil(self.clients.claim()); });

self.addEventListener('message', (event) => {
  if (!event.data || event.data.type !== 'offline-update') return;
  const why = (e) => (e && e.message ? e.message : String(e));
  event.waitUntil(updateOnce()
    .then((r) => tell(Object.assign({ type: 'offline-ready' }, r)))
    .catch(async (e) => {
      const kept = await keptCopy().catch(() => null);
      if (kept) return tell(Object.assign({ type: 'offline-ready', notUpdated: why(e) }, kept));
      return tell({ type: 'offline-failed', message: why(e) });
    }));
});

self.addEventListener('fetch', (event) => {
  const req = event.request;
  if (req.method !== 'GET' || new URL(req.url).origin !== self.location.origin) return;
  event.respondWith(fetch(req).catch(async (err) => {
    const cache = await caches.open(CACHE);
    // The page itself is asked for with its parameters (index.html?autofit=0).
    const hit = await cache.match(req, { ignoreSearch: true }) ||
                (req.mode === 'navigate' ? await cache.match(new URL('index.html', self.registration.scope).href) : null);
    if (hit) return hit;
    throw err;
  }));
});
