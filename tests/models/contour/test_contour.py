"""Contour model (thesis 001 §1.3.1, §4.3.1): spline algebra, pose, likelihood, local search, tracking."""

import cv2
import numpy as np
import pytest

from vistrack.appearance.features import FeatureMaps
from vistrack.io.clips import load_clip
from vistrack.loop import Stepper
from vistrack.models.contour.model import BSpline, Contour, ellipse_template, pose_from, pose_params
from vistrack.registry import make_filter
from vistrack.registry.builders import build_model
from vistrack.scoring.metrics import center_error


def test_spline_interpolates_support_points_and_norm(rng):
    q = rng.normal(size=(9, 2))
    sp = BSpline(9)
    np.testing.assert_allclose(sp.curve_matrix(np.arange(9)) @ q, q, atol=1e-12)
    # closed: t and t + n give the same point
    np.testing.assert_allclose(sp.curve_matrix([0.3]) @ q, sp.curve_matrix([9.3]) @ q)
    # ||S||^2 = (1/L) ∫ |s(t)|^2 dt = q^T U q with U = diag(B, B) (§4.3.1)
    t = (np.arange(9000) + 0.5) / 1000
    pts = sp.curve_matrix(t) @ q
    direct = np.mean(np.sum(pts**2, axis=1))
    assert q[:, 0] @ sp.B @ q[:, 0] + q[:, 1] @ sp.B @ q[:, 1] == pytest.approx(direct, rel=1e-5)
    assert np.all(np.linalg.eigvalsh(sp.B) > 0)


def test_w_plus_recovers_pose_and_pose_roundtrip(rng):
    m = Contour(ellipse_template(40, 24), (0, 0, 0, 0), (320, 240))
    z = np.array([120.0, 80.0, 0.1, -0.2])
    q = m.support_points(z[None])[0]
    flat = np.concatenate([q[:, 0], q[:, 1]])
    np.testing.assert_allclose(m.W @ z + np.concatenate([m.q0[:, 0], m.q0[:, 1]]), flat)
    np.testing.assert_allclose(m.W_plus @ (flat - np.concatenate([m.q0[:, 0], m.q0[:, 1]])), z, atol=1e-9)
    s, a = pose_params(pose_from(10, 20, 1.3, -25.0))
    assert s == pytest.approx(1.3) and a == pytest.approx(-25.0)
    # normals are unit, outward, and turn with the pose
    nrm = m.normals(z[None])[0]
    np.testing.assert_allclose(np.linalg.norm(nrm, axis=1), 1.0)
    assert np.all(np.sum(nrm * (q - z[:2]), axis=1) > 0)


def disk_frame(cx=100.0, cy=70.0, r=25.0, size=(200, 150), clutter=True, seed=0):
    """A bright disk on a dark background with some line clutter."""
    g = np.random.default_rng(seed)
    img = np.full((size[1], size[0]), 60, np.uint8)
    if clutter:
        for _ in range(25):
            p = g.integers(0, size[0], 2), g.integers(0, size[1], 2)
            cv2.line(img, (int(p[0][0]), int(p[1][0])), (int(p[0][1]), int(p[1][1])), int(g.integers(80, 200)), 1)
    cv2.circle(img, (int(round(cx * 16)), int(round(cy * 16))), int(r * 16), 200, -1, cv2.LINE_AA, shift=4)
    return cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)


@pytest.mark.parametrize("polarity", [None, -1])
def test_likelihood_peaks_at_the_true_contour(polarity):
    frame = disk_frame()
    obs = FeatureMaps(frame)
    m = Contour(ellipse_template(50, 50), (100, 70, 0, 0), (200, 150), polarity=polarity)
    d = np.arange(-12, 13, 1.0)
    dx, dy = np.meshgrid(d, d)
    z = np.stack([100 + dx.ravel(), 70 + dy.ravel(), 0 * dx.ravel(), 0 * dx.ravel()], axis=1)
    ll = m.loglik(obs, np.concatenate([z, z], axis=1))
    best = z[np.argmax(ll)]
    assert np.hypot(best[0] - 100, best[1] - 70) <= 1.0
    # a dominant peak: 5 px off costs a lot of log-likelihood
    far = np.hypot(z[:, 0] - 100, z[:, 1] - 70) >= 5
    assert ll.max() - ll[far].max() > 10


def test_polarity_is_learnt_and_grid_likelihood_matches_exact():
    frame = disk_frame()
    obs = FeatureMaps(frame)
    m = Contour(ellipse_template(50, 50), (100, 70, 0, 0), (200, 150))
    assert m.learn_polarity(obs) == -1  # bright disk, dark outside: g · n_out < 0
    x = np.array([[104.0, 68.0, 0.0, 0.0] * 2])  # truth is on the grid: offset (-4, 2)
    offsets = np.stack(np.meshgrid(np.arange(-6, 7, 2.0), np.arange(-6, 7, 2.0)), -1).reshape(-1, 2)
    approx = m.loglik_local_grid(obs, x, offsets)[0]
    shifted = np.repeat(x, len(offsets), axis=0)
    shifted[:, :2] += offsets
    exact = m.loglik(obs, shifted)
    assert np.argmax(approx) == np.argmax(exact)
    np.testing.assert_allclose(offsets[np.argmax(approx)], [-4, 2])
    assert np.corrcoef(approx, exact)[0, 1] > 0.9


def test_local_search_moves_towards_the_edges(rng):
    """LS_λ (§4.3.1) brings perturbed predictions back, and never lowers r when checked."""
    frame = disk_frame()
    obs = FeatureMaps(frame)
    m = Contour(ellipse_template(50, 50), (100, 70, 0, 0), (200, 150))
    m.learn_polarity(obs)
    m.search_check = True  # the guarantee r(LS(x)) >= r(x) is checked exactly
    z = np.array([100.0, 70.0, 0.0, 0.0]) + np.c_[rng.normal(0, 3, (40, 2)), rng.normal(0, 0.03, (40, 2))]
    x = np.concatenate([z, z], axis=1)
    out, ll = m.local_search(obs, x)
    before = np.hypot(x[:, 0] - 100, x[:, 1] - 70)
    after = np.hypot(out[:, 0] - 100, out[:, 1] - 70)
    assert np.median(after) < 1.5 and np.mean(after) < np.mean(before) / 2
    assert np.all(ll >= m.loglik(obs, x) - 1e-9)
    np.testing.assert_allclose(ll, m.loglik(obs, out))
    np.testing.assert_array_equal(out[:, 4:], x[:, 4:])  # only z_t moves
    m.search_check = False  # unchecked: the moves as found, with their exact r
    out, ll = m.local_search(obs, x)
    np.testing.assert_allclose(ll, m.loglik(obs, out))


@pytest.fixture(scope="module")
def small_clip(synth_clip):
    return synth_clip("contour", frames=40, size=(160, 120), seed=4, clutter="low", distractor=False)


def test_synthetic_clip_files(small_clip):
    clip = load_clip(small_clip)
    t = clip.truth
    assert clip.meta["model"] == "contour" and clip.source.frame_count == 40
    assert len(t["frame"]) == 40 and np.all(t["visible"] == 1)
    # truth support points are the template at the recorded pose
    q0 = np.array(clip.meta["template"]["support_points"])
    m = Contour(q0, (0, 0, 0, 0), (160, 120))
    k = 17
    z = pose_from(t["cx"][k], t["cy"][k], t["scale"][k], t["angle_deg"][k])
    q = m.support_points(z[None])[0]
    np.testing.assert_allclose(q[:, 0], [t[f"qx{i}"][k] for i in range(len(q0))], atol=1e-2)
    np.testing.assert_allclose(q[:, 1], [t[f"qy{i}"][k] for i in range(len(q0))], atol=1e-2)


@pytest.mark.slow
@pytest.mark.parametrize("algo,n", [("bootstrap", 300), ("ls-n-ips", 20), ("lls", 20), ("lis", 20)])
def test_algorithms_track_a_synthetic_clip(small_clip, algo, n):
    clip = load_clip(small_clip)
    frames = list(clip.source)
    model = build_model("contour", clip, init_gt="")
    filt = make_filter(algo, model)
    t = clip.truth
    err = np.array([center_error(r.estimate[0], r.estimate[1], t["cx"][r.index], t["cy"][r.index])
                    for r in Stepper(filt, n, np.random.default_rng(1)).steps(frames)])
    assert err.max() < 10, err.round(1)
    assert err.mean() < 3.0


def test_same_seed_same_track(small_clip):
    clip = load_clip(small_clip)
    frames = list(clip.source)[:15]

    def run(seed):
        filt = make_filter("ls-n-ips", build_model("contour", clip, init_gt=""))
        return np.array([r.estimate for r in Stepper(filt, 20, np.random.default_rng(seed)).steps(frames)])

    np.testing.assert_array_equal(run(5), run(5))
    assert not np.array_equal(run(5), run(6))


def test_support_point_lms_step_with_spline_norm(rng):
    """The §4.3.1 LMS step (W⁺ with the spline norm U) recovers translation and scale."""
    obs = FeatureMaps(disk_frame(clutter=False))
    m = Contour(ellipse_template(50, 50), (100, 70, 0, 0), (200, 150))
    z = np.c_[100 + rng.normal(0, 3, (30, 1)), 70 + rng.normal(0, 3, (30, 1)), rng.normal(0, 0.05, (30, 1)),
              np.zeros((30, 1))]
    out = np.concatenate([z, z], axis=1)
    for _ in range(3):  # normals see only the normal component: each step takes about half
        out = m.lms_step(obs, out)
    assert np.mean(np.hypot(out[:, 0] - 100, out[:, 1] - 70)) < np.mean(np.hypot(z[:, 0] - 100, z[:, 1] - 70)) / 3
    assert np.mean(np.abs(out[:, 2])) < 0.03  # radius within ~0.75 px (edge sampling bias)
