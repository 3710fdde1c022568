#!/usr/bin/env python3
"""Serves the demo page (build-web/site) on 127.0.0.1, cross-origin isolated.

Usage: python3 scripts/serve_web.py [SITE_DIR] [PORT]   (defaults build-web/site and 8000)

Every answer carries Cross-Origin-Opener-Policy: same-origin and Cross-Origin-Embedder-Policy:
require-corp, which give the page shared memory and so the threaded module (atmo_mt.wasm, its
tables built on all cores; docs/web.md). Any static server works for the page; one without these
headers gets the single-threaded module.
"""
import functools
import http.server
import os
import sys


class IsolatedHandler(http.server.SimpleHTTPRequestHandler):
    extensions_map = {**http.server.SimpleHTTPRequestHandler.extensions_map,
                      ".wasm": "application/wasm", ".mjs": "text/javascript", ".js": "text/javascript"}

    def end_headers(self):
        self.send_header("Cross-Origin-Opener-Policy", "same-origin")
        self.send_header("Cross-Origin-Embedder-Policy", "require-corp")
        self.send_header("Cache-Control", "no-store")
        super().end_headers()


def main():
    if len(sys.argv) > 1 and sys.argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0
    site = sys.argv[1] if len(sys.argv) > 1 else "build-web/site"
    if not os.path.isfile(os.path.join(site, "index.html")):
        print(f"serve_web: no page in '{site}' (build it with scripts/build_web.sh)", file=sys.stderr)
        return 2
    try:
        port = int(sys.argv[2]) if len(sys.argv) > 2 else 8000
        if not 0 <= port <= 65535:
            raise ValueError
    except ValueError:
        print(f"serve_web: port '{sys.argv[2]}' is not a number in [0, 65535]", file=sys.stderr)
        return 2
    handler = functools.partial(IsolatedHandler, directory=site)
    try:
        server = http.server.ThreadingHTTPServer(("127.0.0.1", port), handler)
    except OSError as error:
        print(f"serve_web: cannot listen on 127.0.0.1:{port}: {error.strerror}", file=sys.stderr)
        return 1
    with server:
        print(f"serving {site} at http://127.0.0.1:{port}/ (cross-origin isolated)", flush=True)
        try:
            server.serve_forever()
        except KeyboardInterrupt:
            pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
