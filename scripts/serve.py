#!/usr/bin/env python3
"""Serves the web app (a folder, build/web by default) on 127.0.0.1.

Like `python3 -m http.server --bind 127.0.0.1`, plus what the page needs:
  - Cross-Origin-Opener-Policy: same-origin and
    Cross-Origin-Embedder-Policy: require-corp on every response, so the page
    is cross-origin isolated and gets SharedArrayBuffer: its worker then runs
    the threaded core (likeness_worker_mt, web/worker.js). --no-isolation
    leaves them out (the page then runs the single-threaded core, as on a host
    that does not send them).
  - the right MIME types, application/wasm above all (streaming compilation
    refuses anything else), whatever the machine's mime.types says.
  - no caching, so a rebuilt module is never mixed with a stale one.

Usage: scripts/serve.py [DIR] [--port N] [--no-isolation]
Standard library only.
"""
import argparse
import http.server
import os
import sys

MIME_TYPES = {
    '.html': 'text/html; charset=utf-8',
    '.js': 'text/javascript; charset=utf-8',
    '.mjs': 'text/javascript; charset=utf-8',
    '.css': 'text/css; charset=utf-8',
    '.json': 'application/json',
    '.wasm': 'application/wasm',
    '.png': 'image/png',
    '.jpg': 'image/jpeg',
    '.jpeg': 'image/jpeg',
    '.txt': 'text/plain; charset=utf-8',
    '.ply': 'application/octet-stream',
    '.obj': 'text/plain; charset=utf-8',
    '.webmanifest': 'application/manifest+json',
}


def make_handler(root, isolation):
    class Handler(http.server.SimpleHTTPRequestHandler):
        extensions_map = dict(http.server.SimpleHTTPRequestHandler.extensions_map, **MIME_TYPES)

        def __init__(self, *args, **kwargs):
            super().__init__(*args, directory=root, **kwargs)

        def end_headers(self):
            if isolation:
                self.send_header('Cross-Origin-Opener-Policy', 'same-origin')
                self.send_header('Cross-Origin-Embedder-Policy', 'require-corp')
            self.send_header('Cache-Control', 'no-store')
            super().end_headers()

    return Handler


def main():
    parser = argparse.ArgumentParser(description='Serve the Likeness web app on 127.0.0.1.')
    parser.add_argument('dir', nargs='?', default=os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'build', 'web'),
                        help='folder to serve (default: build/web)')
    parser.add_argument('--port', type=int, default=8080, help='port (default 8080; 0 = any free port)')
    parser.add_argument('--no-isolation', action='store_true',
                        help='do not send COOP/COEP (the page then runs the single-threaded core)')
    args = parser.parse_args()
    root = os.path.abspath(args.dir)
    if not os.path.isfile(os.path.join(root, 'index.html')):
        sys.exit(f'serve.py: {root}/index.html not found: build the web app first (scripts/build)')
    if not 0 <= args.port <= 65535:
        sys.exit(f'serve.py: --port must be 0..65535, got {args.port}')
    try:
        server = http.server.ThreadingHTTPServer(('127.0.0.1', args.port), make_handler(root, not args.no_isolation))
    except OSError as e:
        sys.exit(f'serve.py: cannot listen on 127.0.0.1:{args.port}: {e.strerror}')
    host, port = server.server_address[:2]
    mode = 'cross-origin isolated (threaded core)' if not args.no_isolation else 'not isolated (single-threaded core)'
    print(f'Serving {root} on http://{host}:{port}/ ({mode})', flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()


if __name__ == '__main__':
    main()
