"""Build a tracking model for a clip from the user's initialisation (``vistrack run``).

Kept out of the CLI so that evaluation code builds models the same way. Each model's own
construction is in its package's ``builder`` module (its registry entry,
:mod:`vistrack.registry.catalog`); this module dispatches on the registry.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..io.starts import MAX_BOX_FACTOR, check_start_box, first_frame, initial_truth, start_box, start_frame
from ..io.video import VideoError
from ..io.video_errors import quoted
from .catalog import MODELS, get_model_spec

__all__ = ["MAX_BOX_FACTOR", "initial_truth", "start_frame", "check_start_box", "build_model", "model_from_box",
           "read_support_points"]


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
                raise VideoError(f"{p}, line {k}: expected two numbers x y, got {quoted(line)}") from None
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
        starts = ", ".join(k for k, v in MODELS.items() if v.from_box is not None)
        raise VideoError(f"model {name!r} does not start from a box; choose from {starts}")
    frame = np.asarray(frame)
    check_start_box(box, (frame.shape[1], frame.shape[0]), "start box")
    return spec.from_box(frame, box, **params)


def _spec(name):
    try:
        return get_model_spec(name)
    except ValueError as e:
        raise VideoError(str(e)) from None


def build_model(name, clip, *, init=None, init_gt=None, template=None, **params):
    """The model ``name`` for ``clip`` started from ``init`` (x, y, w, h) or the ground truth.

    For ``contour``: with the clip's template (meta.json) and a ground-truth row
    that has ``scale``/``angle_deg``, the template at that pose; otherwise an
    ellipse fitted to the box. ``template`` (support points, ``(n, 2)`` pixels)
    replaces the ellipse: scaled to fit the box when one is given, else used
    where it lies in the first frame. ``polarity="auto"`` learns the edge polarity from
    the first frame (:meth:`Contour.learn_polarity`); ``None`` keeps edges unsigned.

    Dispatches on the registry (:mod:`vistrack.registry.catalog`): the model's ``from_clip``,
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
    box = start_box(clip, init, init_gt)
    return spec.from_box(first_frame(clip, start_frame(clip, init, init_gt)), box, **params)
