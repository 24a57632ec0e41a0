"""A patch of a frame about a point at a scale, shrunk by halving first: the filters' samples.

:func:`patch` gives the frame resampled so that output pixel ``(i, j)`` lies at frame point
``centre + ((j, i) - anchor) / s``. Where ``s < 1/2`` the region it covers is first halved with
``cv2.pyrDown`` (a 5-tap Gaussian then every other pixel: no aliasing, a few nanoseconds a pixel) as
often as it takes to bring ``s`` into ``[1/2, 1]``, then read bilinearly (``cv2.warpAffine``), the
frame's edge pixels repeated beyond it. ``INTER_AREA`` resizes of a large region cost a hundred times
more and ``warpAffine`` alone aliases when it shrinks more than twice.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["patch"]


def patch(frame, centre, s, size, anchor):
    """``frame`` (BGR or grey) about ``centre`` (frame px) at ``s`` output px per frame px (a number, or one
    for x and one for y), ``size`` ``(W, H)`` output px, output pixel ``(i, j)`` at
    ``centre + ((j, i) - anchor) / s`` (pixel centres at integers)."""
    W, H = size
    cx, cy = float(centre[0]), float(centre[1])
    ax, ay = float(anchor[0]), float(anchor[1])
    sx, sy = (float(s), float(s)) if np.ndim(s) == 0 else (float(s[0]), float(s[1]))
    src = frame
    if max(sx, sy) < 0.5:
        fh, fw = frame.shape[:2]
        # the frame region the output covers, with a margin for the pyramid's taps
        x0, x1 = cx - ax / sx - 4, cx + (W - ax) / sx + 4
        y0, y1 = cy - ay / sy - 4, cy + (H - ay) / sy + 4
        ix0, iy0 = max(int(np.floor(x0)), 0), max(int(np.floor(y0)), 0)
        ix1, iy1 = min(int(np.ceil(x1)), fw), min(int(np.ceil(y1)), fh)
        if ix1 - ix0 >= 2 and iy1 - iy0 >= 2:
            src = frame[iy0:iy1, ix0:ix1]
            cx, cy = cx - ix0, cy - iy0
            while max(sx, sy) < 0.5 and min(src.shape[:2]) >= 4:
                src = cv2.pyrDown(src)
                cx, cy = cx / 2, cy / 2  # pyrDown centres output pixel i on source pixel 2i
                sx, sy = 2 * sx, 2 * sy
    m = np.array([[1 / sx, 0, cx - ax / sx], [0, 1 / sy, cy - ay / sy]], np.float64)
    return cv2.warpAffine(src, m, (W, H), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_REPLICATE)
