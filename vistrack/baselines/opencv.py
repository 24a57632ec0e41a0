"""OpenCV's trackers as ``eval`` compares them beside the particle filters: whether this OpenCV build
has one, and one run of one over a clip's frames. Which there are, and which of them vary from run to
run, is the registry's (:data:`vistrack.registry.baseline_specs.BASELINES`)."""

from __future__ import annotations

import time

import numpy as np

__all__ = ["check_opencv", "track_opencv"]


def _constructor(ctor):
    """``cv2.<ctor>`` or ``cv2.legacy.<ctor>`` (contrib trackers may live in either, or be missing); ``None``
    when this build has neither."""
    import cv2

    return getattr(cv2, ctor, None) or getattr(getattr(cv2, "legacy", None), ctor, None)


def check_opencv(name, ctor, needs=""):
    """Raise ``ValueError`` (one line) when this OpenCV build lacks the tracker ``name`` (made by
    ``cv2.<ctor>``); ``needs``: the package that has it."""
    import cv2

    if _constructor(ctor) is None:
        raise ValueError(f"{name} is not in this OpenCV build ({cv2.__version__})"
                         + (f"; it needs {needs}" if needs else ""))


def track_opencv(ctor, box, frames):
    """One run of the OpenCV tracker made by ``cv2.<ctor>`` from ``box`` ``(x, y, w, h)`` on the first of
    ``frames`` (``(index, frame)`` pairs). Returns ``(boxes (frames, 4), ms (frames,), index (frames,))``:
    ``x, y, w, h`` per frame (NaN where it lost the object), the milliseconds of each call, the frames'
    indices."""
    tracker = _constructor(ctor)()
    x, y, w, h = box
    boxes, ms, index = [], [], []
    for k, (i, frame) in enumerate(frames):
        index.append(i)
        t0 = time.perf_counter()
        if k == 0:
            tracker.init(frame, (int(round(x)), int(round(y)), int(round(w)), int(round(h))))
            b = (x, y, w, h)
        else:
            ok, b = tracker.update(frame)
            b = tuple(float(v) for v in b) if ok else (np.nan,) * 4
        ms.append((time.perf_counter() - t0) * 1e3)
        boxes.append(b)
    return np.array(boxes, float), np.array(ms), np.array(index, int)
