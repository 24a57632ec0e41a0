"""Build a tracking model for a clip from the user's initialisation (``vistrack run``).

Kept out of the CLI so that evaluation code builds models the same way.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .clips import read_groundtruth_csv
from .features import FeatureMaps
from .models.contour import Contour
from .video import VideoError, read_rects

__all__ = ["MODELS", "initial_truth", "build_model"]

MODELS = ("contour",)


def initial_truth(clip, init_gt):
    """The first visible ground-truth row as a dict, from the clip or from ``init_gt``.

    ``init_gt`` is ``""``/``True`` for the clip's own ground truth, or a path to a
    ``groundtruth.csv`` or an OTB ``x,y,w,h`` file.
    """
    if init_gt in ("", True, None):
        truth = clip.truth
        if truth is None:
            raise VideoError(f"--init-gt: {clip.folder} has no groundtruth.csv or groundtruth_rect.txt; "
                             "give a file (--init-gt FILE) or a box (--init x,y,w,h)")
    else:
        p = Path(init_gt)
        if not p.is_file():
            raise VideoError(f"--init-gt: {p} does not exist")
        if p.suffix == ".csv":
            truth = read_groundtruth_csv(p)
        else:
            r = read_rects(p)
            truth = {"visible": ((r[:, 2] > 0) & (r[:, 3] > 0)).astype(float), "cx": r[:, 0] + r[:, 2] / 2,
                     "cy": r[:, 1] + r[:, 3] / 2, "w": r[:, 2], "h": r[:, 3]}
    vis = np.flatnonzero(np.asarray(truth["visible"]) > 0)
    if not len(vis):
        raise VideoError("--init-gt: the object is not visible in any ground-truth row")
    return {k: float(v[vis[0]]) for k, v in truth.items()}


def _first_frame(clip):
    for _, frame in clip.source:
        return frame
    raise VideoError(f"{clip.source.path}: no frame could be decoded")


def build_model(name, clip, *, init=None, init_gt=None, polarity="auto", **params):
    """The model ``name`` for ``clip`` started from ``init`` (x, y, w, h) or the ground truth.

    For ``contour``: with the clip's template (meta.json) and a ground-truth row
    that has ``scale``/``angle_deg``, the template at that pose; otherwise an
    ellipse fitted to the box. ``polarity="auto"`` learns the edge polarity from
    the first frame (:meth:`Contour.learn_polarity`); ``None`` keeps edges unsigned.
    """
    size = clip.source.size
    if name == "contour":
        model = _contour(clip, size, init, init_gt, params)
        if polarity == "auto":
            model.learn_polarity(FeatureMaps(_first_frame(clip)))
        else:
            model.polarity = polarity
        return model
    raise VideoError(f"unknown model {name!r}; choose from {', '.join(MODELS)}")


def _contour(clip, size, init, init_gt, params):
    if init is not None:
        return Contour.from_box(init, size, **params)
    if init_gt is None:
        raise VideoError("the contour model needs a start: --init x,y,w,h or --init-gt")
    row = initial_truth(clip, init_gt)
    tmpl = ((clip.meta or {}).get("template") or {}).get("support_points")
    if tmpl is not None and "scale" in row:
        return Contour.from_template(np.asarray(tmpl, float), size, cx=row["cx"], cy=row["cy"],
                                     scale=row["scale"], angle_deg=row.get("angle_deg", 0.0), **params)
    return Contour.from_box((row["cx"] - row["w"] / 2, row["cy"] - row["h"] / 2, row["w"], row["h"]), size,
                            **params)
