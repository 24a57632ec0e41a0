"""The siam model's compiled kernels against their numpy paths (vistrack.models.siam.kernels), and its lost test
and re-detection on a synthetic clip."""

import numpy as np
import pytest

import vistrack
from vistrack import kernels
from vistrack.models.siam import kernels as K
from vistrack.models.siam.lost import psr, rival
from vistrack.models.siam.network import cell_points
from vistrack.models.siam.observation import SiamFrame, cell_boxes
from vistrack.models.siam.proposal import mixture_parts


def _response(rng, m=15):
    logit = rng.normal(0, 2, (m, m))
    logit[4, 9] = 9.0
    ltrb = rng.uniform(5, 60, (4, m, m)).astype(np.float32)
    return logit, ltrb


def test_cell_boxes_kernel_equals_the_numpy_path():
    rng = np.random.default_rng(0)
    _, ltrb = _response(rng)
    want = cell_boxes(ltrb, np.array([130.0, 90.0]), 1.7, np.array([30.0, 40.0]))
    got = K.cell_boxes_into(ltrb.astype(float), cell_points(15), 130.0, 90.0, 1.7, 30.0, 40.0, np.empty((225, 4)))
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


def test_the_mixture_and_the_map_cues_equal_the_numpy_paths():
    rng = np.random.default_rng(1)
    logit, ltrb = _response(rng)
    boxes = cell_boxes(ltrb, np.array([130.0, 90.0]), 1.7, np.array([30.0, 40.0]))

    def frame():
        return SiamFrame(np.zeros((8, 8, 3), np.uint8), np.array([130.0, 90.0]), 1.7, logit, boxes,
                         np.array([30.0, 40.0]))

    fast = mixture_parts(frame(), 8, 1.3, (0.08, 0.05))
    with kernels.numpy_paths():
        slow = mixture_parts(frame(), 8, 1.3, (0.08, 0.05))
    for a, b in zip(fast, slow):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)
    peak, sharp, lead = K.map_cues(logit, 2, 3, np.empty(3))
    assert peak == logit.max() and lead == pytest.approx(rival(logit), rel=1e-12)
    assert sharp == pytest.approx(psr(logit), rel=1e-9)


def _scene(x, y, seed=3, show=True):
    """A 240 x 180 frame of textured clutter with (``show``) a textured 30 x 30 object at (x, y)."""
    import cv2

    rng = np.random.default_rng(seed)
    bg = cv2.GaussianBlur(rng.integers(60, 200, (180, 240, 3)).astype(np.uint8), (0, 0), 2.0)
    obj = cv2.GaussianBlur(np.random.default_rng(99).integers(0, 255, (30, 30, 3)).astype(np.uint8), (0, 0), 1.0)
    obj[::6] = (20, 60, 220)
    if show:
        bg[int(y):int(y) + 30, int(x):int(x) + 30] = obj
    return bg


def test_the_pose_terms_and_the_cloud_statistics_equal_the_numpy_paths():
    from vistrack.appearance.features import FeatureMaps
    from vistrack.core.particles import ParticleSet
    from vistrack.models.siam.model import Siam

    model = Siam(_scene(100, 70), (100, 70, 30, 30), confidence=False)
    rng = np.random.default_rng(2)
    states = np.tile(np.r_[115.0, 85.0, 0.0, 0.0, 113.0, 86.0, 0.0, 0.0], (200, 1))
    states += rng.normal(0, [4, 4, 0.05, 0.05, 4, 4, 0.05, 0.05], states.shape)
    particles = ParticleSet(states, rng.normal(0, 1, 200))
    obs = model.observe(FeatureMaps(_scene(104, 69)), particles)
    pose = states[7]
    fast = model.pose_terms(obs, pose)
    with kernels.numpy_paths():
        slow = model.pose_terms(obs, pose)
    np.testing.assert_allclose(fast, slow, rtol=1e-12)
    w = particles.weights
    stats = K.cloud_stats(states, w, model.damping, np.empty(5))
    np.testing.assert_allclose(stats[:4], w @ model.predict_mean(states)[:, :4], rtol=1e-12)
    c = states[:, :2] - w @ states[:, :2]
    assert stats[4] == pytest.approx(np.sqrt(w @ np.einsum("ij,ij->i", c, c)), rel=1e-12)


def test_a_vanished_object_is_reported_lost_and_found_again_where_it_comes_back():
    """The object is tracked for 12 frames, hidden for 12, then shown 60 px away: the frames it is hidden are
    reported lost (all but at most the first two), and a search finds it back within 8 frames of its return."""
    frames = [_scene(60 + 2 * k, 60, show=True) for k in range(12)]
    frames += [_scene(0, 0, show=False) for _ in range(12)]
    frames += [_scene(150, 100, show=True) for _ in range(15)]
    t = vistrack.Tracker(model="siam", seed=1)
    t.init(frames[0], (60, 60, 30, 30))
    out = [(t.update(f)[0], t.result.redetected, t.box_estimate) for f in frames[1:]]
    visible = np.array([v for v, _, _ in out])
    assert visible[:11].all()  # frames 1..11: tracked
    assert not visible[13:23].any()  # frames 14..23: hidden, reported lost
    found = [k for k, (_, r, _) in enumerate(out) if r]
    assert found and 23 <= found[0] <= 31
    x, y, w, h = out[-1][2]
    assert abs(x + w / 2 - 165) < 6 and abs(y + h / 2 - 115) < 6
