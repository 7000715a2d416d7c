// Which view of the head a photo shows, from its face points (MediaPipe
// Face Mesh indices), and which of the views a head from photos wants are
// still missing: the live hint of "Take photos" (capture.js). Plain
// functions of points (tested in Node by tests/browser/views_node.mjs on the
// detector's points of real photos).

// Landmark indices: the nose tip, the face outline at the cheekbones (the
// subject's right, then left), the forehead's top and the chin.
const NOSE = 1, RIGHT_CHEEK = 234, LEFT_CHEEK = 454, FOREHEAD = 10, CHIN = 152;

// Where the nose tip lies between the two cheek outline points, along the
// line between them: 0.5 frontal, towards 0 as the head turns to show its
// left cheek (the nose moves towards the subject's right outline), beyond
// 1 or 0 as the far outline hides behind the nose. Measured on the
// detector's points of Kira's photos (tests/photos/data/kira): frontal
// 0.50-0.51, turned about 17 deg 0.76, three-quarter views -0.19..-0.07
// and 0.96-1.29.
export function noseOffset(points) {
  const n = points && points[NOSE], a = points && points[RIGHT_CHEEK], b = points && points[LEFT_CHEEK];
  if (!n || !a || !b) return NaN;
  const dx = b[0] - a[0], dy = b[1] - a[1];
  const len2 = dx * dx + dy * dy;
  return len2 > 0 ? ((n[0] - a[0]) * dx + (n[1] - a[1]) * dy) / len2 : NaN;
}

// A face is upright when its chin lies below its forehead in the photo
// (within 60 deg of the image's vertical) and the subject's right outline
// lies on the image's left of the line forehead -> chin, as in a
// photo of a person (a mirror image swaps the sides: see VIEWS).
function upright(points) {
  const t = points[FOREHEAD], c = points[CHIN];
  if (!t || !c) return false;
  const vx = c[0] - t[0], vy = c[1] - t[1];
  return vy > 0 && vy >= 0.5 * Math.hypot(vx, vy);
}

// The views a head from photos wants, in the order the guide asks for them.
// "left"/"right" are the subject's: the left three-quarter view shows the
// head's left cheek and ear (the person turns to their right). A selfie
// camera that saves mirror images swaps the two; both are wanted anyway.
export const VIEWS = [
  { id: 'front', label: 'front', ask: 'look straight at the camera' },
  { id: 'left', label: 'left three-quarter', ask: 'turn your head about 30-45° to your right, so your left ear shows' },
  { id: 'right', label: 'right three-quarter', ask: 'turn your head about 30-45° to your left, so your right ear shows' },
];

// Beyond this distance from 0.5 the head counts as turned (Kira's photo
// turned about 17 deg: 0.26; frontal ones: 0.01).
const TURNED = 0.15;

// The view of a photo from its face points: 'front', 'left', 'right', or
// null when there are no usable points (no face, or a face upside down or
// on its side: the detector's points on a full profile can come out so).
export function viewOf(points) {
  if (!points || !upright(points)) return null;
  const r = noseOffset(points);
  if (!Number.isFinite(r)) return null;
  if (Math.abs(r - 0.5) <= TURNED) return 'front';
  return r < 0.5 ? 'left' : 'right';
}

// The guide's state for a list of photos' points (null entries: no face):
// {counts: {front, left, right}, missing: [view...], next: view or null,
//  enough: true once every view has a photo and there are at least `least`
//  photos with face points}.
export function viewGuide(pointLists, least = 5) {
  const counts = Object.fromEntries(VIEWS.map((v) => [v.id, 0]));
  let withFace = 0;
  for (const points of pointLists) {
    const v = viewOf(points);
    if (v) { counts[v]++; withFace++; }
  }
  const missing = VIEWS.filter((v) => counts[v.id] === 0);
  return { counts, withFace, missing, next: missing[0] || null, enough: !missing.length && withFace >= least };
}
