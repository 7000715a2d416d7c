// Browser test of the Likeness web app (run through run.sh): the page served
// on 127.0.0.1 (with the cross-origin isolation headers, as scripts/serve.py;
// some flows also without, or with files broken) and driven in Debian's
// Chromium (WebGL2 on SwiftShader) by playwright-core.
//
// The checks are grouped by flow, one file each in flows/, run here in this
// order in one browser: a flow may rely on the main page and on the fitted
// head the flows before it left (fit.mjs's fittedHead() makes it once), so
// the fit is paid once per run. Every run ends with two checks of its own:
// no console errors on the watched pages, and no request off the page's
// origins. Screenshots go to $LK_SCREENSHOT_DIR when set (web_*.png).
//
// Usage: node test.mjs WEBDIR [flow ...]   (only the named flows; each sets
//        up what it needs), or node flows/<file>.mjs WEBDIR for one flow.
// The fit flows need a native `likeness` to make the synthetic scan (env
// LK_LIKENESS_BIN, else WEBDIR/../bin/likeness); without one they are
// skipped with a note.
import { runFlows } from './harness.mjs';
import { flow as startup } from './flows/startup.mjs';
import { flow as scanLoad } from './flows/scan_load.mjs';
import { flow as startupFailures } from './flows/startup_failures.mjs';
import { flow as fit } from './flows/fit.mjs';
import { flow as fitChecks } from './flows/fit_checks.mjs';
import { flow as fitThreads } from './flows/fit_threads.mjs';
import { flow as exportFlow } from './flows/export.mjs';
import { flow as animation } from './flows/animation.mjs';
import { flow as expressions } from './flows/expressions.mjs';
import { flow as followFace } from './flows/follow_face.mjs';
import { flow as texture } from './flows/texture.mjs';
import { flow as eyeSmile } from './flows/eye_smile.mjs';
import { flow as project } from './flows/project.mjs';
import { flow as keep } from './flows/keep.mjs';
import { flow as pageStates } from './flows/page_states.mjs';
import { flow as fitCancel } from './flows/fit_cancel.mjs';
import { flow as scanAxes } from './flows/scan_axes.mjs';
import { flow as photoRefusals } from './flows/photo_refusals.mjs';
import { flow as offline } from './flows/offline.mjs';
import { flow as accessibility } from './flows/accessibility.mjs';
import { flow as largeScan } from './flows/large_scan.mjs';
import { flow as landmarks } from './flows/landmarks.mjs';
import { flow as glb } from './flows/glb.mjs';
import { flow as photosHead } from './flows/photos_head.mjs';
import { flow as phone } from './flows/phone.mjs';
import { flow as realPhotos } from './flows/real_photos.mjs';

runFlows([startup, scanLoad, startupFailures, fit, fitChecks, fitThreads, exportFlow, animation, expressions, followFace, texture, eyeSmile,
          project, keep, pageStates, fitCancel, scanAxes, photoRefusals, landmarks, photosHead, realPhotos, phone, glb, offline, accessibility, largeScan]);
