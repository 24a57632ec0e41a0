"""How ``run`` and ``eval`` build the landmark model: its registry entry."""

from __future__ import annotations

import numpy as np

from ...io.starts import initial_truth
from ...io.video import VideoError
from ...scoring.metrics import landmark_error
from ..spec import ModelOption, ModelSpec
from .video_model import LandmarkVideo

__all__ = ["SPEC"]


def _landmarks_from_clip(clip, *, init, init_gt, template, **params):
    if init is not None:
        raise VideoError("--init is a box; the landmarks model starts from --template FILE or --init-gt")
    return _landmarks(clip, clip.source.size, init_gt, template, params)


def _landmarks(clip, size, init_gt, template, params):
    """Landmark model started from the first frame's landmarks: ``--template FILE`` (x y per
    line), ``--init-gt`` (lx0.., ly0.. columns), or the clip's meta.json; the clip's centre,
    scale and dynamics when meta.json has them."""
    meta = clip.meta or {}
    if template is not None:
        first = np.asarray(template, float)
    elif init_gt is not None:
        row = initial_truth(clip, init_gt)
        k = 0
        while f"lx{k}" in row:
            k += 1
        if k < 3:
            raise VideoError("--init-gt: the ground truth has no landmark columns lx0.., ly0.. (need at least 3)")
        first = np.array([[row[f"lx{i}"], row[f"ly{i}"]] for i in range(k)])
    elif (meta.get("template") or {}).get("landmarks"):
        first = np.asarray(meta["template"]["landmarks"], float)
    else:
        raise VideoError("the landmarks model needs the first frame's landmarks: --template FILE (x y per line) "
                         "or --init-gt")
    kw = dict(params)
    if meta.get("model") == "landmarks":
        kw.setdefault("centre", meta.get("centre"))
        kw.setdefault("scale_px", meta.get("scale_px"))
        kw.setdefault("theta0", meta.get("theta0", 0.0))
        for key, v in (meta.get("dynamics") or {}).items():
            kw.setdefault(key, v)
    return LandmarkVideo(first, size, **{k: v for k, v in kw.items() if v is not None})


def _summary(rows, truth, model):
    """``run``'s line against landmark ground truth (``lx0.., ly0..``): the mean landmark error."""
    if "lx0" not in truth:
        return None
    err = landmark_error(rows, truth, model.k)
    return (f"vs ground truth: mean landmark error {err.mean():.2f} px (per frame: median {np.median(err):.2f}, "
            f"max {err.max():.2f})")


SPEC = ModelSpec("landmarks", description="landmark shape (seed 000 §3)", box_init=False,
                 from_clip=_landmarks_from_clip, model_class=LandmarkVideo, seed="000", summary=_summary,
                 options=(ModelOption("template", None, "the first frame's landmark positions (K, 2) in pixels",
                                      flag="--template"),))
