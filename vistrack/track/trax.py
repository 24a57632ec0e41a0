"""vistrack as a tracker of the VOT toolkit: a TraX server (``vistrack trax``, ``python -m vistrack.track.trax``).

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
"""

from __future__ import annotations

import sys

import cv2

from ..registry import DEFAULT_MODEL, DEFAULT_PARTICLES

__all__ = ["serve", "main"]


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
    the client quits. Raises ``ImportError`` without ``vot-trax``."""
    from trax import TraxStatus
    from trax.image import Image
    from trax.region import Rectangle, Region
    from trax.server import Server

    from .tracker import Tracker

    tracker = None
    with Server([Region.RECTANGLE, Region.POLYGON], [Image.PATH], tracker_name="vistrack",
                tracker_description=f"{model} model, {algo or 'default'} filter, N={particles}",
                tracker_family="vistrack") as server:
        while True:
            req = server.wait()
            if req.type == TraxStatus.QUIT:
                break
            frame = cv2.imread(req.image["color"].path(), cv2.IMREAD_COLOR)
            if frame is None:
                raise OSError(f"cannot read the frame {req.image['color'].path()}")
            if req.type == TraxStatus.INITIALIZE:
                tracker = Tracker(model=model, algo=algo, particles=particles, seed=seed, **model_options)
                tracker.init(frame, _box(req.objects[0][0]))
                box = tracker.box_estimate
            else:
                tracker.update(frame)
                box = tracker.box_estimate
            server.status([(Rectangle.create(*(float(v) for v in box)), {})])


def main(argv=None):
    """``python -m vistrack.track.trax [--model M] [--algo A] [-n N] [--seed S]``."""
    import argparse

    ap = argparse.ArgumentParser(prog="python -m vistrack.track.trax", description=__doc__.splitlines()[0])
    ap.add_argument("--model", default=DEFAULT_MODEL)
    ap.add_argument("--algo", default=None)
    ap.add_argument("-n", "--particles", type=int, default=DEFAULT_PARTICLES)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    try:
        serve(args.model, args.algo, args.particles, args.seed)
    except ImportError as e:
        sys.exit(f"vistrack trax needs the vot-trax package ({e}): pip install 'vistrack[trax]'")


if __name__ == "__main__":
    main()
