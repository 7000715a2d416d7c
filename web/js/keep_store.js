// The browser's IndexedDB as the page's memory of its heads (keep.js):
// database "likeness", two stores keyed by a project id:
//   heads  {id, name, savedAt, thumb (PNG data URL), size, vertices, textured,
//           page (options, photos' names, roles, clicks, points)}: small, listed
//   files  {id, bytes (the .likeness.glb from save_project_job), photos: [Blob]}
// Every call resolves or rejects with an Error whose .quota is true when the
// browser's storage is full; nothing here touches the page.
const DB = 'likeness', VERSION = 1;
let opened = null;

function request(r) {
  return new Promise((resolve, reject) => {
    r.onsuccess = () => resolve(r.result);
    r.onerror = () => reject(r.error);
  });
}

function failure(e) {
  const err = new Error(e && e.message ? e.message : String(e));
  err.quota = !!e && (e.name === 'QuotaExceededError' || /quota/i.test(String(e.message)));
  return err;
}

export function openStore() {
  if (!opened) {
    opened = new Promise((resolve, reject) => {
      if (!self.indexedDB) { reject(new Error('this browser keeps no IndexedDB (a private window?)')); return; }
      const r = indexedDB.open(DB, VERSION);
      r.onupgradeneeded = () => {
        r.result.createObjectStore('heads', { keyPath: 'id' });
        r.result.createObjectStore('files', { keyPath: 'id' });
      };
      r.onsuccess = () => resolve(r.result);
      r.onerror = () => reject(failure(r.error));
      r.onblocked = () => reject(new Error('the page\'s storage is held by an older tab of this page'));
    });
    opened.catch(() => { opened = null; });
  }
  return opened;
}

// Runs fn(stores) in one transaction over both stores; resolves when it commits.
async function transact(mode, fn) {
  const db = await openStore();
  return new Promise((resolve, reject) => {
    let tx, value;
    try {
      tx = db.transaction(['heads', 'files'], mode);
      value = fn({ heads: tx.objectStore('heads'), files: tx.objectStore('files') });
    } catch (e) {
      reject(failure(e));
      return;
    }
    tx.oncomplete = () => Promise.resolve(value).then(resolve, reject);
    tx.onerror = () => reject(failure(tx.error));
    tx.onabort = () => reject(failure(tx.error || new Error('the storage write was aborted')));
  });
}

// The heads, newest first (without their bytes).
export async function listHeads() {
  const db = await openStore();
  const all = await request(db.transaction('heads').objectStore('heads').getAll());
  return all.sort((a, b) => b.savedAt - a.savedAt);
}

// Writes a head; file (bytes and photos) when given, else the stored one stays.
export function putHead(head, file) {
  return transact('readwrite', (st) => {
    st.heads.put(head);
    if (file) st.files.put(Object.assign({ id: head.id }, file));
  });
}

// Whether the bytes of head `id` are stored (another tab may have pruned them).
export async function hasFile(id) {
  const db = await openStore();
  return (await request(db.transaction('files').objectStore('files').count(id))) > 0;
}

export async function getFile(id) {
  const db = await openStore();
  return request(db.transaction('files').objectStore('files').get(id));
}

export function deleteHead(id) {
  return transact('readwrite', (st) => { st.heads.delete(id); st.files.delete(id); });
}
