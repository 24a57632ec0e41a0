"""Tracking errors and losses (docs/architecture.md, evaluation protocol; thesis §3.2.5, §4.5.3).

- the reproductions of the thesis (``reproduce contour``; ``lost_rule="centre"``): centre
  distance (px); lost when it exceeds 50 px at the thesis's 240-px frame width, scaled with
  the frame width;
- ``eval`` and ``run`` on box-level ground truth (``lost_rule="size"``, as OTB users read
  it): lost when the centre error exceeds half the larger side of the true box — the
  object's own size, not the frame's;
- plate (``lost_rule="plate"``, docs/architecture.md): lost in a frame with a plate when no plate is
  reported or the summed vertex error exceeds a third of the plate height; a report in a
  frame without a plate is a false report (:func:`plate_frame_measures`);
- P(lost) per frame is the fraction of runs lost; the mean error is over
  runs (and frames) not lost;
- what the tracker reported: the long-term scores of :mod:`vistrack.scoring.long_term_scores` (:func:`lt_scores`,
  :func:`reported_ious`).
"""

from __future__ import annotations

import time

import numpy as np

from .long_term_scores import lt_pooled

__all__ = ["center_error", "contour_lost_threshold", "plate_frame_measures", "lost_frames", "summarize_runs",
           "landmark_error", "iou", "success_auc", "success_curve", "precision", "precision_curve", "IOU_THRESHOLDS",
           "PRECISION_THRESHOLDS", "box_scores", "score_frames", "reported_ious",
           "lt_scores",
           "equal_time", "best_ms", "equal_time_n", "equal_time_search"]

#: IoU thresholds of the success plot (OTB protocol)
IOU_THRESHOLDS = np.linspace(0.0, 1.0, 21)
#: centre-error thresholds (px) of the precision plot (OTB)
PRECISION_THRESHOLDS = np.arange(0, 51)


def center_error(est_cx, est_cy, true_cx, true_cy):
    """Euclidean centre distance (px), elementwise."""
    return np.hypot(np.asarray(est_cx) - true_cx, np.asarray(est_cy) - true_cy)


def contour_lost_threshold(frame_width):
    """50 px at 240-px frame width (thesis §3.2.5), scaled with the width."""
    return 50.0 * frame_width / 240.0


def summarize_runs(errors, lost):
    """Summaries of ``errors, lost (runs, frames)`` arrays.

    Returns a dict: ``p_lost_per_frame (frames,)``, ``p_lost_final``, ``p_lost_mean``
    (average over frames), ``mean_error`` (over all not-lost run-frames, NaN if none)
    and ``error_per_frame (frames,)`` (mean over runs not lost at that frame).
    """
    errors = np.asarray(errors, float)
    lost = np.asarray(lost, bool)
    p = lost.mean(axis=0)
    ok = ~lost
    with np.errstate(invalid="ignore"):
        per_frame = np.where(ok.any(axis=0), np.sum(np.where(ok, errors, 0), axis=0) / ok.sum(axis=0), np.nan)
    return {
        "p_lost_per_frame": p,
        "p_lost_final": float(p[-1]),
        "p_lost_mean": float(p.mean()),
        "mean_error": float(errors[ok].mean()) if ok.any() else float("nan"),
        "error_per_frame": per_frame,
    }


def landmark_error(rows, truth, k):
    """Mean distance (px) between estimated and true landmarks per frame.

    ``rows``: track rows (``frame``, ``lx0..``, ``ly0..``); ``truth``: ground-truth
    columns with the same names. Frames beyond the truth are ignored.
    """
    idx = np.array([r["frame"] for r in rows], int)
    ok = idx < len(truth["lx0"])
    est = np.array([[[r[f"lx{i}"], r[f"ly{i}"]] for i in range(k)] for r, o in zip(rows, ok) if o])
    tru = np.stack([np.column_stack([truth[f"lx{i}"][idx[ok]], truth[f"ly{i}"][idx[ok]]]) for i in range(k)], axis=1)
    return np.linalg.norm(est - tru, axis=2).mean(axis=1)


def iou(a, b):
    """Intersection over union of boxes ``(..., 4)`` as ``(x, y, w, h)``, in ``[0, 1]`` (two equal boxes'
    rounding can give 1 + 1e-15, which the success plot's last threshold, 1, would count as above it)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    x0 = np.maximum(a[..., 0], b[..., 0])
    y0 = np.maximum(a[..., 1], b[..., 1])
    x1 = np.minimum(a[..., 0] + a[..., 2], b[..., 0] + b[..., 2])
    y1 = np.minimum(a[..., 1] + a[..., 3], b[..., 1] + b[..., 3])
    inter = np.clip(x1 - x0, 0, None) * np.clip(y1 - y0, 0, None)
    union = a[..., 2] * a[..., 3] + b[..., 2] * b[..., 3] - inter
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.clip(np.where(union > 0, inter / union, 0.0), 0.0, 1.0)


def success_curve(ious):
    """The success plot (OTB): for each of :data:`IOU_THRESHOLDS`, the share of the IoUs ``(...)`` (one
    run's frames, or runs × frames) above it; NaN counts as 0. Without frames (a ground truth in which
    the object is never in view) each share is NaN: there is nothing to score."""
    ious = np.nan_to_num(np.asarray(ious, float))
    if not ious.size:
        return [float("nan")] * len(IOU_THRESHOLDS)
    return [float((ious > t).mean()) for t in IOU_THRESHOLDS]


def success_auc(ious):
    """Area under the success plot (OTB): the mean of :func:`success_curve` (NaN without frames)."""
    return float(np.mean(success_curve(ious))) if np.size(ious) else float("nan")


def precision(errors, px=20.0):
    """Share of the centre errors ``(...)`` (px; ``inf`` where there is no estimate) at most ``px``: the
    precision score (OTB: 20 px)."""
    errors = np.asarray(errors, float)
    return float(np.mean(errors <= px)) if errors.size else 0.0


def precision_curve(errors):
    """The precision plot (OTB): :func:`precision` at each of :data:`PRECISION_THRESHOLDS`."""
    return [precision(errors, th) for th in PRECISION_THRESHOLDS]


def box_scores(boxes, truth, precision_px=20.0):
    """OTB's one-pass scores of a box track.

    Parameters
    ----------
    boxes, truth : ndarray, shape (T, 4)
        Estimated and true ``x, y, w, h`` per frame; frames whose true box has no area (the
        object not in view, ``0,0,0,0``) are not scored, as the toolkits do.
    precision_px : float
        Centre-error threshold of the precision score.

    Returns
    -------
    auc : float
        :func:`success_auc` of the IoUs.
    precision : float
        Share of frames whose centre error is at most ``precision_px``.
    error : float
        Mean centre error (px).
    """
    boxes, truth = np.asarray(boxes, float).reshape(-1, 4), np.asarray(truth, float).reshape(-1, 4)
    seen = (truth[:, 2] > 0) & (truth[:, 3] > 0)
    b, g = boxes[seen], truth[seen]
    if not len(g):
        return float("nan"), float("nan"), float("nan")
    err = center_error(b[:, 0] + b[:, 2] / 2, b[:, 1] + b[:, 3] / 2, g[:, 0] + g[:, 2] / 2, g[:, 1] + g[:, 3] / 2)
    err = np.nan_to_num(err, nan=np.inf)
    return success_auc(iou(b, g)), precision(err, precision_px), float(np.mean(err))


def reported_ious(boxes, truth, visible):
    """IoUs ``(T,)`` of ``boxes`` with ``truth`` (``(T, 4)`` ``x, y, w, h``) where the tracker reports the
    object (``visible (T,)`` true) and 0 where it reports it lost: an empty box. Frames whose true box
    has no area get 0 too (the callers score only frames with the object, as OTB does)."""
    v = np.nan_to_num(iou(boxes, truth), nan=0.0)
    return np.where(np.asarray(visible, bool), v, 0.0)


def lt_scores(boxes, truth, visible, confidence=None, resolution=100):
    """VOT-LT's long-term scores of one track (module docstring).

    Parameters
    ----------
    boxes, truth : ndarray, shape (T, 4)
        Predicted and true ``x, y, w, h`` (a true box without area: the object absent).
    visible : ndarray, shape (T,)
        Whether the tracker reports the object on each frame.
    confidence : ndarray of shape (T,) or None
        The tracker's confidence; ``None`` for a tracker without one (the scores at its own threshold).
    resolution : int
        Thresholds over the confidences (:func:`~vistrack.scoring.long_term_scores.lt_thresholds`).

    Returns
    -------
    dict
        ``precision``, ``recall``, ``f_score`` and ``threshold`` at the best threshold (at the tracker's own:
        ``threshold`` NaN, where it has no confidence), and ``precision_own``, ``recall_own``, ``f_own``
        over the frames it reports visible.
    """
    truth = np.asarray(truth, float)
    present = (truth[:, 2] > 0) & (truth[:, 3] > 0)
    return lt_pooled([("", iou(boxes, truth), present, visible, confidence)], resolution)


def plate_frame_measures(result, truth, aspect):
    """Per-frame ``(has_plate, vertex_error, lost, false_report)`` of one task against the truth."""
    m = min(len(result["reported"]), len(truth["frame"]))
    has = np.asarray(truth["visible"][:m]) > 0
    rep = np.asarray(result["reported"][:m], bool)
    est = np.asarray(result["vertices"][:m], float).reshape(m, 4, 2)
    tv = np.stack([np.column_stack([truth[f"x{i}"][:m], truth[f"y{i}"][:m]]) for i in range(4)], axis=1)
    err = np.linalg.norm(est - tv, axis=2).sum(axis=1)
    height = np.asarray(truth["scale"][:m], float) / aspect
    with np.errstate(invalid="ignore"):
        lost = has & (~rep | ~(err <= height / 3))
    return has, np.where(has, err, np.nan), lost, ~has & rep


def lost_frames(rule, centre_err, frame_width, *, truth=None, reported=None, vertices=None, aspect=None):
    """Per-frame lost flags ``(frames,)`` by a model's lost rule (module docstring).

    ``rule="centre"``: ``centre_err (frames,)`` above :func:`contour_lost_threshold` of the
    frame width. ``rule="size"``: above half the larger side of the true box (``truth["w"]``,
    ``truth["h"]``). ``rule="plate"``: :func:`plate_frame_measures` of ``reported (frames,)`` and
    ``vertices (frames, 4, 2)`` against ``truth`` (groundtruth.csv columns with vertices
    ``x0..y3``, ``scale``, ``frame``, ``visible``); where the truth has no vertices (a box
    ground truth), the centre rule.
    """
    centre_err = np.asarray(centre_err, float)
    if rule == "plate" and truth is not None and "x0" in truth:
        rec = {"reported": list(reported), "vertices": np.asarray(vertices, float).reshape(len(reported), -1)}
        _, _, lost, _ = plate_frame_measures(rec, truth, aspect)
        out = np.zeros(len(centre_err), bool)
        out[:len(lost)] = lost[:len(centre_err)]
        return out
    if rule == "size" and truth is not None:
        m = len(centre_err)
        half = 0.5 * np.maximum(np.asarray(truth["w"][:m], float), np.asarray(truth["h"][:m], float))
        with np.errstate(invalid="ignore"):
            return ~(centre_err <= half)
    if rule not in ("centre", "plate", "size"):
        raise ValueError(f"unknown lost rule {rule!r}")
    return centre_err > contour_lost_threshold(frame_width)


def score_frames(truth, boxes, frame_width, *, rule="size", reported=(), vertices=(), aspect=None, shown=None,
                 confidence=None):
    """Per-frame measures of one track, what ``eval`` records per task and ``run``'s summary scores.

    Parameters
    ----------
    truth : dict
        The ground truth's columns (``cx``, ``cy``, ``w``, ``h``, ``visible``; a plate's vertices).
    boxes : ndarray, shape (frames, 4)
        ``x, y, w, h`` per frame from the first, NaN where the tracker gave no estimate (a frame
        that failed to decode, one before the start): such a frame is a missed frame (error
        infinite: lost, outside every precision threshold, IoU 0).
    frame_width : int
    rule, reported, vertices, aspect
        The lost rule and its inputs (:func:`lost_frames`).
    shown : array_like of bool, shape (frames,), optional
        Whether the tracker reported the object on each frame (``visible``); by default where it gave a
        box with an area.
    confidence : array_like, shape (frames,), optional
        The tracker's confidence per frame (NaN where it gave none).

    Returns
    -------
    dict
        ``frames``, ``visible``, ``error`` (centre, px; ``None`` without an estimate), ``lost``,
        ``iou``, ``boxes`` (``None`` without an estimate), ``reported`` (0/1) and ``confidence``
        (``None`` without one), lists of ``frames`` values (``confidence``: ``None`` when not given).
    """
    t = truth
    m = min(len(boxes), len(t["cx"]))
    tb = np.stack([t["cx"] - t["w"] / 2, t["cy"] - t["h"] / 2, t["w"], t["h"]], axis=1)[:m]
    boxes = np.asarray(boxes, float)[:m]
    err = center_error(boxes[:, 0] + boxes[:, 2] / 2, boxes[:, 1] + boxes[:, 3] / 2, tb[:, 0] + tb[:, 2] / 2,
                       tb[:, 1] + tb[:, 3] / 2)
    err = np.where(np.isfinite(err), err, np.inf)
    visible = np.asarray(t["visible"][:m]) > 0
    if shown is None:
        shown = np.all(np.isfinite(boxes), axis=1) & (np.nan_to_num(boxes[:, 2]) > 0) & (np.nan_to_num(boxes[:, 3]) > 0)
    shown = np.asarray(shown, bool)[:m]
    return {
        "reported": shown.astype(int).tolist(),
        "confidence": None if confidence is None else [None if not np.isfinite(v) else round(float(v), 4)
                                                       for v in np.asarray(confidence, float)[:m]],
        "frames": int(m), "visible": visible.astype(int).tolist(),
        "error": [float(e) if np.isfinite(e) else None for e in err],
        "lost": lost_frames(rule, err, frame_width, truth=t, reported=list(reported)[:m],
                            vertices=list(vertices)[:m], aspect=aspect).astype(int).tolist(),
        "iou": [float(v) for v in np.nan_to_num(iou(boxes, tb), nan=0.0)],
        "boxes": [None if not np.all(np.isfinite(b)) else [round(float(v), 3) for v in b] for b in boxes],
    }


# -- equal-time particle counts (thesis Tables 3.1, 4.1, 4.3) ---------------------------------------
def best_ms(run, repeats=2, clock=time.perf_counter):
    """The least time of ``repeats`` calls of ``run()``, in ms by ``clock`` (the timing of every
    equal-time comparison: the fastest run is the one least disturbed by the machine's other work)."""
    best = np.inf
    for _ in range(repeats):
        t0 = clock()
        run()
        best = min(best, (clock() - t0) * 1e3)
    return best


def equal_time(ms, entries, *, search_steps=None, doubled=False, **line):
    """``entries`` (``(algo, N)`` pairs) with every N after the first set so that its time ``ms(algo, N)``
    matches the first entry's (thesis Tables 3.1, 4.1, 4.3: the particle counts of equal CPU time).

    Each N is solved by a straight line through N and 2N (:func:`equal_time_n`, with the options
    ``line``), or with ``search_steps`` by the secant search (:func:`equal_time_search`). Returns
    ``(entries, times)``: ``times`` maps ``"algo:N"`` to ``ms(algo, N)`` for the first entry and, for
    each other, at its given N (and with ``doubled`` at 2N) or, searched, at the N found.
    """
    (ref_algo, ref_n), *rest = entries
    budget = ms(ref_algo, ref_n)
    out, times = [(ref_algo, ref_n)], {f"{ref_algo}:{ref_n}": budget}
    for algo, n in rest:
        if search_steps is not None:
            m, t = equal_time_search(lambda k: ms(algo, k), n, budget, search_steps)
            times[f"{algo}:{m}"] = t
        else:
            m, t1, t2 = equal_time_n(lambda k: ms(algo, k), n, budget, **line)
            times[f"{algo}:{n}"] = t1
            if doubled:
                times[f"{algo}:{2 * n}"] = t2
        out.append((algo, m))
    return out, times


def equal_time_n(t, n, budget, *, min_slope=0.0, checks=0, tolerance=1.25):
    """The particle count whose time ``t(N)`` matches ``budget``: a straight line through ``t(n)`` and
    ``t(2n)`` (time per particle ``(t(2n) - t(n)) / n``, at least ``min_slope · t(n) / n`` so that a
    slope lost in timing noise cannot pick a huge N), then up to ``checks`` timings at the pick, each
    scaling it by ``budget / t`` while it takes over ``tolerance · budget``.

    Returns ``(N, t(n), t(2n))``. ``eval --equal-time`` uses ``min_slope=0.1, checks=3``; the
    history-sampling and several-plate reproductions the plain line.
    """
    t1, t2 = t(n), t(2 * n)
    per = max((t2 - t1) / n, min_slope * t1 / n, 1e-6)
    m = int(max(1, round(n + (budget - t1) / per)))
    for _ in range(checks):
        tm = t(m)
        if tm <= tolerance * budget:
            break
        m = max(1, int(m * budget / tm))
    return m, t1, t2


def equal_time_search(t, n, budget, steps):
    """``(N, t(N))`` with ``t(N)`` closest to ``budget`` (in ratio) among the N tried: ``n``, then
    ``steps`` steps, each a secant step through the last two N (kept within a factor 4 of the
    last), or the last N scaled by ``budget / t`` where the secant has no positive slope (the
    bearings reproduction: a straight line through N and 2N is thrown far off by one noisy timing
    when the answer lies far from N)."""
    tried = {n: t(n)}
    a, b = None, max(1, round(n * budget / tried[n]))
    for _ in range(steps):
        if b in tried:
            break
        tried[b] = t(b)
        slope = (tried[b] - tried[a]) / (b - a) if a is not None else 0.0
        c = b + (budget - tried[b]) / slope if slope > 0 else b * budget / tried[b]
        a, b = b, int(max(1, round(min(max(c, b / 4), 4 * b))))
    best = min(tried, key=lambda k: abs(np.log(tried[k] / budget)))
    return best, tried[best]
