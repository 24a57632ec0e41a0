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
reaches the client. A session error (a frame that cannot be read, a box outside the frame, a frame
of another size than the first) is sent to the client as the session's end reason and raised as
:class:`SessionError` (one line, no traceback); a client that is not there or does not speak TraX
is :class:`ClientError`.
"""

from __future__ import annotations

import os
import sys

from ..registry import DEFAULT_MODEL, DEFAULT_PARTICLES

__all__ = ["serve", "main", "SessionError", "ClientError"]


class SessionError(RuntimeError):
    """The session failed on the client's input (a frame, a region); the client was told why."""


class ClientError(RuntimeError):
    """No TraX client on standard input and output, or one that broke off or sent what is not TraX."""


def _box(region):
    """``(x, y, w, h)`` of a TraX rectangle, or the bounding box of a polygon."""
    from trax.region import Region

    if region.type == Region.POLYGON:
        pts = [region.get(i) for i in range(region.size())]
        xs, ys = [p[0] for p in pts], [p[1] for p in pts]
        return min(xs), min(ys), max(xs) - min(xs), max(ys) - min(ys)
    return tuple(region.bounds())


def serve(model=DEFAULT_MODEL, algo=None, particles=DEFAULT_PARTICLES, seed=0, **model_options):
    """Answer one TraX session on standard input and output (or the socket in ``TRAX_SOCKET``) until
    the client quits. Raises ``ImportError`` without ``vot-trax``, ``ValueError`` for bad options
    (before the hello), :class:`SessionError` and :class:`ClientError` (module docstring)."""
    from trax import TraxException, TraxStatus
    from trax.image import Image
    from trax.region import Region
    from trax.server import Server

    from .tracker import Tracker

    # the options checked before the hello; each initialisation starts it again from the seed
    tracker = Tracker(model=model, algo=algo, particles=particles, seed=seed, **model_options)
    try:
        server = Server([Region.RECTANGLE, Region.POLYGON], [Image.PATH], tracker_name="vistrack",
                        tracker_description=f"{model} model, {tracker.algo} filter, N={particles}",
                        tracker_family="vistrack")
    except TraxException as e:
        raise ClientError(f"cannot start a TraX session on standard output ({e})") from None
    while True:
        try:
            req = server.wait()
        except TraxException:
            raise ClientError("no TraX client: standard input closed or sent what is not TraX (vistrack trax is "
                              "started by a TraX client such as the VOT toolkit)") from None
        if req.type == TraxStatus.QUIT:
            break
        try:
            box = _answer(tracker, req, req.type == TraxStatus.INITIALIZE)
        except (OSError, ValueError, RuntimeError) as e:
            _quit(server, str(e))
            raise SessionError(str(e)) from None
        _status(server, box)
    _quit(server)


def _answer(tracker, req, initialize):
    """The box of the request's frame: the tracker started on it (``initialize``) or updated."""
    import cv2

    path = req.image["color"].path()
    frame = cv2.imread(path, cv2.IMREAD_COLOR) if os.path.isfile(path) else None
    if frame is None:
        raise OSError(f"cannot read the frame {path}" + ("" if os.path.isfile(path) else ": no such file"))
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
