"""Long-term tracking scores: what a tracker reported against the ground truth's absences.

VOT-LT (Lukežič et al. 2018, "Now you see me: evaluating performance in long-term visual tracking"):
a frame is *predicted* when the tracker reports the object there with a confidence at least ``τ``;
the tracking precision ``Pr(τ)`` is the mean IoU over the predicted frames (0 where the truth has no
object), the recall ``Re(τ)`` the IoU summed over the predicted frames over the number of frames with
the object; ``F(τ) = 2 Pr Re / (Pr + Re)``, and the scores are ``Pr``, ``Re`` and ``F`` at the ``τ``
that maximises ``F`` (:func:`vistrack.scoring.metrics.lt_scores`); for a tracker without a confidence, at
its own threshold: the frames it reports visible. The OTB success AUC of a long-term tracker scores the
frames it reports lost as empty boxes (IoU 0, :func:`vistrack.scoring.metrics.reported_ious`). One
track's scores from its boxes: :func:`vistrack.scoring.metrics.lt_scores`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["lt_thresholds", "lt_curves", "lt_pooled", "reported_summary"]


def lt_thresholds(confidences, resolution=100):
    """VOT-LT's confidence thresholds: ``resolution - 2`` values spread evenly over the sorted finite
    ``confidences`` (all of them, when fewer), from the highest down, between ``+inf`` and ``-inf``."""
    c = np.asarray(confidences, float)
    c = np.sort(c[np.isfinite(c)])[::-1]
    if len(c) > resolution - 2:
        delta = len(c) // (resolution - 2)
        c = c[np.round(np.linspace(delta, len(c) - delta, resolution - 2)).astype(int)]
    return np.concatenate([[np.inf], c, [-np.inf]])


def lt_curves(overlap, present, confidence, thresholds):
    """Tracking precision and recall ``(K,)`` at each of ``thresholds (K,)`` (module docstring).

    Parameters
    ----------
    overlap : ndarray, shape (T,)
        The IoU of the tracker's box with the true box per frame (NaN counts as 0).
    present : ndarray, shape (T,)
        Whether the object is in view (a true box); a frame without it scores 0 where predicted.
    confidence : ndarray, shape (T,)
        The tracker's confidence per frame (the frame is predicted at ``τ`` where it is at least ``τ``;
        NaN: never); ``visible`` as 0/1 for a tracker without one.
    thresholds : ndarray, shape (K,)

    Returns
    -------
    precision, recall : ndarray, shape (K,)
        Precision is 1 and recall 0 at a threshold with no frame predicted (as VOT's toolkit).
    """
    present = np.asarray(present, bool)
    overlap = np.where(present, np.nan_to_num(np.asarray(overlap, float), nan=0.0), 0.0)
    conf = np.nan_to_num(np.asarray(confidence, float), nan=-np.inf)
    pred = conf[None, :] >= np.asarray(thresholds, float)[:, None]  # (K, T)
    n_pred = pred.sum(axis=1)
    hit = pred @ overlap
    precision = np.where(n_pred > 0, hit / np.maximum(n_pred, 1), 1.0)
    recall = hit / present.sum() if present.any() else np.zeros(len(hit))
    return precision, recall


def _f_max(precision, recall):
    """``(Pr, Re, F, k)`` at the index ``k`` of the highest ``F = 2 Pr Re / (Pr + Re)`` (the first of equals)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        f = np.where(precision + recall > 0, 2 * precision * recall / (precision + recall), 0.0)
    k = int(np.argmax(f))
    return float(precision[k]), float(recall[k]), float(f[k]), k


def lt_pooled(tracks, resolution=100):
    """VOT-LT's scores over several runs and sequences: the thresholds from every run's confidences
    (:func:`lt_thresholds`), each sequence's precision and recall curves averaged over its runs, those
    averaged over the sequences, and ``Pr``, ``Re``, ``F`` at the threshold that maximises the mean
    curves' ``F``; and the same at the trackers' own threshold (the frames reported visible).

    Parameters
    ----------
    tracks : list of (str, overlap, present, visible, confidence)
        One per run: its sequence's name, the IoU per frame ``(T,)``, whether the object is in view
        ``(T,)``, whether the tracker reports it ``(T,)`` and its confidence ``(T,)`` or ``None``.

    Returns
    -------
    dict
        ``precision``, ``recall``, ``f_score``, ``threshold`` (at the own threshold, and ``threshold`` NaN,
        where no run has a confidence), ``precision_own``, ``recall_own``, ``f_own``.
    """
    def mean_curves(confs, th):
        seqs = {}
        for (name, overlap, present, _, _), conf in zip(tracks, confs):
            seqs.setdefault(name, []).append(lt_curves(overlap, present, conf, th))
        return (np.mean([np.mean([c[0] for c in cs], axis=0) for cs in seqs.values()], axis=0),
                np.mean([np.mean([c[1] for c in cs], axis=0) for cs in seqs.values()], axis=0))

    shown = [np.asarray(v, bool).astype(float) for _, _, _, v, _ in tracks]
    p, r, f, _ = _f_max(*mean_curves(shown, np.array([1.0])))
    out = {"precision_own": p, "recall_own": r, "f_own": f}
    if all(c is None for *_, c in tracks):
        return {"precision": p, "recall": r, "f_score": f, "threshold": float("nan"), **out}
    confs = [v if c is None else np.asarray(c, float) for v, (*_, c) in zip(shown, tracks)]
    th = lt_thresholds(np.concatenate(confs), resolution)
    p, r, f, k = _f_max(*mean_curves(confs, th))
    return {"precision": p, "recall": r, "f_score": f, "threshold": float(th[k]), **out}


def reported_summary(clip, results, vis):
    """What the tracker reported over ``results`` (one clip's task results, each with ``iou`` and, from a
    tracker that reports, ``reported`` and ``confidence``; ``vis (frames,)``: the frames with the object):
    ``reported_lost`` (the share of the frames with the object it reported lost), ``lost_empty`` (the IoUs
    ``(runs, frames with the object)`` with those frames as empty boxes, for the success AUC), and VOT-LT's
    ``lt_precision``, ``lt_recall``, ``lt_f`` over the runs (:func:`lt_pooled`; at the tracker's own
    threshold where it has no confidence) and ``lt_f_own`` (at its own threshold). A result without
    ``reported`` reported every frame."""
    ious = np.array([r["iou"] for r in results], float)
    shown = np.array([r.get("reported") or [1] * len(r["iou"]) for r in results], bool)
    conf = [None if r.get("confidence") is None else np.array([np.nan if v is None else v for v in r["confidence"]])
            for r in results]
    lt = lt_pooled([(clip, v, vis, s, c) for v, s, c in zip(ious, shown, conf)])
    return {"reported_lost": float((~shown[:, vis]).mean()) if vis.any() else 0.0,
            "lost_empty": np.where(shown, np.nan_to_num(ious, nan=0.0), 0.0)[:, vis],
            "lt_precision": lt["precision"], "lt_recall": lt["recall"], "lt_f": lt["f_score"], "lt_f_own": lt["f_own"]}
