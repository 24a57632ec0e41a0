"""vistrack as a tracker of the VOT toolkit: a TraX server (``vistrack trax``, ``python -m vistrack.api.trax_server``).

The `TraX protocol <https://github.com/votchallenge/trax>`_ is how ``vot-toolkit`` talks to a
tracker: it starts the tracker's command, sends the first frame (an image file's path) with the
object's region, then one frame at a time, and reads back a region per frame. This server answers
with :class:`vistrack.Tracker` (the same code, options and seed give the same boxes as
``vistrack run FRAMES --init x,y,w,h``). It needs the optional ``vot-trax`` package
(``pip install "vistrack[trax]"``). The toolkit's ``trackers.ini`` stanza::

    [vistrack]
    label = vistrack
    protocol = trax
    command = vistrack trax --seed 0

A polygon region (VOT's rotated boxes) starts the tracker from its axis-aligned bounding box.

The options are checked before the hello (:class:`vistrack.Tracker`'s checks): a bad one never
reaches the client. A session error (a frame that cannot be read, a region that is not a finite box,
a box outside the frame, a frame of another size than the first) is sent to the client as the
session's end reason and raised as :class:`SessionError` (one line, no traceback); a client that is
not there, goes away (its end of the pipe or socket closed, a message cut short) or does not speak
TraX is :class:`ClientError`, within a second. The client's messages reach libtrax through
:class:`_Relay` (standard input, or the socket of ``TRAX_SOCKET``, which is checked once): it sees the
client go, and it passes paths that are not ASCII (which libtrax reads as the end of the stream), so
the session never waits on a client that is gone and a signal always ends it.
"""

from __future__ import annotations

import math
import os
import re
import sys
import threading

from ..registry import DEFAULT_MODEL, DEFAULT_PARTICLES

__all__ = ["serve", "main", "SessionError", "ClientError"]

#: seconds a client may stay gone, with libtrax still waiting on it, before the session ends
GONE_AFTER = 0.3
#: marks a byte above 127 of a client's message (``\x01`` and two hex digits) on its way to libtrax
_ESCAPE = b"\x01"


class SessionError(RuntimeError):
    """The session failed on the client's input (a frame, a region); the client was told why."""


class ClientError(RuntimeError):
    """No TraX client on standard input and output, or one that broke off or sent what is not TraX."""


def _socket_port():
    """The port in ``TRAX_SOCKET`` (``None`` when unset): a one-line :class:`ClientError` for one that is
    not a port number."""
    value = os.environ.get("TRAX_SOCKET")
    if value is None:
        return None
    if not value.strip().isdigit() or not 0 < int(value) < 65536:
        raise ClientError(f"TRAX_SOCKET={value!r} is not a port number (1-65535): the TraX client sets it to the "
                          "port it listens on; unset it to talk over standard input and output")
    return int(value)


def _connect(port):
    """A socket connected to the TraX client listening on 127.0.0.1:``port`` (tried once; a one-line
    :class:`ClientError` where nothing answers)."""
    import socket

    try:
        sock = socket.create_connection(("127.0.0.1", port), timeout=10)
    except OSError as e:
        raise ClientError(f"TRAX_SOCKET={port}: no TraX client answers on 127.0.0.1:{port} ({e.strerror or e}); "
                          "unset TRAX_SOCKET to talk over standard input and output") from None
    sock.settimeout(None)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


class _Relay:
    """The client's messages passed on to libtrax through a pipe (libtrax reads ``TRAX_IN``): from
    standard input, or from the client's socket (``TRAX_SOCKET``; libtrax's replies go back through a
    second pipe). Marks when the client is gone (:attr:`gone`: end of file, and whether a message was
    cut short, :attr:`cut`), and escapes the bytes of non-ASCII paths that libtrax cannot read
    (:data:`_ESCAPE`; :func:`_unescape` restores them)."""

    def __init__(self, port):
        self.sock = _connect(port) if port is not None else None
        self.gone, self.cut, self.last = threading.Event(), False, b""
        self.trax_in, self._to_trax = os.pipe()
        self.trax_out = sys.stdout.fileno()
        if self.sock is not None:
            back, self.trax_out = os.pipe()  # libtrax writes trax_out; the relay reads back
            threading.Thread(target=self._send_back, args=(back,), daemon=True, name="vistrack-trax-out").start()
        threading.Thread(target=self._pump, daemon=True, name="vistrack-trax-in").start()

    def env(self):
        """libtrax's environment: read from the relay's pipe, write to stdout or the reply pipe."""
        return {"TRAX_IN": str(self.trax_in), "TRAX_OUT": str(self.trax_out)}

    def _read(self):
        if self.sock is not None:
            return self.sock.recv(1 << 16)
        return os.read(sys.stdin.fileno(), 1 << 16)

    def _pump(self):
        pending = b""
        try:
            while True:
                chunk = self._read()
                if not chunk:
                    break
                lines, newline, pending = (pending + chunk).rpartition(b"\n")
                if newline:  # whole lines on; the rest waits for its end
                    self.last = lines.rpartition(b"\n")[2]
                    os.write(self._to_trax, re.sub(rb"[\x80-\xff]", lambda m: _ESCAPE + b"%02x" % m[0][0],
                                                   lines + newline))
        except OSError:
            pass
        self.cut = bool(pending.strip())
        self.gone.set()
        os.close(self._to_trax)

    def _send_back(self, fd):
        while True:
            data = os.read(fd, 1 << 16)
            if not data:
                return
            try:
                self.sock.sendall(data)
            except OSError:
                return


def _unescape(path):
    """A path as the client sent it (:class:`_Relay`'s escapes undone)."""
    raw = re.sub(rb"\x01([0-9a-f]{2})", lambda m: bytes([int(m[1], 16)]), path.encode("utf-8", "surrogateescape"))
    return os.fsdecode(raw)


def _wait(server, relay):
    """The client's next request (``server.wait()``, run aside so that this thread stays free for
    signals): a :class:`ClientError` once the client is gone and libtrax still waits (it may wait
    forever on a message cut short), or for what libtrax cannot read."""
    from trax import TraxException

    out = {}

    def wait():
        try:
            out["req"] = server.wait()
        except TraxException as e:
            out["error"] = str(e)

    waiter = threading.Thread(target=wait, daemon=True, name="vistrack-trax-wait")
    waiter.start()
    while waiter.is_alive():
        waiter.join(0.05)
        if relay.gone.is_set() and waiter.is_alive():
            waiter.join(GONE_AFTER)
            if waiter.is_alive():
                raise ClientError("the TraX client went away in the middle of a message (its end closed"
                                  + (" after part of a line)" if relay.cut else ")"))
    if "error" in out:
        raise ClientError(_client_error(relay.last.decode("utf-8", "replace")))
    return out["req"]


def _client_error(line):
    """One line for a request libtrax could not read, the client's last ``line`` before it."""
    scheme = re.match(r'@@TRAX:(?:initialize|frame)\s+"?([a-z][a-z0-9+.-]*)://', line)
    if scheme and scheme[1] != "file":
        return (f"the TraX client sent a frame as a {scheme[1]}:// address ({line[:80]!r}): vistrack trax reads "
                "frames from image files (trax.image=path); give the client local image files")
    return ("no TraX client: standard input closed or sent what is not TraX (vistrack trax is started by a TraX "
            "client such as the VOT toolkit)")


def _box(region):
    """``(x, y, w, h)`` of a TraX rectangle, or the bounding box of a polygon; a one-line ``ValueError``
    for a region that is neither (libtrax reads text it cannot parse, such as ``abc``, as a special
    region) or is not finite with a positive size."""
    from trax.region import Region

    if region.type == Region.POLYGON:
        pts = [region.get(i) for i in range(region.size())]
        xs, ys = [p[0] for p in pts], [p[1] for p in pts]
        box = min(xs), min(ys), max(xs) - min(xs), max(ys) - min(ys)
    elif region.type == Region.RECTANGLE:
        box = tuple(region.bounds())
    else:
        raise ValueError("the client's start region is not a rectangle x,y,w,h or a polygon (libtrax read it as a "
                         f"{region.type} region: text that is not numbers, or numbers it cannot hold)")
    if not (all(math.isfinite(v) for v in box) and box[2] > 0 and box[3] > 0):
        raise ValueError("the client's start region " + ",".join(f"{v:g}" for v in box) + " is not a box of "
                         "finite numbers and positive size")
    return box


def serve(model=DEFAULT_MODEL, algo=None, particles=DEFAULT_PARTICLES, seed=0, **model_options):
    """Answer one TraX session on standard input and output (or the socket in ``TRAX_SOCKET``) until
    the client quits. Raises ``ImportError`` without ``vot-trax``, ``ValueError`` for bad options
    (before the hello), :class:`SessionError` and :class:`ClientError` (module docstring)."""
    from trax import TraxStatus

    from .tracker import Tracker

    # the options checked before the hello; each initialisation starts it again from the seed
    tracker = Tracker(model=model, algo=algo, particles=particles, seed=seed, **model_options)
    server, relay = _start(tracker, model, particles)
    while True:
        req = _wait(server, relay)
        if req.type == TraxStatus.QUIT:
            break
        try:
            box = _answer(tracker, req, req.type == TraxStatus.INITIALIZE)
        except (OSError, ValueError, RuntimeError) as e:
            _quit(server, str(e))
            raise SessionError(str(e)) from None
        _status(server, box)
    _quit(server)


def _start(tracker, model, particles):
    """``(server, relay)``: libtrax's server (it says hello) reading the client through a :class:`_Relay`."""
    from trax import TraxException
    from trax.image import Image
    from trax.region import Region
    from trax.server import Server

    relay = _Relay(_socket_port())
    saved = {k: os.environ.pop(k, None) for k in ("TRAX_SOCKET", "TRAX_IN", "TRAX_OUT")}
    os.environ.update(relay.env())
    try:
        server = Server([Region.RECTANGLE, Region.POLYGON], [Image.PATH], tracker_name="vistrack",
                        tracker_description=f"{model} model, {tracker.algo} filter, N={particles}",
                        tracker_family="vistrack")
    except TraxException as e:
        raise ClientError(f"cannot start a TraX session on standard output ({e})") from None
    finally:
        for k, v in saved.items():
            os.environ.pop(k, None)
            if v is not None:
                os.environ[k] = v
    return server, relay


def _answer(tracker, req, initialize):
    """The box of the request's frame: the tracker started on it (``initialize``) or updated."""
    import cv2

    path = _unescape(req.image["color"].path())
    frame = cv2.imread(path, cv2.IMREAD_COLOR) if os.path.isfile(path) else None
    if frame is None:
        why = ": a folder, not an image file" if os.path.isdir(path) else \
            ": no such file" if not os.path.exists(path) else " (not an image OpenCV reads)"
        raise OSError(f"cannot read the frame {path}{why}")
    if initialize:
        tracker.init(frame, _box(req.objects[0][0]))
    else:
        tracker.update(frame)
    return tracker.box_estimate


def _status(server, box):
    from trax import TraxException
    from trax.region import Rectangle

    try:
        server.status([(Rectangle.create(*(float(v) for v in box)), {})])
    except TraxException:
        raise ClientError("the TraX client went away during the session") from None


def _quit(server, reason=None):
    """End the session, telling the client ``reason``; a client already gone is no error here."""
    from trax import TraxException

    try:
        server.quit(reason=reason)
    except TraxException:
        pass


def main(argv=None):
    """``python -m vistrack.api.trax_server [--model M] [--algo A] [-n N] [--seed S]``."""
    import argparse

    ap = argparse.ArgumentParser(prog="python -m vistrack.api.trax_server", description=__doc__.splitlines()[0])
    ap.add_argument("--model", default=DEFAULT_MODEL)
    ap.add_argument("--algo", default=None)
    ap.add_argument("-n", "--particles", type=int, default=DEFAULT_PARTICLES)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    try:
        serve(args.model, args.algo, args.particles, args.seed)
    except ImportError as e:
        sys.exit(f"vistrack trax needs the vot-trax package ({e}): pip install 'vistrack[trax]'")
    except (ValueError, SessionError, ClientError) as e:
        sys.exit(f"Error: {e}")


if __name__ == "__main__":
    main()
