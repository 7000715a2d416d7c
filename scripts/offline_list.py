#!/usr/bin/env python3
"""Writes WEBDIR/offline.json: the files the page's service worker (web/sw.js)
keeps for offline use, each with its size and SHA-256, and a version (the
hash of the list). Run by scripts/build after the wasm build and by
scripts/demo after it installs the sample, so the list is always what is
served. Left out: the list itself and sw.js (the browser fetches the worker).

Usage: scripts/offline_list.py WEBDIR
"""
import hashlib
import json
import os
import sys

SKIP = {"offline.json", "sw.js"}


def main():
    if len(sys.argv) != 2 or not os.path.isdir(sys.argv[1]):
        sys.exit("usage: scripts/offline_list.py WEBDIR")
    root = sys.argv[1]
    files = []
    for folder, dirs, names in os.walk(root):
        dirs.sort()
        for name in sorted(names):
            path = os.path.join(folder, name)
            rel = os.path.relpath(path, root).replace(os.sep, "/")
            if rel in SKIP or name.startswith("."):
                continue
            h = hashlib.sha256()
            with open(path, "rb") as f:
                for block in iter(lambda: f.read(1 << 20), b""):
                    h.update(block)
            files.append({"path": rel, "size": os.path.getsize(path), "sha256": h.hexdigest()})
    version = hashlib.sha256(json.dumps(files, sort_keys=True).encode()).hexdigest()[:16]
    with open(os.path.join(root, "offline.json"), "w") as f:
        json.dump({"version": version, "files": files}, f, separators=(",", ":"))
    print(f"[offline] {root}/offline.json: {len(files)} files, "
          f"{sum(x['size'] for x in files) / 1048576:.1f} MB, version {version}")


if __name__ == "__main__":
    main()
