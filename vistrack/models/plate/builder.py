"""How ``run``, ``eval`` and :class:`vistrack.Tracker` build the plate model: its registry entry."""

from __future__ import annotations

import numpy as np

from ...io.starts import first_frame, initial_truth, start_frame
from ...io.video import VideoError
from ...scoring.metrics import plate_frame_measures
from ..spec import ModelOption, ModelSpec
from .model import Plate
from .plates import Plates

__all__ = ["SPEC"]


def _plate_from_frame_box(frame, box, *, appearance=True, layout=None, **params):
    size = (frame.shape[1], frame.shape[0])
    layout = None if layout == "auto" else layout
    return _plate_from_box(size, box, layout, params, frame if appearance else None)


def _plate_from_clip(clip, *, init, init_gt, template, targets=None, **params):
    if targets is not None:  # several plates at once: acquired by the slots' births
        if init is not None or init_gt is not None:
            raise VideoError("--targets finds the plates by itself: give no --init or --init-gt")
        params.pop("appearance", None)
        layout = _layout(params) or (clip.meta or {}).get("layout") or "jp"
        return Plates(clip.source.size, targets, layout, **params)
    return _plate(clip, clip.source.size, init, init_gt, params)


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
        from .detect import PlateSearch

        def build(frame, det):
            # the angle's random walk 0.003 rad/frame, not 0.01: started from a detection, with 0.01 the
            # angle wanders 3 -> 9 degrees on the dashcam clip blurred 7 px (the learned appearance reads the
            # parallelogram's axis-aligned box and hardly holds it): no box, seeds 1-3, AUC 0.77 / 0.75 /
            # 0.77 against 0.70 / 0.68 / 0.47, mean of the 10 plate clips 0.850 against 0.832. From a box
            # 0.01: 0.003 lowers every clip there (dashcam 0.861 against 0.877; docs/experiments.md)
            return _plate_from_box(size, det.box, layout or det.layout, params, frame, angle_sigma=0.003)

        return PlateSearch(build)
    frame = first_frame(clip, start_frame(clip, init, init_gt)) if appearance and box is not None else None
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
    if layout is None and box is not None:  # the layout whose aspect ratio is nearest the box's
        from .layout import LAYOUTS

        r = float(box[2]) / max(float(box[3]), 1e-9)
        layout = min(LAYOUTS, key=lambda k: abs(np.log(LAYOUTS[k].aspect / r)))
    if frame is not None and box is not None:
        # one plate, its appearance learned: no entering-car births (they take the track to other
        # plate-like structure: dashcam from the first box, LIS-100 seeds 1-3, AUC 0.35 / 0.85 /
        # 0.48 with the births; docs/experiments.md)
        params = {"enter_weight": 0.0, "birth_reserve": 0.0, **params}
    model = Plate(size, layout=layout or "jp", **params)
    if box is not None:
        x, y, w, h = (float(v) for v in box)
        pose = np.array([x + w / 2, y + h / 2, 0.0, w])
        model.prior_mean = np.concatenate([pose, pose, [0.0]])
        model.start = (pose, np.array([0.05 * w, 0.05 * h, 0.03, 0.05 * w]))
        if frame is not None:
            from .detect import PlateDetector

            model.learn_appearance(frame, (x, y, w, h))
            model.detector = PlateDetector()  # the plate searched for again while it is not reported
    if angle_sigma is not None and params.get("sigma") is None:
        model.sigma[2] = float(angle_sigma)
    return model


def _summary(rows, truth, model):
    """``run``'s line against plate ground truth (vertices ``x0..y3``): the frames the plate was lost in (no
    plate reported, or the vertex error above a third of the plate height), the mean vertex error when
    tracked and the false reports."""
    if "x0" not in truth:
        return None
    rec = {"reported": [r["visible"] for r in rows],
           "vertices": [[r[f"{c}{i}"] for i in range(4) for c in "xy"] for r in rows]}
    has, err, lost, false = plate_frame_measures(rec, truth, model.layout.aspect)
    ok = has & ~lost
    mean = f"{np.nanmean(err[ok]):.2f} px" if ok.any() else "n/a (never tracked)"
    return (f"vs ground truth: plate lost in {int(lost.sum())} of {int(has.sum())} plate frames; mean vertex "
            f"error {mean} when tracked; {int(false.sum())} frames reported a plate where there was none")


SPEC = ModelSpec("plate", description="license-plate template (thesis 001 §1.3.2); acquires plates without a box",
                 from_box=_plate_from_frame_box, from_clip=_plate_from_clip, lost_rule="plate",
                 bytes_per_particle=48_000, model_class=Plate, targets_class=Plates, summary=_summary, options=(
                     ModelOption("targets", None, "track up to K plates at once, one slot each", flag="--targets"),
                     ModelOption("layout", "auto", "a layout's name (LAYOUTS); auto: from the clip, the box or the "
                                 "plate found", flag="--layout"),
                     ModelOption("appearance", "auto", "learn the plate's appearance from the start box (auto: on "
                                 "real footage)", flag="--no-colour", value=False)))
