"""How ``run``, ``eval`` and :class:`vistrack.Tracker` build the contour model: its registry entry."""

from __future__ import annotations

import numpy as np

from ...appearance.features import FeatureMaps, is_grey
from ...io.starts import first_frame, initial_truth, start_frame
from ...io.video import VideoError
from ..protocol import LocalSearch
from ..spec import ModelOption, ModelSpec
from .model import Contour
from .nn import NNSearchConfig, load_or_train

__all__ = ["SPEC", "train_search"]


def _contour_from_box(frame, box, *, polarity="auto", colour="auto", template=None, **params):
    size = (frame.shape[1], frame.shape[0])
    model = _fit_template(template, box, size, params) if template is not None else \
        Contour.from_box(box, size, **params)
    return _learn_contour(model, frame, polarity, colour)


def _learn_contour(model, frame, polarity, colour):
    """What the contour learns from the first frame: the edge polarity (``"auto"``: learned,
    :meth:`Contour.learn_polarity`; else as given) and the colour term (``"auto"``: on for
    colour video, :meth:`Contour.learn_colour`; ``True``/``False``)."""
    if polarity == "auto":
        model.learn_polarity(FeatureMaps(frame))
    else:
        model.polarity = polarity
    if colour == "auto":
        colour = not is_grey(frame)
    if colour:
        model.learn_colour(frame)
    model.learn_blob(frame)  # the colour-blob proposal of the history-sampling filters and sir
    return model


def _contour_from_clip(clip, *, init, init_gt, template, polarity="auto", colour="auto", **params):
    if colour == "auto" and (clip.meta or {}).get("model"):
        colour = False  # a rendered clip: the thesis's edge likelihood, as its experiments
    if init is not None:
        return _contour_from_box(first_frame(clip), init, template=template, polarity=polarity, colour=colour,
                                 **params)
    model = _contour(clip, clip.source.size, init, init_gt, template, params)
    return _learn_contour(model, first_frame(clip, start_frame(clip, init, init_gt)), polarity, colour)


def _fit_template(template, box, size, params):
    """The support points scaled (uniformly) and moved to fit the box ``(x, y, w, h)``."""
    x, y, w, h = (float(v) for v in box)
    q = np.asarray(template, float)
    ext = q.max(axis=0) - q.min(axis=0)
    s = float(np.sqrt(w * h / max(ext[0] * ext[1], 1e-9)))
    q = (q - q.mean(axis=0)) * s
    return Contour(q, (x + w / 2, y + h / 2, 0.0, 0.0), size, **params)


def _contour(clip, size, init, init_gt, template, params):
    if init is not None:
        if template is not None:
            return _fit_template(template, init, size, params)
        return Contour.from_box(init, size, **params)
    if init_gt is None:
        if template is not None:  # support points where they lie in the first frame
            q = np.asarray(template, float)
            c = q.mean(axis=0)
            return Contour(q - c, (c[0], c[1], 0.0, 0.0), size, **params)
        raise VideoError("the contour model needs a start: --init x,y,w,h, --init-gt or --template FILE")
    row = initial_truth(clip, init_gt)
    if template is not None:
        return _fit_template(template, (row["cx"] - row["w"] / 2, row["cy"] - row["h"] / 2, row["w"], row["h"]),
                             size, params)
    tmpl = ((clip.meta or {}).get("template") or {}).get("support_points")
    if tmpl is not None and "scale" in row:
        return Contour.from_template(np.asarray(tmpl, float), size, cx=row["cx"], cy=row["cy"],
                                     scale=row["scale"], angle_deg=row.get("angle_deg", 0.0), **params)
    return Contour.from_box((row["cx"] - row["w"] / 2, row["cy"] - row["h"] / 2, row["w"], row["h"]), size,
                            **params)



def train_search(points, size=(320, 240), *, samples=NNSearchConfig.samples, seed=0, path=None, notify=None):
    """The neural-network local search of LS-N-IPS (thesis 001 §4.3.1, Fig. 4.5) for the contour of support
    points ``points`` (``(n, 2)`` pixels as tracked) on frames of ``size``: trained on ``samples`` simulated
    poses from ``seed`` and cached (``path``, else the cache), or loaded where it is there; ``(network,
    info)`` of :func:`~vistrack.models.contour.nn.load_or_train`."""
    model = Contour(points, (0.0, 0.0, 0.0, 0.0), size)
    return load_or_train(model, NNSearchConfig(samples=samples, seed=seed), path=path, notify=notify)


SPEC = ModelSpec("contour", description="B-spline contour on edges (thesis 001 §1.3.1), + colour on colour video",
                 from_box=_contour_from_box, from_clip=_contour_from_clip, bytes_per_particle=48_000,
                 model_class=Contour, options=(
                     ModelOption("template", None, "support points (n, 2) in pixels instead of the ellipse",
                                 flag="--template"),
                     ModelOption("colour", "auto", "the colour term: on for colour video (auto), True or False",
                                 flag="--no-colour", value=False),
                     ModelOption("search", None, "LS-N-IPS's local search: lms or nn (the neural network)",
                                 flag="--search", needs=LocalSearch)))
