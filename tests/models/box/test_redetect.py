"""The box model's whole-frame search, coarse to fine, every k-th lost frame (issue 53)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import vistrack
from box_helpers import BACK, GONE, reappearing_clip
from vistrack.models.box.model import Box


def _scene(seed=5, shape=(240, 320, 3)):
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.integers(70, 180, shape).astype(np.uint8), (0, 0), 3)


def _planted(bg, x, y):
    """``bg`` with an orange square with dark stripes (28 px) whose corner is at ``(x, y)``."""
    f = bg.copy()
    obj = np.zeros((28, 28, 3), np.uint8)
    obj[:] = (30, 120, 230)
    obj[::6] = 20
    f[y:y + 28, x:x + 28] = obj
    return f


@pytest.mark.parametrize("stride", [2, 4])
def test_coarse_to_fine_search_finds_a_planted_object(stride):
    bg = _scene()
    model = Box(_planted(bg, 40, 50), (40, 50, 28, 28), search_stride=stride)
    frame = _planted(np.roll(bg, (7, -11), axis=(0, 1)), 230, 170)  # the scene moved, the object far away
    coarse = model.cf.search(frame, 0.0, stride=stride, crop=model.search_crop, peaks=model.search_peaks)
    assert min(np.hypot(x - 244, y - 184) for x, y, _ in coarse) < 28  # a coarse place within the object's size
    found = model.candidates(frame)
    assert len(found) == model.search_peaks  # one scale: the last reported is the first frame's
    c, k = max((model.conf.candidate(model, o, p), -k) for k, (o, p, _) in enumerate(found))
    obs, pose, centre = found[-k]
    assert c >= model.threshold
    assert np.hypot(pose[0] - 244, pose[1] - 184) < 2.0  # the fine stage: within 2 px of the centre
    assert abs(pose[2]) < 0.05 and obs.scale is None  # the scale filter's response only for the one taken
    model.scale_response(frame, obs, centre)
    assert abs(obs.scale.peak_log_scale) < 0.1  # the same size, within three of its 17 scales (steps of 3 %)


def test_searches_every_kth_lost_frame():
    model = Box(_scene(), (40, 50, 28, 28), redetect_after=2, redetect_every=3)
    due = []
    for run in range(10):
        model._lost_run = run
        due.append(model.search_due())
    assert due == [False, False, True, False, False, True, False, False, True, False]
    with pytest.raises(ValueError, match="redetect_every must be an integer >= 1"):
        Box(_scene(), (40, 50, 28, 28), redetect_every=0)


def _track(frames, box, seed, **options):
    t = vistrack.Tracker(model="box", seed=seed, **options)
    t.init(frames[0], box)
    out = []
    for f in frames[1:]:
        ok, b = t.update(f)
        out.append((ok, t.box_estimate, t.confidence, t.result.redetected, t.lost_reason))
    return out


@pytest.mark.parametrize("every", [1, 3])
def test_found_again_and_the_same_seed_gives_the_same_track(every):
    frames, boxes = reappearing_clip()
    a = _track(frames, boxes[0], 5, redetect_every=every)
    assert a == _track(frames, boxes[0], 5, redetect_every=every)
    back = next(t for t in range(BACK, len(frames)) if a[t - 1][0])
    assert back <= BACK + every + 2 and a[back - 1][3]  # found by a search, within k + 2 frames of the return
    assert not any(r for _, _, _, r, _ in a[:GONE])
