// Take photos (issue 39, phones): the camera button (a file input with
// `capture`, so a phone opens its camera) and the guide around the head:
// which views a head from photos still wants, from each photo's face points
// (views.js), updated as each photo's points come in. Photos taken while a
// job runs wait and are added when it ends: a taken photo is never dropped.
// While photos are being taken, Auto-run makes the head once the guide has
// enough (photos_head.js reads app.viewGuide), not after every photo.
import { app, onPageChange } from './state.js';
import { handleFiles } from './files.js';
import { facePhotos, findingFacePoints } from './photos.js';
import { VIEWS, viewGuide } from './views.js';
import { photoCount } from './wording.js';

const $ = (id) => document.getElementById(id);
const LEAST = 5;       // photos with face points before the head is made by itself
let taken = 0;
const waiting = [];    // taken while a job ran


// The guide: shown while no scan is loaded and photos are taken or dropped.
function renderViewGuide() {
  const photos = facePhotos();
  const guide = $('view-guide');
  guide.hidden = !!app.scan || !(app.capturing || photos.length);
  const g = app.viewGuide = viewGuide(photos.map((p) => (p.detect ? p.detect.points : null)), LEAST);
  if (guide.hidden) return;
  const list = $('view-list');
  list.textContent = '';
  for (const v of VIEWS) {
    const li = document.createElement('li');
    const n = g.counts[v.id];
    li.className = n ? 'have' : 'missing';
    li.textContent = v.label + (n ? ' (' + n + ')' : ': missing');
    list.append(li);
  }
  const finding = photos.filter(findingFacePoints).length;
  // Detected, and no face: not a photo the detector never saw (restored).
  const noFace = photos.filter((p) => p.detect && !findingFacePoints(p) && !p.detect.points).length;
  let hint;
  if (waiting.length) hint = photoCount(waiting.length) + ' taken meanwhile: added when the current job ends.';
  else if (finding) hint = 'Finding the face in ' + photoCount(finding) + '…';
  else if (g.next) hint = 'Next: the ' + g.next.label + ' view: ' + g.next.ask + '.';
  else if (!g.enough) hint = 'Every view is there. ' + (LEAST - g.withFace) + ' more ' + (LEAST - g.withFace === 1 ? 'photo' : 'photos') + ' from in between, or a little ' +
                             'from above and below, make a better head.';
  else hint = g.withFace + ' photos with a face: enough for a head. More views between these make it better.';
  if (noFace && !finding) hint += ' No face was found in ' + photoCount(noFace) + (noFace === 1 ? ': it is' : ': they are') + ' kept for the texture but not ' +
                                  'used for the shape (a full profile has too little of the face for the detector).';
  $('view-hint').textContent = hint;
}

// A phone's camera names every photo the same (image.jpg): each taken photo
// gets a name of its own, so it never replaces the one before.
function takenPhoto(file) {
  taken++;
  const ext = /\.png$/i.test(file.name) ? 'png' : 'jpg';
  return new File([file], 'photo-' + String(taken).padStart(2, '0') + '.' + ext, { type: file.type, lastModified: file.lastModified });
}

async function addTaken(files) {
  app.capturing = true;
  if (document.body.dataset.state === 'working' || waiting.length) {
    waiting.push(...files);
    renderViewGuide();
    return;
  }
  await handleFiles(files);
}

// Called just after a job ended: the code that ended it may have started
// the next one meanwhile (a head from photos goes on to its texture); then
// the photos wait for that one too.
function flushWaiting() {
  const state = document.body.dataset.state;
  if (!waiting.length || (state !== 'ready' && state !== 'done')) return;
  handleFiles(waiting.splice(0));
}

export function wireCapture() {
  const input = $('camera-input');
  input.addEventListener('change', () => {
    const files = Array.from(input.files || []).map(takenPhoto);
    input.value = '';
    if (files.length) addTaken(files);
  });
  onPageChange((snap) => {
    input.disabled = snap.state === 'loading' || !!snap.fatal || app.startupFailed;
    renderViewGuide();
    // The job that held them back has ended: add the photos taken meanwhile
    // (after an error, once its banner is dismissed).
    if (waiting.length && (snap.state === 'ready' || snap.state === 'done')) queueMicrotask(flushWaiting);
  });
}
