"""Build a tracking model for a clip from the user's initialisation (``vistrack run``).

Kept out of the CLI so that evaluation code builds models the same way.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .clips import read_groundtruth_csv
from .features import FeatureMaps, is_grey
from .models.contour.model import Contour
from .models.registry import MODELS as _REGISTRY
from .models.registry import ModelSpec, get_model_spec, register
from .video import VideoError, _short, groundtruth_origin, read_rects

__all__ = ["MODELS", "PLATES_ALGOS", "initial_truth", "start_frame", "check_start_box", "build_model", "model_from_box",
           "read_support_points"]


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
            r = read_rects(p, origin=groundtruth_origin(p))
            truth = {"visible": ((r[:, 2] > 0) & (r[:, 3] > 0)).astype(float), "cx": r[:, 0] + r[:, 2] / 2,
                     "cy": r[:, 1] + r[:, 3] / 2, "w": r[:, 2], "h": r[:, 3]}
    vis = np.flatnonzero(np.asarray(truth["visible"]) > 0)
    if not len(vis):
        raise VideoError("--init-gt: the object is not visible in any ground-truth row")
    row = {k: float(v[vis[0]]) for k, v in truth.items() if np.asarray(v).dtype.kind in "fiub"}
    if "w" in row and "cx" in row:
        check_start_box((row["cx"] - row["w"] / 2, row["cy"] - row["h"] / 2, row["w"], row["h"]),
                        clip.source.size, f"the first ground-truth box (frame {int(vis[0])})")
    return row


def start_frame(clip, init=None, init_gt=None):
    """The frame a run starts from: the first frame whose ground-truth row has the object
    (``init_gt`` given, no ``init``), else 0. Frames before it are not tracked (``vistrack run``
    gives them rows with ``lost_reason`` "not started"; their ground truth has no box to score)."""
    if init is not None or init_gt is None:
        return 0
    if init_gt in ("", True):
        truth = clip.truth
        if truth is None:
            return 0
    else:
        p = Path(init_gt)
        if p.suffix == ".csv":
            truth = read_groundtruth_csv(p)
        else:
            r = read_rects(p, origin=groundtruth_origin(p))
            truth = {"visible": ((r[:, 2] > 0) & (r[:, 3] > 0)).astype(float)}
    vis = np.flatnonzero(np.asarray(truth["visible"]) > 0)
    return int(vis[0]) if len(vis) else 0


#: a start box may be at most this many times the frame's width and height
MAX_BOX_FACTOR = 2


def check_start_box(box, size, what="--init box"):
    """Raise :class:`VideoError` unless ``box`` ``(x, y, w, h)`` is one to start tracking from in
    a frame of ``size`` ``(width, height)``: finite, a positive size, at least 2 px of it inside
    the frame each way, and at most :data:`MAX_BOX_FACTOR` times the frame's width and height."""
    fw, fh = size
    x, y, w, h = (float(v) for v in box)
    text = f"{x:.6g},{y:.6g},{w:.6g},{h:.6g}"
    if not all(np.isfinite([x, y, w, h])) or w <= 0 or h <= 0:
        raise VideoError(f"{what} {text} needs finite numbers and a positive size (width and height)")
    if w > MAX_BOX_FACTOR * fw or h > MAX_BOX_FACTOR * fh:
        raise VideoError(f"{what} {text} is far larger than the {fw}x{fh} frame (at most {MAX_BOX_FACTOR} times "
                         "its width and height): give the object's box")
    if min(x + w, fw) - max(x, 0) < 2 or min(y + h, fh) - max(y, 0) < 2:
        raise VideoError(f"{what} {text} lies outside the {fw}x{fh} frame (less than 2 px of it inside): "
                         "give a box on the object")


def read_support_points(path):
    """Contour support points from a file: ``x y`` (or ``x,y``) per line, ``#`` comments,
    or a JSON list of ``[x, y]`` pairs (or a meta.json with ``template.support_points``)."""
    p = Path(path)
    if not p.is_file():
        raise VideoError(f"template file {p} does not exist")
    try:
        text = p.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as e:
        raise VideoError(f"template file {p} is not a text file (byte {e.start} is not UTF-8)") from None
    if p.suffix == ".json":
        import json

        try:
            data = json.loads(text)
        except json.JSONDecodeError as e:
            raise VideoError(f"template file {p} is not valid JSON: {e}") from None
        if isinstance(data, dict):
            tpl = data.get("template")
            data = (tpl if isinstance(tpl, dict) else {}).get("support_points", data.get("support_points"))
        try:
            pts = np.asarray(data, dtype=float) if data is not None else np.zeros((0, 2))
        except (TypeError, ValueError):
            raise VideoError(f"template file {p}: expected a list of [x, y] pairs of numbers") from None
    else:
        rows = []
        for k, line in enumerate(text.splitlines(), 1):
            line = line.split("#")[0].strip()
            if not line:
                continue
            parts = line.replace(",", " ").split()
            try:
                rows.append([float(v) for v in parts])
            except ValueError:
                raise VideoError(f"{p}, line {k}: expected two numbers x y, got {_short(line)}") from None
            if len(parts) != 2:
                raise VideoError(f"{p}, line {k}: expected two numbers x y, got {len(parts)}")
        pts = np.asarray(rows, dtype=float).reshape(-1, 2)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 4:
        raise VideoError(f"template file {p} needs at least 4 support points (x y), got "
                         f"{len(pts) if pts.ndim == 2 and pts.shape[1] == 2 else 'another shape'}")
    bad = np.flatnonzero(~np.all(np.isfinite(pts), axis=1) | np.any(np.abs(pts) > 1e6, axis=1))
    if len(bad):
        raise VideoError(f"template file {p}: support point {bad[0] + 1} is not a finite pixel position "
                         f"({pts[bad[0], 0]:.6g}, {pts[bad[0], 1]:.6g})")
    return pts


def _first_frame(clip, index=0):
    """The first decodable frame of ``clip`` at or after ``index`` (the start frame)."""
    for i, frame in clip.source:
        if i >= index:
            return frame
    raise VideoError(f"{clip.source.path}: no frame could be decoded" + (f" from frame {index} on" if index else ""))


def model_from_box(name, frame, box, **params):
    """Model ``name`` started from ``box`` ``(x, y, w, h)`` in the first ``frame`` (BGR or grey):
    the one place where ``vistrack run --init`` and :class:`vistrack.Tracker` build a model
    (the registry's ``from_box``).

    ``box``: the appearance learned from the frame; ``contour``: the ellipse in the box, its
    edge polarity and (colour video; ``colour="auto"``) its colour term learned from the
    frame (both: the target's colour for the colour-blob proposal); ``plate``: a plate in the box (layout: ``layout``
    or the one nearest the box's aspect ratio), its appearance learned from the frame
    (``appearance=False``: the plate likelihood alone).
    """
    spec = _spec(name)
    if spec.from_box is None:
        starts = ", ".join(k for k, v in _REGISTRY.items() if v.from_box is not None)
        raise VideoError(f"model {name!r} does not start from a box; choose from {starts}")
    frame = np.asarray(frame)
    check_start_box(box, (frame.shape[1], frame.shape[0]), "start box")
    return spec.from_box(frame, box, **params)


def _spec(name):
    try:
        return get_model_spec(name)
    except ValueError as e:
        raise VideoError(str(e)) from None


def _box_from_box(frame, box, **params):
    from .models.box.model import Box

    return Box(frame, box, **params)


def _contour_from_box(frame, box, *, polarity="auto", colour="auto", template=None, **params):
    size = (frame.shape[1], frame.shape[0])
    model = _fit_template(template, box, size, params) if template is not None else \
        Contour.from_box(box, size, **params)
    return _learn_contour(model, frame, polarity, colour)


def _plate_from_frame_box(frame, box, *, appearance=True, layout=None, **params):
    size = (frame.shape[1], frame.shape[0])
    layout = None if layout == "auto" else layout
    return _plate_from_box(size, box, layout, params, frame if appearance else None)


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


def _start_box(clip, init, init_gt):
    """The start box ``(x, y, w, h)``: ``init``, or the first ground-truth row."""
    if init is not None:
        return tuple(float(v) for v in init)
    row = initial_truth(clip, init_gt)
    return (row["cx"] - row["w"] / 2, row["cy"] - row["h"] / 2, row["w"], row["h"])


def build_model(name, clip, *, init=None, init_gt=None, template=None, **params):
    """The model ``name`` for ``clip`` started from ``init`` (x, y, w, h) or the ground truth.

    For ``contour``: with the clip's template (meta.json) and a ground-truth row
    that has ``scale``/``angle_deg``, the template at that pose; otherwise an
    ellipse fitted to the box. ``template`` (support points, ``(n, 2)`` pixels)
    replaces the ellipse: scaled to fit the box when one is given, else used
    where it lies in the first frame. ``polarity="auto"`` learns the edge polarity from
    the first frame (:meth:`Contour.learn_polarity`); ``None`` keeps edges unsigned.

    Dispatches on the registry (:mod:`vistrack.models.registry`): the model's ``from_clip``,
    or without one its ``from_box`` at the start box in the clip's first frame.
    """
    spec = _spec(name)
    if init is not None:
        check_start_box(init, clip.source.size)
    if spec.from_clip is not None:
        return spec.from_clip(clip, init=init, init_gt=init_gt, template=template, **params)
    if init is None and init_gt is None:
        raise VideoError(f"the {name} model needs a start: --init x,y,w,h or --init-gt")
    if template is not None:
        raise VideoError(f"--template is not for the {name} model")
    box = _start_box(clip, init, init_gt)
    return spec.from_box(_first_frame(clip, start_frame(clip, init, init_gt)), box, **params)


def _contour_from_clip(clip, *, init, init_gt, template, polarity="auto", colour="auto", **params):
    if colour == "auto" and (clip.meta or {}).get("model"):
        colour = False  # a rendered clip: the thesis's edge likelihood, as its experiments
    if init is not None:
        return _contour_from_box(_first_frame(clip), init, template=template, polarity=polarity, colour=colour,
                                 **params)
    model = _contour(clip, clip.source.size, init, init_gt, template, params)
    return _learn_contour(model, _first_frame(clip, start_frame(clip, init, init_gt)), polarity, colour)


def _plate_from_clip(clip, *, init, init_gt, template, targets=None, **params):
    if targets is not None:  # several plates at once: acquired by the slots' births
        if init is not None or init_gt is not None:
            raise VideoError("--targets finds the plates by itself: give no --init or --init-gt")
        from .models.plate.plates import Plates

        params.pop("appearance", None)
        layout = _layout(params) or (clip.meta or {}).get("layout") or "jp"
        return Plates(clip.source.size, targets, layout, **params)
    return _plate(clip, clip.source.size, init, init_gt, params)


def _landmarks_from_clip(clip, *, init, init_gt, template, **params):
    if init is not None:
        raise VideoError("--init is a box; the landmarks model starts from --template FILE or --init-gt")
    return _landmarks(clip, clip.source.size, init_gt, template, params)


def _landmarks(clip, size, init_gt, template, params):
    """Landmark model started from the first frame's landmarks: ``--template FILE`` (x y per
    line), ``--init-gt`` (lx0.., ly0.. columns), or the clip's meta.json; the clip's centre,
    scale and dynamics when meta.json has them."""
    from .models.landmarks.video import LandmarkVideo

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


def _plate(clip, size, init, init_gt, params):
    """Plate model; without a start, on a rendered clip it acquires plates through the entering-car
    component, on real footage (the appearance on) it is a
    :class:`~vistrack.models.plate.detect.PlateSearch` that finds the plate in the first frames and
    starts there. The layout is the given one, the clip's, the one nearest the start box's aspect
    ratio, the detection's, or jp."""
    box = init
    if box is None and init_gt is not None:
        row = initial_truth(clip, init_gt)
        box = (row["cx"] - row["w"] / 2, row["cy"] - row["h"] / 2, row["w"], row["h"])
    layout = _layout(params) or (clip.meta or {}).get("layout")
    appearance = params.pop("appearance", "auto")
    if appearance == "auto":  # a rendered clip: the plate likelihood alone, as the thesis experiments
        appearance = not (clip.meta or {}).get("model")
    if box is None and appearance:  # real footage without a box: find the plate first (PlateSearch)
        from .models.plate.detect import PlateSearch

        def build(frame, det):
            # the angle's random walk 0.003 rad/frame, not 0.01: started from a detection, the angle
            # wandered 3 -> 9 degrees on the dashcam clip blurred 7 px (the learned appearance reads the
            # parallelogram's axis-aligned box and hardly holds it): no box, seeds 1-3, AUC 0.70 / 0.68
            # / 0.47 -> 0.77 / 0.75 / 0.77, mean of the 10 plate clips 0.832 -> 0.850. From a box 0.01
            # stays: 0.003 lowered every clip there (dashcam 0.877 -> 0.861; docs/experiments.md, issue 35)
            return _plate_from_box(size, det.box, layout or det.layout, params, frame, angle_sigma=0.003)

        return PlateSearch(build)
    frame = _first_frame(clip, start_frame(clip, init, init_gt)) if appearance and box is not None else None
    return _plate_from_box(size, box, layout, params, frame)


def _layout(params):
    """The ``layout`` parameter taken out of ``params``; ``None`` for none or ``"auto"`` (decided
    from the clip, the start box or the detection)."""
    layout = params.pop("layout", None)
    return None if layout == "auto" else layout


def _plate_from_box(size, box, layout, params, frame=None, angle_sigma=None):
    """A plate model started at ``box`` (or acquiring when ``None``); with the first ``frame``,
    the appearance of the plate in the box is learned too (:meth:`Plate.learn_appearance`) and the
    detector kept for :meth:`Plate.redetect`; ``angle_sigma``: the angle's random walk (rad/frame)
    instead of the model's, unless ``sigma`` is given."""
    from .models.plate.model import Plate

    if layout is None and box is not None:  # the layout whose aspect ratio is nearest the box's
        from .models.plate.layout import LAYOUTS

        r = float(box[2]) / max(float(box[3]), 1e-9)
        layout = min(LAYOUTS, key=lambda k: abs(np.log(LAYOUTS[k].aspect / r)))
    if frame is not None and box is not None:
        # one plate, its appearance learned: no entering-car births (they take the track to other
        # plate-like structure: dashcam from the first box, LIS-100 seeds 1-3, AUC 0.35 / 0.85 /
        # 0.48 with the births; docs/experiments.md, issue 35)
        params = {"enter_weight": 0.0, "birth_reserve": 0.0, **params}
    model = Plate(size, layout=layout or "jp", **params)
    if box is not None:
        x, y, w, h = (float(v) for v in box)
        pose = np.array([x + w / 2, y + h / 2, 0.0, w])
        model.prior_mean = np.concatenate([pose, pose, [0.0]])
        model.start = (pose, np.array([0.05 * w, 0.05 * h, 0.03, 0.05 * w]))
        if frame is not None:
            from .models.plate.detect import PlateDetector

            model.learn_appearance(frame, (x, y, w, h))
            model.detector = PlateDetector()  # the plate searched for again while it is not reported
    if angle_sigma is not None and params.get("sigma") is None:
        model.sigma[2] = float(angle_sigma)
    return model


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


# -- the built-in models -------------------------------------------------------------------
_THESIS = ("lis", "bootstrap", "condensation", "ls-n-ips", "lls", "avpf")
#: SIR and the history-sampling family (§3.2) with the colour-blob proposal: models with an innovation split
_HISTORY = ("sir", "basic-sir", "hs-sir", "rb-hs-sir", "rb-ss-hs-sir")
register(ModelSpec("box", _THESIS + _HISTORY,
                   "any object from a box: colour + template appearance learned from the first frame",
                   from_box=_box_from_box, bytes_per_particle=32_000))
register(ModelSpec("contour", _THESIS + _HISTORY + ("ls-n-ips-nn",),
                   "B-spline contour on edges (thesis 001 §1.3.1), + colour on colour video",
                   from_box=_contour_from_box, from_clip=_contour_from_clip, bytes_per_particle=48_000))
#: with ``targets`` (several plates at once, :class:`~vistrack.models.plate.plates.Plates`): partitioned sampling too
PLATES_ALGOS = ("partitioned-lis", "partitioned", "branched-partitioned-lis", "branched-partitioned", "lis",
                "bootstrap", "condensation")
register(ModelSpec("plate", ("lis", "bootstrap", "condensation", "lls", "avpf"),
                   "license-plate template (thesis 001 §1.3.2); acquires plates without a box",
                   from_box=_plate_from_frame_box, from_clip=_plate_from_clip, lost_rule="plate",
                   bytes_per_particle=48_000, multi_algos=PLATES_ALGOS))
register(ModelSpec("landmarks", ("pf-eis-mt", "pf-eis", "pf-doucet", "pf-gordon", "bootstrap"),
                   "landmark shape (seed 000 §3)", box_init=False, from_clip=_landmarks_from_clip))

#: the built-in models' names (the registry may hold more: :func:`~vistrack.models.registry.register`)
MODELS = tuple(_REGISTRY)
