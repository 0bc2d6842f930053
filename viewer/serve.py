#!/usr/bin/env python3
"""Serves vismask's viewer page and one run's outputs on localhost.

`vismask view OUT_DIR` checks its arguments, finds the viewer directory (this
file's) and execs this script:

    python3 serve.py --viewer DIR --out OUT_DIR --glb NAME.glb [--run] [--port P]

The page is served at / and OUT_DIR's files under /out/ (nothing else); the
first line on standard output is the URL to open. Ctrl-C stops it.
"""
import argparse
import http.server
import os
import posixpath
import sys
import urllib.parse


def MakeHandler(viewer, out):
    class Handler(http.server.SimpleHTTPRequestHandler):
        extensions_map = {
            '': 'application/octet-stream',
            '.html': 'text/html; charset=utf-8',
            '.js': 'text/javascript; charset=utf-8',
            '.json': 'application/json',
            '.glb': 'model/gltf-binary',
            '.png': 'image/png',
            '.csv': 'text/csv',
        }

        def translate_path(self, path):
            # /out/NAME -> OUT_DIR/NAME, anything else -> the viewer directory;
            # '..' cannot climb out of either.
            path = urllib.parse.unquote(path.split('?', 1)[0].split('#', 1)[0])
            parts = [p for p in posixpath.normpath(path).split('/') if p not in ('', '.', '..')]
            root = viewer
            if parts and parts[0] == 'out':
                root, parts = out, parts[1:]
            return os.path.join(root, *parts)

        def end_headers(self):
            self.send_header('Cache-Control', 'no-store')
            super().end_headers()

        def log_message(self, fmt, *args):
            pass  # quiet: errors are logged by log_error

        def log_error(self, fmt, *args):
            sys.stderr.write('vismask view: %s\n' % (fmt % args))

    return Handler


def Main():
    ap = argparse.ArgumentParser(description='serve the vismask viewer and a run on localhost')
    ap.add_argument('--viewer', required=True, help='the viewer directory (index.html)')
    ap.add_argument('--out', required=True, help="the run's output directory")
    ap.add_argument('--glb', required=True, help='the mesh, a file name in --out')
    ap.add_argument('--run', action='store_true', help='--out has a run.json to take the camera from')
    ap.add_argument('--port', type=int, default=0, help='0: any free port')
    a = ap.parse_args()
    handler = MakeHandler(os.path.abspath(a.viewer), os.path.abspath(a.out))
    try:
        server = http.server.ThreadingHTTPServer(('127.0.0.1', a.port), handler)
    except OSError as e:
        sys.stderr.write('vismask view: cannot listen on 127.0.0.1 port %d: %s\n' % (a.port, e.strerror))
        return 1
    query = 'glb=' + urllib.parse.quote('out/' + a.glb)
    if a.run:
        query += '&run=' + urllib.parse.quote('out/run.json')
    url = 'http://127.0.0.1:%d/?%s' % (server.server_address[1], query)
    sys.stdout.write(url + '\n')
    sys.stdout.flush()
    sys.stderr.write('vismask view: serving %s and %s (Ctrl-C stops)\n' % (a.viewer, a.out))
    sys.stderr.flush()
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
    return 0


if __name__ == '__main__':
    sys.exit(Main())
