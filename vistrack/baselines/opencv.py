"""OpenCV's trackers as ``eval`` compares them beside the particle filters: which there are, which of
them vary from run to run, whether this OpenCV build has one, and one run of one over a clip's frames."""

from __future__ import annotations

import time

import numpy as np

__all__ = ["OPENCV_TRACKERS", "OPENCV_RANDOMISED", "check_opencv", "track_opencv"]

#: OpenCV trackers by name -> constructor attribute (contrib ones may be missing)
OPENCV_TRACKERS = {"opencv-mil": "TrackerMIL_create", "opencv-kcf": "TrackerKCF_create",
                   "opencv-csrt": "TrackerCSRT_create"}
#: the OpenCV trackers whose result varies from run to run (randomised inside OpenCV, which no seed
#: reaches: MIL's samples); they run ``runs`` times like the particle filters, the others once
OPENCV_RANDOMISED = {"opencv-mil"}


def check_opencv(name):
    """Raise ``ValueError`` (one line) when this OpenCV build lacks the tracker ``name``."""
    import cv2

    if not hasattr(cv2, OPENCV_TRACKERS[name]) and not hasattr(getattr(cv2, "legacy", None), OPENCV_TRACKERS[name]):
        raise ValueError(f"{name} is not in this OpenCV build ({cv2.__version__}); "
                         "KCF and CSRT need opencv-contrib-python")


def track_opencv(name, box, frames):
    """One run of OpenCV's tracker ``name`` from ``box`` ``(x, y, w, h)`` on the first of ``frames``
    (``(index, frame)`` pairs). Returns ``(boxes (frames, 4), ms (frames,), index (frames,))``: ``x, y, w,
    h`` per frame (NaN where it lost the object), the milliseconds of each call, the frames' indices."""
    import cv2

    ctor = getattr(cv2, OPENCV_TRACKERS[name], None) or getattr(cv2.legacy, OPENCV_TRACKERS[name])
    tracker = ctor()
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
