#!/usr/bin/env python3
"""Serves vismask's viewer page and one run's outputs on localhost.

`vismask view OUT_DIR` checks its arguments, finds the viewer directory (this
file's) and execs this script:

    python3 serve.py --viewer DIR --out OUT_DIR --glb NAME.glb [--run] [--port P]

The page is served at / and OUT_DIR's files under /out/ (nothing else): only
regular files whose real path (symbolic links resolved) lies inside OUT_DIR
or the viewer directory, no directory listings, only to requests whose Host
is 127.0.0.1, localhost or [::1] with the port (403 otherwise: DNS
rebinding), and 400 for a path that is not one (a NUL byte, bad UTF-8). The
first line on standard output is the URL to open. Ctrl-C stops it.
"""
import argparse
import http.server
import os
import posixpath
import sys
import urllib.parse


def MakeHandler(viewer, out, hosts):
    """The request handler: `viewer` and `out` are real paths (symbolic links
    resolved); `hosts` the Host header values a request may carry."""

    class BadPath(Exception):
        pass

    def inside(path, root):
        return path == root or path.startswith(root + os.sep)

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
            # '..' cannot climb out of either, and neither can a symbolic
            # link: the real path must lie inside the root (else a name that
            # does not exist, so 404).
            path = urllib.parse.unquote(path.split('?', 1)[0].split('#', 1)[0], errors='strict')
            if '\0' in path:
                raise BadPath()
            parts = [p for p in posixpath.normpath(path).split('/') if p not in ('', '.', '..')]
            root = viewer
            if parts and parts[0] == 'out':
                root, parts = out, parts[1:]
            real = os.path.realpath(os.path.join(root, *parts))
            if not inside(real, root):
                return os.path.join(root, '\0outside')  # never exists
            return real

        def send_head(self):
            # Only regular files; a directory only as the page's own folder
            # (index.html); no listings.
            try:
                path = self.translate_path(self.path)
            except (BadPath, UnicodeDecodeError, ValueError):
                self.send_error(400, 'bad path')
                return None
            if '\0' not in path and os.path.isdir(path):
                if path == viewer and os.path.isfile(os.path.join(path, 'index.html')):
                    return super().send_head()
                self.send_error(404, 'no listings')
                return None
            if '\0' in path or not os.path.isfile(path):
                self.send_error(404, 'not found')
                return None
            return super().send_head()

        def list_directory(self, path):
            self.send_error(404, 'no listings')
            return None

        def HostAllowed(self):
            # DNS rebinding: a page of another site that resolves its name to
            # 127.0.0.1 sends its own name as Host.
            if self.headers.get('Host', '') in hosts:
                return True
            self.send_error(403, 'Host must be 127.0.0.1, localhost or [::1] with the port')
            return False

        def do_GET(self):
            if self.HostAllowed():
                super().do_GET()

        def do_HEAD(self):
            if self.HostAllowed():
                super().do_HEAD()

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
    hosts = set()
    handler = MakeHandler(os.path.realpath(a.viewer), os.path.realpath(a.out), hosts)
    try:
        server = http.server.ThreadingHTTPServer(('127.0.0.1', a.port), handler)
    except OSError as e:
        sys.stderr.write('vismask view: cannot listen on 127.0.0.1 port %d: %s\n' % (a.port, e.strerror))
        return 1
    port = server.server_address[1]
    hosts.update({'127.0.0.1:%d' % port, 'localhost:%d' % port, '[::1]:%d' % port})
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
