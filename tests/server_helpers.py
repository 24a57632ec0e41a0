"""Shared by the tests that read URLs: HTTP handlers for ``http.server`` (:class:`QuietHandler`, a server
without range requests like ``python -m http.server``; :class:`RangeHandler`, one with them) and
:func:`serve_folder`, behind the ``serve`` fixture of ``conftest.py``."""

import io
import os
import re
import threading
from functools import partial
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer


class QuietHandler(SimpleHTTPRequestHandler):
    """``python -m http.server``'s handler (no range requests), without its log lines."""

    def log_message(self, *args):
        pass


class RangeHandler(QuietHandler):
    """The same, answering ``Range: bytes=a-b`` with 206 and the part (the starts asked are kept)."""

    starts = []

    def send_head(self):
        path = self.translate_path(self.path)
        m = re.fullmatch(r"bytes=(\d+)-(\d*)", self.headers.get("Range", ""))
        if os.path.isdir(path) or not os.path.isfile(path) or not m:
            return super().send_head()
        data = open(path, "rb").read()
        start, end = int(m[1]), min(int(m[2]) if m[2] else len(data) - 1, len(data) - 1)
        type(self).starts.append(start)
        self.send_response(206)
        self.send_header("Content-Type", self.guess_type(path))
        self.send_header("Content-Range", f"bytes {start}-{end}/{len(data)}")
        self.send_header("Content-Length", str(end - start + 1))
        self.send_header("Accept-Ranges", "bytes")
        self.send_header("ETag", f'"{len(data)}-{int(os.path.getmtime(path))}"')
        self.end_headers()
        return io.BytesIO(data[start:end + 1])


def serve_folder(folder, handler=None):
    """``(url, server)``: ``folder`` served on 127.0.0.1 by ``handler`` (default :class:`QuietHandler`)
    in a thread; ``server.shutdown()`` ends it."""
    server = ThreadingHTTPServer(("127.0.0.1", 0), partial(handler or QuietHandler, directory=str(folder)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return f"http://127.0.0.1:{server.server_address[1]}", server
