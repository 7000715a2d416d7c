#!/usr/bin/env bash
# Tests of the web app in WEBDIR (build/web): first the worker's wasm core
# under Node (worker_node.mjs; worker_threads_node.mjs: the pthreads build
# gives the single-threaded build's fit bit for bit), then the page itself,
# served on 127.0.0.1 with and without the cross-origin isolation headers and
# driven in Debian's Chromium by playwright-core: test.mjs runs the flows of
# flows/ one after the other in one browser and fails if any check fails.
# Usage: tests/browser/run.sh WEBDIR     (env LK_SCREENSHOT_DIR=dir keeps screenshots)
# Exit: 0 pass, 1 fail, 77 skipped (no /usr/bin/chromium, or WEBDIR not built).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
WEBDIR="${1:-}"
if [ -z "$WEBDIR" ]; then
  echo "usage: tests/browser/run.sh WEBDIR" >&2
  exit 2
fi
for f in likeness_viewer.js likeness_viewer.wasm likeness_worker.js likeness_worker.wasm \
         likeness_worker_mt.js likeness_worker_mt.wasm likeness_worker_mt.worker.js; do
  if [ ! -f "$WEBDIR/$f" ]; then
    echo "SKIPPED: $WEBDIR/$f is missing: the wasm build has not run (scripts/build)"
    exit 77
  fi
done
# The face-landmark detector the page serves (vendor/, from npm): the wasm
# build copies it only if scripts/setup installed it before cmake configured.
if [ ! -f "$WEBDIR/vendor/face_mesh/face_mesh.js" ]; then
  echo "FAILED: $WEBDIR/vendor/face_mesh/ is missing: run scripts/setup (npm install in vendor/), then" \
       "touch wasm/CMakeLists.txt && scripts/build --wasm-only" >&2
  exit 1
fi
# The page's own files: every file under web/ (its modules in web/js/ too),
# copied there by the wasm build; a missing or stale copy would test old code.
SRC_WEB="$(cd "$HERE/../../web" && pwd)"
stale=()
while IFS= read -r -d '' f; do
  rel="${f#"$SRC_WEB"/}"
  cmp -s "$f" "$WEBDIR/$rel" || stale+=("$rel")
done < <(find "$SRC_WEB" -type f -print0)
if [ "${#stale[@]}" -gt 0 ]; then
  echo "FAILED: $WEBDIR lacks web/'s ${stale[*]} (missing or older): run scripts/build --wasm-only" >&2
  exit 1
fi
# 1. The worker's wasm core under Node (no browser needed).
node --no-experimental-fetch "$HERE/worker_node.mjs" "$WEBDIR"
node --no-experimental-fetch "$HERE/worker_threads_node.mjs" "$WEBDIR"
# 2. The page in Chromium.
if [ ! -x /usr/bin/chromium ]; then
  echo "SKIPPED: the browser part: /usr/bin/chromium is missing (apt-get install chromium, or run scripts/setup)"
  exit 77
fi
if [ ! -d "$HERE/node_modules/playwright-core" ]; then
  echo "FAILED: $HERE/node_modules/playwright-core is missing: run scripts/setup" >&2
  exit 1
fi
exec node "$HERE/test.mjs" "$WEBDIR"
