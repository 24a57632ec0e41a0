"""The box model's calibrated confidence, honest visibility and the long-term scores (issue 44)."""

import json

import numpy as np
import pytest

import vistrack
from cli_helpers import run
from clip_helpers import BOX, vanishing_frames
from vistrack.io.clips import read_groundtruth_csv
from vistrack.models.box.confidence import FEATURES, MONOTONE, Calibration, apce, psr
from vistrack.scoring.long_term_scores import lt_pooled
from vistrack.scoring.metrics import lt_scores, reported_ious

NOISE = 16  # frames of pure noise follow the object's frames from here


def _response(width, rng):
    """A 41 x 41 response: a Gaussian peak of ``width`` cells at the middle over the same small noise."""
    yy, xx = np.mgrid[-20:21, -20:21]
    return np.exp(-(xx**2 + yy**2) / (2 * width**2)) + 0.05 * rng.standard_normal((41, 41))


def test_a_sharper_response_or_a_closer_appearance_never_lowers_the_confidence():
    cal = Calibration.load()
    assert all(cal.coef[cal.names.index(n)] >= 0 for n in MONOTONE if n in cal.names)
    base = np.array(cal.mean.tolist())  # the shipped calibration's mean cues, in its order
    x0 = np.zeros(len(FEATURES))
    x0[cal.index()] = base
    # sharpness: narrower peaks over the same noise give a larger APCE and PSR, and the confidence follows
    widths = (8.0, 5.0, 3.0, 2.0, 1.0)
    sharp = [(np.log(apce(_response(w, np.random.default_rng(0)))), psr(_response(w, np.random.default_rng(0))))
             for w in widths]
    assert all(a2 > a1 and p2 > p1 for (a1, p1), (a2, p2) in zip(sharp, sharp[1:]))
    for name in MONOTONE:
        steps = np.linspace(-3, 3, 13)
        xs = np.repeat(x0[None], len(steps), axis=0)
        xs[:, FEATURES.index(name)] += steps
        if name in ("apce", "psr"):  # the cues of the responses above
            xs[:5, FEATURES.index(name)] = [s[0 if name == "apce" else 1] for s in sharp]
            xs = xs[:5]
        c = cal(xs)
        assert np.all(np.diff(c) >= 0), name
    assert 0.0 <= cal(x0) <= 1.0


def _noise_after_object(n=NOISE + 10):
    frames = vanishing_frames(n=NOISE, gone=NOISE)
    rng = np.random.default_rng(5)
    return frames + [rng.integers(0, 256, frames[0].shape).astype(np.uint8) for _ in range(n - NOISE)]


def test_pure_noise_after_a_tracked_object_is_reported_lost_within_5_frames():
    frames = _noise_after_object()
    t = vistrack.Tracker(seed=3)
    t.init(frames[0], BOX)
    seen = [t.update(f)[0] for f in frames[1:]]
    conf = t.confidence
    assert all(seen[:NOISE - 1]), seen  # tracked while the object is there
    lost = [k + 1 for k, ok in enumerate(seen) if not ok]
    assert lost and NOISE <= lost[0] <= NOISE + 4, lost
    assert conf is not None and 0.0 <= conf <= 1.0
    assert t.lost_reason in ("low-confidence", "collapse", "out-of-frame")


def test_same_seed_same_track_and_confidences():
    frames = _noise_after_object(NOISE + 4)

    def once():
        t = vistrack.Tracker(seed=11)
        t.init(frames[0], BOX)
        out = []
        for f in frames[1:]:
            ok, _ = t.update(f)
            out.append((*t.box_estimate, ok, t.confidence, t.lost_reason))
        return out

    a, b = once(), once()
    assert a == b
    assert all(row[-2] is not None for row in a)


def test_long_term_scores_equal_hand_computed_values():
    # 6 frames: the object present on frames 0-3, absent (0,0,0,0) on 4-5
    truth = np.array([[0, 0, 10, 10]] * 4 + [[0, 0, 0, 0]] * 2, float)
    boxes = np.array([[0, 0, 10, 10],   # IoU 1
                      [5, 0, 10, 10],   # IoU 50 / 150 = 1/3
                      [0, 0, 10, 5],    # IoU 1/2
                      [20, 20, 5, 5],   # IoU 0
                      [0, 0, 10, 10],   # absent: 0 where predicted
                      [0, 0, 10, 10]], float)
    visible = np.array([1, 1, 0, 1, 1, 0], bool)
    np.testing.assert_allclose(reported_ious(boxes, truth, visible), [1, 1 / 3, 0, 0, 0, 0])
    # at the tracker's own threshold: predicted frames 0, 1, 3, 4: Pr = (1 + 1/3 + 0 + 0) / 4 = 1/3,
    # Re = (1 + 1/3) / 4 = 1/3, F = 1/3
    own = lt_scores(boxes, truth, visible)
    assert own["precision"] == pytest.approx(1 / 3) and own["recall"] == pytest.approx(1 / 3)
    assert own["f_score"] == pytest.approx(1 / 3) and np.isnan(own["threshold"])
    # with a confidence: thresholds from the confidences; F is highest at τ = 0.8 (frames 0, 1, 2 predicted:
    # Pr = (1 + 1/3 + 1/2) / 3 = 11/18, Re = (11/6) / 4 = 11/24, F = 2 Pr Re / (Pr + Re) = 11/21)
    conf = np.array([0.9, 0.85, 0.8, 0.3, 0.2, 0.1])
    lt = lt_scores(boxes, truth, visible, conf)
    assert lt["threshold"] == pytest.approx(0.8)
    assert lt["precision"] == pytest.approx(11 / 18) and lt["recall"] == pytest.approx(11 / 24)
    assert lt["f_score"] == pytest.approx(11 / 21)
    # two runs of one sequence: their curves averaged (own threshold: Pr (1/3 + 1) / 2, Re (1/3 + 1/4) / 2)
    perfect = np.array([1, 0, 0, 0, 0, 0], bool)
    pooled = lt_pooled([("s", np.nan_to_num(np.array([1, 1 / 3, 0.5, 0, 0, 0])), truth[:, 2] > 0, v, None)
                        for v in (visible, perfect)])
    pr, re = (1 / 3 + 1) / 2, (1 / 3 + 1 / 4) / 2
    assert pooled["precision"] == pytest.approx(pr) and pooled["recall"] == pytest.approx(re)
    assert pooled["f_score"] == pytest.approx(2 * pr * re / (pr + re))


@pytest.mark.slow
def test_synth_longterm_marks_the_absent_frames(tmp_path):
    out = tmp_path / "lt"
    code, _, err = run(["synth", "longterm", "--out", out, "--size", "160x120", "--seed", "2", "--gap", "0.3", "-q"])
    assert code == 0, err
    t = read_groundtruth_csv(out / "groundtruth.csv")
    meta = json.loads((out / "meta.json").read_text())
    absent = np.zeros(len(t["frame"]), bool)
    for first, last in meta["absent"]:
        absent[first:last + 1] = True
    assert len(meta["absent"]) == 2 and absent.sum() >= 2 * 9  # two absences of 0.3 s at 30 frames/s
    assert np.all(t["visible"][absent] == 0) and np.all(t["visible"][~absent] == 1)
    assert np.all(np.column_stack([t["cx"], t["cy"], t["w"], t["h"]])[absent] == 0)
    assert np.all(t["w"][~absent] > 0)


def test_the_calibration_ships_with_the_installed_package():
    """The box model's calibration is package data: without it an installed vistrack tracks without a
    confidence (no frame reported low-confidence) and its tracks differ from a clone's."""
    from importlib.resources import files

    from vistrack.models.box.confidence import CALIBRATION

    assert files("vistrack.models.box").joinpath("confidence.npz").is_file()
    cal = Calibration.load(CALIBRATION)
    assert 0 < cal.threshold < 1
