"""The box model's compiled filter step (vistrack.models.box.kernels) against the numpy paths it replaces.

Tolerances: the prediction, the transition density, the proposal map's scores, the map proposal's
draws (``z``, ``log alpha``, ``log q``, and the generator left in the same state) and the collapse
level are equal bit for bit on this machine (the C library's ``exp``/``log`` in both; 1e-12
relative is asserted where numpy may use its own SIMD ``exp``/``log``); the likelihood sums the
template correlation in sample order (1e-12 relative). Tracks: the same seed gives the same track
bit for bit, and the kernels' track is the numpy path's within 1e-9 px over 20 frames.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import vistrack
import vistrack.appearance.cues
from box_helpers import moving_box_frames
from kernel_helpers import both
from vistrack import kernels
from vistrack.appearance.features import FeatureMaps
from vistrack.core.particles import ParticleSet
from vistrack.models.collapse import CollapseWatch

pytestmark = pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")



@pytest.fixture(scope="module")
def tracked():
    """A box tracker after 8 frames (kernels on), with the next frame's observation."""
    frames, box = moving_box_frames(10)
    t = vistrack.Tracker(model="box", particles=60, seed=1, dcf=False)  # the map proposal
    t.init(frames[0], box)
    for f in frames[1:8]:
        t.update(f)
    return t, t.model.observe(FeatureMaps(frames[8]), t.particles)


@pytest.mark.slow
def test_prediction_and_transition_density_equal_the_numpy_path(tracked):
    t, _ = tracked
    model, prev = t.model, t.particles.states
    a, b = both(lambda: model.predict(prev, np.random.default_rng(5)))
    np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)
    x = a
    a, b = both(lambda: model.transition_logpdf(x, prev))
    np.testing.assert_allclose(b, a, rtol=1e-12)


def test_box_loglik_equals_the_numpy_path(tracked):
    t, obs = tracked
    x = t.model.predict(t.particles.states, np.random.default_rng(2))
    x[0, :2] = (1.0, 2.0)  # a box over the region's border
    a, b = both(lambda: t.model.loglik(obs, x))
    np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)


def test_map_proposal_draws_equal_the_numpy_path(tracked):
    t, obs = tracked
    prop = t._stepper.filt.proposal
    x = t.model.predict(t.particles.states, np.random.default_rng(3))

    def draw():
        obs.proposal = None  # the map is made afresh on each path
        rng = np.random.default_rng(4)
        z, log_alpha, log_q = prop.sample(x, obs, rng)
        return z, log_alpha, log_q, rng.random()

    a, b = both(draw)
    for u, v in zip(a, b):
        np.testing.assert_allclose(v, u, rtol=1e-12, atol=1e-12)
    assert a[3] == b[3]  # the same draws consumed


def test_region_of_interest_equals_the_numpy_path(tracked):
    t, _ = tracked
    frames, _ = moving_box_frames(10)
    a, b = both(lambda: t.model.observe(FeatureMaps(frames[8]), t.particles).roi)
    assert a == b and a != (0, 0, 160, 120)  # a part of the frame


def test_frame_features_equal_the_numpy_path():
    frames, box = moving_box_frames(1)
    app = vistrack.appearance.cues.Appearance(frames[0], box)
    for roi in ((0, 0, 160, 120), (37, 21, 90, 70), (5, 5, 6, 9), (3, 3, 10, 4)):
        a, b = both(lambda: app.frame(frames[0], roi))
        for name in ("texture", "labels", "ii"):
            np.testing.assert_array_equal(getattr(b, name), getattr(a, name), err_msg=f"{name} of {roi}")


def test_adaptation_equals_the_numpy_path(tracked):
    t, obs = tracked
    app, box = t.model.app, t.model.boxes(t.particles.mean())[0]
    saved = app.template.copy(), app.colour.q.copy()

    def adapt():
        app.template, app.colour.q = saved[0].copy(), saved[1].copy()
        return app.adapt(obs, box), app.template.copy(), app.colour.q.copy()

    a, b = both(adapt)
    assert a[0] and b[0]  # a confident frame: both adapt
    np.testing.assert_allclose(b[1], a[1], rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(b[2], a[2], rtol=1e-12, atol=1e-15)
    app.adapt_min_ncc = 2.0  # above any correlation: neither adapts
    a, b = both(adapt)
    app.adapt_min_ncc = 0.6
    assert not a[0] and not b[0]
    np.testing.assert_array_equal(b[1], saved[0])


def test_fused_lis_step_equals_the_calls_one_by_one(tracked):
    t, obs = tracked
    filt, model = t._stepper.filt, t.model
    kernel, prev = filt.kernel, t.particles.states
    prop = filt.part("proposal", kernel)
    obs.proposal = None
    rng = np.random.default_rng(7)
    z, log_incr, x, ll = prop.propose(prev, obs, rng, kernel)
    left = rng.random()
    obs.proposal, rng = None, np.random.default_rng(7)
    x2 = kernel.predict(prev, rng)
    z2, log_alpha, log_q = prop.sample(x2, obs, rng)
    ll2 = model.loglik(obs, z2)
    incr2 = log_alpha + ll2 - log_q + kernel.logpdf(z2, prev) - kernel.logpdf(x2, prev)
    assert rng.random() == left  # the same draws consumed
    np.testing.assert_array_equal(x, x2)
    np.testing.assert_allclose(z, z2, rtol=1e-14, atol=1e-12)
    np.testing.assert_allclose(ll, ll2, rtol=1e-12)
    np.testing.assert_allclose(log_incr, incr2, rtol=1e-12, atol=1e-9)
    assert prop.propose(prev, obs, rng, filt.prior_kernel) is None  # the first step: the calls one by one


def test_proposal_map_scores_equal_the_numpy_path(tracked):
    t, obs = tracked
    app = t.model.app
    a, b = both(lambda: app.proposal_map(obs, 31.0, 37.0))
    np.testing.assert_array_equal(b[0], a[0])
    assert b[1:] == a[1:]


@pytest.mark.slow
def test_box_tracks_with_kernels_are_the_numpy_paths_and_repeat():
    frames, box = moving_box_frames(20)

    def run():
        t = vistrack.Tracker(model="box", particles=50, seed=3)
        t.init(frames[0], box)
        return np.array([t.update(f) and t.box_estimate for f in frames[1:]])

    a, b = both(run)
    np.testing.assert_allclose(b, a, atol=1e-9)
    np.testing.assert_array_equal(run(), b)  # the same seed, the same track


def test_collapse_level_is_the_median():
    rng = np.random.default_rng(0)
    for n in (1, 2, 7, 30):
        w = CollapseWatch(window=30)
        w.history.extend(rng.normal(0, 40, n).tolist())
        assert w.level == float(np.median(w.history))


def test_weights_are_computed_once_per_log_weights():
    p = ParticleSet(np.zeros((4, 2)), np.log([1.0, 2.0, 3.0, 4.0]))
    w = p.weights
    assert p.weights is w and not w.flags.writeable
    np.testing.assert_allclose(w, [0.1, 0.2, 0.3, 0.4])
    p.log_weights = np.zeros(4)
    np.testing.assert_array_equal(p.weights, np.full(4, 0.25))


def test_area_shrink_equals_opencv():
    import cv2

    from vistrack.appearance.cues import shrink

    rng = np.random.default_rng(21)
    for _ in range(80):
        h, w = rng.integers(1, 300, 2) if _ < 60 else rng.integers(1, 8, 2)
        img = rng.integers(0, 256, (h, w, 3)).astype(np.uint8)
        if rng.random() < 0.5:
            img = cv2.GaussianBlur(img, (0, 0), 1.0)
        f = float(rng.uniform(0.1, 0.99))
        if round(h * f) < 1 or round(w * f) < 1:
            continue
        want = cv2.resize(img, None, fx=f, fy=f, interpolation=cv2.INTER_AREA)
        a, b = both(lambda: shrink(img, f))
        np.testing.assert_array_equal(a, want)
        np.testing.assert_array_equal(b, want)


def test_area_shrink_of_a_window_equals_that_part_of_the_whole():
    from vistrack.appearance.frame_kernels import shrink_area

    rng = np.random.default_rng(22)
    frame = cv2.GaussianBlur(rng.integers(0, 256, (200, 260, 3)).astype(np.uint8), (0, 0), 1.5)
    for _ in range(40):
        y0, x0 = rng.integers(0, 60, 2)
        src = frame[y0:y0 + rng.integers(20, 140), x0:x0 + rng.integers(20, 200)]  # a view, as a region is
        f = float(rng.uniform(0.2, 0.95))
        dh, dw = round(src.shape[0] * f), round(src.shape[1] * f)
        if abs(1 / f - round(1 / f)) < 1e-6 or min(dh, dw) < 1:
            continue
        want = cv2.resize(np.ascontiguousarray(src), None, fx=f, fy=f, interpolation=cv2.INTER_AREA)
        r0, c0 = rng.integers(0, dh), rng.integers(0, dw)
        r1, c1 = rng.integers(r0, dh + 1), rng.integers(c0, dw + 1)
        out = np.full((dh, dw, 3), 7, np.uint8)
        shrink_area(src, f, out, r0, r1, c0, c1)
        np.testing.assert_array_equal(out[r0:r1, c0:c1], want[r0:r1, c0:c1])
        outside = np.ones((dh, dw), bool)
        outside[r0:r1, c0:c1] = False
        assert (out[outside] == 7).all()  # the rest left as it was


def test_maps_made_over_a_window_equal_the_whole_regions():
    """The compiled maps made only where boxes read them (``AppearanceFrame.maps``): inside the window the
    texture and labels are the whole region's, every box inside counts what it counts there, and the
    likelihood of particles (some over the region's edge) is the same bit for bit."""
    from vistrack.appearance.features import box_sums

    frames, box = moving_box_frames(2)
    app = vistrack.appearance.cues.Appearance(frames[0], box, work_size=20.0)  # f < 1: a shrunk region
    roi = (10, 8, 150, 112)
    whole = app.frame(frames[1], roi)
    whole.texture  # noqa: B018 - made whole at once
    rng = np.random.default_rng(3)
    for _ in range(25):
        part = app.frame(frames[1], roi)
        hh, ww = part.shape
        r0, c0 = rng.integers(0, hh - 1), rng.integers(0, ww - 1)
        r1, c1 = rng.integers(r0 + 1, hh + 1), rng.integers(c0 + 1, ww + 1)
        texture, ii = part.maps((r0, r1, c0, c1))
        np.testing.assert_array_equal(texture[r0:r1, c0:c1], whole.texture[r0:r1, c0:c1])
        xs, ys = np.sort(rng.integers(c0, c1 + 1, (20, 2)), axis=1), np.sort(rng.integers(r0, r1 + 1, (20, 2)), axis=1)
        np.testing.assert_array_equal(box_sums(ii, xs[:, 0], ys[:, 0], xs[:, 1], ys[:, 1]),
                                      box_sums(whole.ii, xs[:, 0], ys[:, 0], xs[:, 1], ys[:, 1]))
    states = np.column_stack([rng.uniform(0, 160, 50), rng.uniform(0, 120, 50), rng.normal(0, 0.3, 50)])
    want = app.loglik_states(whole, states, app.size)
    lazy = app.frame(frames[1], roi)
    np.testing.assert_array_equal(app.loglik_states(lazy, states[:5], app.size), want[:5])  # a small window
    np.testing.assert_array_equal(app.loglik_states(lazy, states, app.size), want)  # grown to cover them all
    assert lazy.maps((0, 1, 0, 1))[1].shape == whole.ii.shape


def test_lent_maps_are_remade_after_the_next_frame_takes_them():
    """Two frames of one appearance share its map buffers (``MapBuffers``): the second frame's maps take them
    from the first, whose likelihood is then made afresh, not read from the second frame's maps."""
    frames, box = moving_box_frames(3)
    app = vistrack.appearance.cues.Appearance(frames[0], box, work_size=20.0)
    states = np.array([[60.0, 40.0, 0.0], [66.0, 44.0, 0.1]])
    want = [app.loglik_states(app.frame(f, (0, 0, 160, 120)), states, app.size) for f in frames[1:]]
    a = app.frame(frames[1], (0, 0, 160, 120))
    b = app.frame(frames[2], (0, 0, 160, 120))
    np.testing.assert_array_equal(app.loglik_states(a, states, app.size), want[0])
    np.testing.assert_array_equal(app.loglik_states(b, states, app.size), want[1])  # b takes a's buffers
    np.testing.assert_array_equal(app.loglik_states(a, states, app.size), want[0])  # a remakes its own
    kept = b.texture  # read whole: b keeps its arrays, the next frame gets new ones
    c = app.frame(frames[1], (0, 0, 160, 120))
    np.testing.assert_array_equal(app.loglik_states(c, states, app.size), want[0])
    assert not np.shares_memory(c.maps()[0], kept)


def test_window_of_boxes_known_answers():
    """``AppearanceFrame.window``: a box's working rows and columns (with its ring and two pixels to spare),
    the union of several, and the whole region for a box that is not finite."""
    frames, box = moving_box_frames(1)
    app = vistrack.appearance.cues.Appearance(frames[0], box, work_size=20.0)
    obs = app.frame(frames[0], (10, 20, 150, 110))
    f, (hh, ww) = obs.f, obs.shape
    cx, cy, w, h = 60.0, 50.0, 20.0, 10.0
    u0, u1 = (cx - w / 2 - 10 - 3 * 4.5) * f, (cx + w / 2 - 10 + 3 * 4.5) * f  # ring 0.3: 4.5 px a side
    v0, v1 = (cy - h / 2 - 20 - 3 * 4.5) * f, (cy + h / 2 - 20 + 3 * 4.5) * f
    want = (int(np.floor(v0)) - 2, int(np.ceil(v1)) + 2, int(np.floor(u0)) - 2, int(np.ceil(u1)) + 2)
    boxes = np.array([[cx, cy, w, h]])
    assert obs.window(boxes, 0.3 * 3) == want  # grown by 0.9 (w + h) / 2 = 13.5 = 3 x 4.5 px
    right = int(np.ceil((cx + 30 + w / 2 - 10 + 3 * 4.5) * f)) + 2  # the union's right edge: the second box's
    assert obs.window(np.array([[cx, cy, w, h], [cx + 30, cy, w, h]]), 0.9) == want[:3] + (right,)
    assert obs.window(np.array([[np.nan, cy, w, h]])) == (0, hh, 0, ww)
    assert obs.window(np.array([[-500.0, cy, w, h]]))[2] == -1  # left of the region: clipped there
    states = np.array([[cx, cy, 0.0]])
    assert obs.states_window(states, (w, h), 0.9) == want
