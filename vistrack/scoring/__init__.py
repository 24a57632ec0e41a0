"""Scores of tracks against ground truth and their summaries over runs: :mod:`~vistrack.scoring.metrics`
(errors, lost frames, success and precision, the per-frame measures, equal time),
:mod:`~vistrack.scoring.long_term_scores` (VOT-LT's precision, recall and F), :mod:`~vistrack.scoring.mot`
(several targets: CLEAR-MOT and IDF1) and :mod:`~vistrack.scoring.aggregate` (``eval``'s summaries)."""

from .aggregate import pooled_summary, summarize
from .metrics import (
    IOU_THRESHOLDS,
    PRECISION_THRESHOLDS,
    best_ms,
    box_scores,
    center_error,
    equal_time,
    iou,
    landmark_error,
    lost_frames,
    precision,
    precision_curve,
    score_frames,
    success_auc,
    success_curve,
)
from .mot import Identities, MultiTarget, clear_mot, objects_by_frame

__all__ = ["summarize", "pooled_summary", "center_error", "landmark_error", "iou", "lost_frames", "success_auc",
           "success_curve", "precision", "precision_curve", "box_scores", "score_frames", "equal_time", "best_ms",
           "IOU_THRESHOLDS", "PRECISION_THRESHOLDS", "MultiTarget", "Identities", "clear_mot", "objects_by_frame"]
