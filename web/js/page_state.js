// The page's states and their one owner: every job, error, Dismiss and
// Cancel goes through a PageState, so no path can leave the page "working"
// with nothing running. Plain JavaScript without the DOM (state.js applies
// it to the page), so tests/browser/page_state_node.mjs checks it in Node.
//
// States (document.body.dataset.state shows the current one):
//   loading  the modules start; nothing can be used yet
//   ready    nothing is shown but the generic head
//   working  one job runs (job.name: scan, fit, photos head, texture, photos, points,
//            eye photo, smile photo, project, sample); Cancel ends it
//   done     a scan or head is shown: the resting state once one is
//   error    the last action failed; the message is in the banner and what
//            was shown before is still shown. Dismiss goes back to rest.
// "Rest" is ready or done, read from what is shown (rest()), never from a
// remembered state: remembering "working" under an error is what stranded
// the page (issue 39). A failed start-up is an error that Dismiss keeps.
//
// Transitions:
//   loading --started()--> rest          loading --startFailed(m)--> error (fatal)
//   rest|error --begin(name)--> working  (refused, null, while loading, working or fatal)
//   working --job.end()--> rest          working --cancel()--> rest (the job is dead)
//   working|rest|error --fail(m)--> error
//   error --dismiss()--> rest (fatal: stays error, the banner hides)
export class PageState {
  // rest(): 'ready' or 'done' from what the page shows; onChange(snapshot)
  // after every transition; onCancel(job) when Cancel ends a job.
  constructor({ rest = () => 'ready', onChange = () => {}, onCancel = () => {} } = {}) {
    this.rest = rest;
    this.onChange = onChange;
    this.onCancel = onCancel;
    this.state = 'loading';
    this.job = null;       // the running job: {name, live, cancelled}
    this.message = null;   // the error shown (state error)
    this.fatal = false;    // start-up failed: nothing works
    this.bannerShown = false;
  }

  snapshot() {
    return { state: this.state, job: this.job ? this.job.name : null, message: this.message, fatal: this.fatal,
             banner: this.bannerShown };
  }

  go(state) {
    this.state = state;
    this.onChange(this.snapshot());
  }

  restState() {
    const r = this.rest();
    return r === 'done' ? 'done' : 'ready';
  }

  started() {
    if (this.state !== 'loading' || this.fatal) return;
    this.go(this.restState());
  }

  startFailed(message) {
    this.fatal = true;
    this.endJob();
    this.message = String(message);
    this.bannerShown = true;
    this.go('error');
  }

  // A job starts: the running job, or null when none may start now. Starting
  // from "error" hides the banner (the user went on).
  begin(name) {
    if (this.fatal || this.state === 'loading' || this.state === 'working') return null;
    const job = { name: String(name), live: true, cancelled: false };
    this.job = job;
    this.message = null;
    this.bannerShown = false;
    this.go('working');
    return job;
  }

  // Whether job is the one running (a cancelled or replaced one is not).
  isLive(job) { return !!job && job === this.job && job.live; }

  endJob() {
    if (this.job) this.job.live = false;
    this.job = null;
  }

  // The job finished (succeeded, or stopped on its own): back to rest. A
  // job no longer running (cancelled, failed) changes nothing.
  end(job) {
    if (!this.isLive(job)) return false;
    this.endJob();
    this.go(this.restState());
    return true;
  }

  // Cancel: whatever runs ends now, whether or not the worker answers.
  cancel() {
    if (this.state !== 'working' || !this.job) return false;
    const job = this.job;
    job.cancelled = true;
    this.endJob();
    this.go(this.restState());
    this.onCancel(job);
    return true;
  }

  // An error: the running job (if any) ends with it. Never refused.
  fail(message) {
    this.endJob();
    this.message = String(message);
    this.bannerShown = true;
    this.go('error');
  }

  dismiss() {
    this.bannerShown = false;
    if (this.state !== 'error') { this.onChange(this.snapshot()); return; }
    if (this.fatal) { this.onChange(this.snapshot()); return; }
    this.message = null;
    this.go(this.restState());
  }

  // What is shown changed (a head forgotten, a scan loaded) outside a job:
  // a resting state follows it; working and error keep theirs.
  refresh() {
    if (this.state === 'ready' || this.state === 'done') this.go(this.restState());
    else this.onChange(this.snapshot());
  }
}

// What each control allows in a state, given what the page holds:
// s = {state, fatal, scanFile (a scan to fit: a file, or the points a
// head opened from a project keeps), fit (a fitted head in
// the worker), texture, photos (how many), distance (a distance map),
// scan (a scan is loaded or opened), facePoints (photos with face points)}.
// Returns {control: enabled}; state.js maps the names to elements.
export function controlsFor(s) {
  const usable = s.state !== 'loading' && !s.fatal;
  const idle = usable && s.state !== 'working';
  const head = idle && !!s.fit;
  return {
    files: idle, sample: idle, generic: idle, openProject: idle, photoRoles: idle, restore: idle,
    reset: usable, pointSize: usable, wireframe: usable,
    cancel: usable && s.state === 'working',
    fit: idle && !!s.scanFile,
    // Which way the scan is turned: set before a scan comes, or to fit it again.
    scanAxes: idle,
    // A head from the photos' face points: the main flow when no scan is loaded.
    photosHead: idle && !s.scan && (s.facePoints || 0) > 0,
    exportObj: head, exportPly: head, exportGlb: head, animate: head, expressions: head, fullDetail: head, level: head, showPoints: head,
    showComponents: head, saveProject: head,
    texture: head && s.photos > 0,
    exportTextured: head && !!s.texture,
    exportMap: head && !!s.distance,
  };
}
