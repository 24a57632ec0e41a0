"""Summaries of ``eval``'s task results (per clip × algorithm × N, and pooled over clips): OTB's
scores, P(lost) by the ground truth's rule, the errors, and what the tracker reported
(:mod:`vistrack.scoring.long_term_scores`); the per-frame measures they read are
:func:`~vistrack.scoring.metrics.score_frames`'s."""

from __future__ import annotations

import numpy as np

from .long_term_scores import reported_summary
from .metrics import precision, precision_curve, success_auc, success_curve, summarize_runs

__all__ = ["summarize", "pooled_summary"]


def summarize(results, not_filters=()):
    """Per clip × algo × N summaries (list of dicts, in first-seen order) from task results (``eval``'s
    task files); ``not_filters``: the algorithms that are not particle filters (OpenCV's trackers:
    their ``N`` means nothing), besides results read from other trackers' files (``external``).

    Beside OTB's scores and P(lost) (lost by the ground truth), each summary has what the tracker
    reported (:func:`~vistrack.scoring.long_term_scores.reported_summary`)."""
    groups = {}
    for r in results:
        groups.setdefault((r["clip"], r["algo"], r["particles"]), []).append(r)
    out = []
    for (clip, algo, n), rs in groups.items():
        rs = sorted(rs, key=lambda r: r["run"])
        vis = np.array(rs[0]["visible"], bool)
        err = np.array([[np.inf if e is None else e for e in r["error"]] for r in rs])
        lost = np.array([r["lost"] for r in rs], bool) & vis
        ok = ~lost & vis
        p_lost = lost.mean(axis=0)
        with np.errstate(invalid="ignore"):
            err_frame = np.where(ok.any(axis=0), np.sum(np.where(ok, err, 0), axis=0) / ok.sum(axis=0), np.nan)
        ious = np.array([r["iou"] for r in rs])[:, vis]
        reported = reported_summary(clip, rs, vis)
        lost_empty = success_curve(reported.pop("lost_empty"))  # the frames reported lost as empty boxes
        # the scores: over runs × frames, and per run
        success = success_curve(ious)
        precision20 = precision(err[:, vis])
        prec_curve = precision_curve(err[:, vis])
        every = err[:, vis][np.isfinite(err[:, vis])]
        ms = np.array([np.mean(r["ms"]) if r["ms"] else np.nan for r in rs])
        ess = [e for r in rs for e in r["ess"] if e is not None]
        # per run: the spread over runs of the scores below
        auc_run = [success_auc(v) if v.size else 0.0 for v in ious]
        prec_run = [precision(e) for e in err[:, vis]]
        lost_run = [float(v[vis].mean()) if vis.any() else 0.0 for v in lost]
        out.append({
            "clip": clip, "algo": algo, "particles": n, "runs": len(rs),
            # OpenCV's trackers and other trackers' result files have no particles (their N means nothing)
            "particle_filter": algo not in not_filters and not rs[0].get("external", False),
            "success_auc_sd": float(np.std(auc_run)), "precision_20px_sd": float(np.std(prec_run)),
            "p_lost_sd": float(np.std(lost_run)),
            "mean_error": float(err[ok].mean()) if ok.any() else None,
            "mean_error_all": float(every.mean()) if every.size else None,
            "p_lost": float(p_lost[vis].mean()) if vis.any() else 0.0,
            "p_lost_final": float(p_lost[-1]) if p_lost.size else 0.0,
            "p_lost_per_frame": p_lost.tolist(),
            "error_per_frame": [None if not np.isfinite(v) else float(v) for v in err_frame],
            "success_auc": float(np.mean(success)),
            "success_curve": success,
            **reported,
            "success_auc_lost_empty": float(np.mean(lost_empty)),
            "precision_20px": precision20,
            "precision_curve": prec_curve,
            "frames_per_s": float(1e3 / ms.mean()) if np.all(np.isfinite(ms)) else None,
            "mean_ess": float(np.mean(ess)) if ess else None,
        })
    return out


def pooled_summary(results):
    """Per (algo, N) over all clips and runs (same frame count): P(lost) per frame, at the
    last frame and averaged, mean error over frames not lost, ms per frame, mean ESS."""
    groups = {}
    for r in results:
        groups.setdefault((r["algo"], r["particles"]), []).append(r)
    out = []
    for (algo, n), rs in groups.items():
        err = np.array([[np.inf if e is None else e for e in r["error"]] for r in rs])
        s = summarize_runs(err, np.array([r["lost"] for r in rs], bool))
        ms = float(np.mean([np.mean(r["ms"]) for r in rs]))
        ess = [e for r in rs for e in r["ess"] if e is not None]
        out.append({"algo": algo, "particles": n, "clips": len({r["clip"] for r in rs}),
                    "runs": len(rs) // max(1, len({r["clip"] for r in rs})),
                    "p_lost_final": s["p_lost_final"], "p_lost_mean": s["p_lost_mean"], "mean_error": s["mean_error"],
                    "ms_per_frame": ms, "frames_per_s": 1e3 / ms, "mean_ess": float(np.mean(ess)) if ess else None,
                    "p_lost_per_frame": s["p_lost_per_frame"].tolist(),
                    "error_per_frame": [None if not np.isfinite(v) else float(v) for v in s["error_per_frame"]]})
    return out
