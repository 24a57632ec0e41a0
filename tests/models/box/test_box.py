"""The box model for real footage: colour features, appearance likelihood, mean shift, LIS
proper weighting, the OpenCV-shaped ``vistrack.Tracker`` and ``vistrack run`` with a box."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import vistrack
from box_helpers import OBJ, H, W, background, clip_frames, draw_object, obj_box, path
from vistrack.appearance.cues import Appearance
from vistrack.appearance.features import bin_integrals, box_sums, colour_bins, is_grey, n_colour_bins
from vistrack.core.particles import logsumexp
from vistrack.models.box.model import Box


# -- colour features --------------------------------------------------------------------
def test_colour_bins_known_colours_and_grey_levels():
    img = np.zeros((2, 3, 3), np.uint8)
    img[0, 0] = (0, 0, 255)  # red: hue 0, full saturation
    img[0, 1] = (255, 0, 0)  # blue: hue 120 of 180
    img[0, 2] = (128, 128, 128)  # grey: achromatic, value 128
    img[1, :] = (10, 10, 10)  # black
    lab = colour_bins(img)
    assert lab[0, 0] == 0 * 3 + 2  # hue bin 0, top saturation bin
    assert lab[0, 1] == (120 * 8 // 180) * 3 + 2
    assert lab[0, 2] == 24 + 128 // 64
    assert (lab[1] == 24).all()
    assert lab.max() < n_colour_bins(False)
    g = colour_bins(np.array([[0, 15, 16, 255]], np.uint8), grey=True)
    assert g.tolist() == [[0, 0, 1, 15]]
    assert is_grey(np.dstack([g] * 3).astype(np.uint8)) and not is_grey(img)


def test_box_histograms_from_bin_integrals_equal_counting():
    rng = np.random.default_rng(1)
    lab = rng.integers(0, 28, (37, 53)).astype(np.uint8)
    ii = bin_integrals(lab, 28)
    x0, y0, x1, y1 = np.array([0, 5, 40]), np.array([0, 3, 30]), np.array([53, 17, 60]), np.array([37, 21, 36])
    h = box_sums(ii, x0, y0, x1, y1)
    for k in range(3):
        crop = lab[y0[k]:y1[k], x0[k]:x1[k]]
        assert h[k].tolist() == np.bincount(crop.ravel(), minlength=28).tolist()


# -- likelihood -------------------------------------------------------------------------
@pytest.mark.parametrize("grey", [False, True])
def test_appearance_peaks_at_the_true_box_and_colour_is_flat_without_the_target(grey):
    bg = background(np.random.default_rng(2), grey)
    frame = draw_object(bg, 150, 110)
    app = Appearance(frame, obj_box(150, 110), adapt_rate=0)
    later = draw_object(bg, 171, 97)  # the object moved
    obs = app.frame(later, (0, 0, W, H))
    cx, cy = np.meshgrid(np.arange(141, 201, 1.0), np.arange(67, 127, 1.0))
    boxes = np.stack([cx.ravel(), cy.ravel(), np.full(cx.size, OBJ[0]), np.full(cx.size, OBJ[1])], axis=1)
    ll = app.loglik(obs, boxes)
    best = boxes[np.argmax(ll)]
    assert abs(best[0] - 171) <= 1.5 and abs(best[1] - 97) <= 1.5
    # far from the object the colour term does not vary by more than a small share of its range
    far = np.stack([np.linspace(20, 60, 30), np.full(30, 200.0), np.full(30, OBJ[0]), np.full(30, OBJ[1])], 1)
    log_rc_far = app.terms(obs, far)[0]
    log_rc_near = app.terms(obs, boxes)[0]
    assert np.ptp(log_rc_far) < 0.15 * (log_rc_near.max() - log_rc_far.min())


def test_appearance_prefers_the_true_scale():
    bg = background(np.random.default_rng(3), False)
    frame = draw_object(bg, 150, 110)
    app = Appearance(frame, obj_box(150, 110), adapt_rate=0)
    obs = app.frame(frame, (0, 0, W, H))
    s = np.exp(np.linspace(-0.4, 0.4, 17))
    boxes = np.stack([np.full(17, 150.0), np.full(17, 110.0), OBJ[0] * s, OBJ[1] * s], axis=1)
    assert abs(np.log(s[np.argmax(app.loglik(obs, boxes))])) <= 0.06


def test_mean_shift_converges_to_the_centre_of_a_colour_blob():
    bg = background(np.random.default_rng(4), False)
    frame = bg.copy()
    cv2.circle(frame, (150, 100), 20, (30, 60, 220), -1)
    app = Appearance(frame, (130, 80, 40, 40), adapt_rate=0)
    obs = app.frame(frame, (0, 0, W, H))
    start = np.array([[141.0, 109.0, 40, 40], [160.0, 92.0, 40, 40], [150.0, 86.0, 40, 40]])
    c = app.mean_shift(obs, start, iterations=8)
    np.testing.assert_allclose(c, [[150.5, 100.5]] * 3, atol=1.5)


@pytest.mark.slow
def test_box_lis_weights_match_a_brute_force_posterior():
    """Proper weighting: one LIS step (the map proposal on a grid of translations) from a
    particle at rest, scale known; the mean weight is the evidence ∫ r K and the weighted mean
    of the centre the posterior mean, both also by brute force on a 0.25-px grid."""
    bg = background(np.random.default_rng(5), False)
    # a flatter likelihood and a narrower window than the defaults: the weights are heavy-tailed
    # (the map proposal is coarser than r; the wider the window, the more cells where q is far
    # below r K), and 6000 of them pin the evidence only for a flat r on a narrow window. Proper
    # weighting holds for any window; with the default 2.5 the estimate needs far more samples.
    model = Box(draw_object(bg, 150, 110), obj_box(150, 110), sigma_xy=0.1, sigma_scale=1e-9, adapt_rate=0, dcf=False,
                lambda_colour=10, lambda_template=6, window=1.5)
    frame = draw_object(bg, 153, 108)
    pose = np.array([150.0, 110.0, 0.0])
    n = 6000
    prev = np.tile(np.concatenate([pose, pose]), (n, 1))
    obs = model.observe(vistrack.appearance.features.FeatureMaps(frame), vistrack.ParticleSet(prev))
    rng = np.random.default_rng(0)
    x = model.predict(prev, rng)
    z, log_alpha, log_q = model.lis_proposal().sample(x, obs, rng, prev)
    lw = log_alpha + model.loglik(obs, z) - log_q + model.transition_logpdf(z, prev) \
        - model.transition_logpdf(x, prev)
    w = np.exp(lw - lw.max())
    sd = model.sigma[0]
    step = 0.25
    du, dv = np.meshgrid(np.arange(-6 * sd, 6 * sd, step), np.arange(-6 * sd, 6 * sd, step), indexing="ij")
    grid = np.tile(np.concatenate([pose, pose]), (du.size, 1))
    grid[:, 0] += du.ravel()
    grid[:, 1] += dv.ravel()
    # K on the centre only (the scale is known: it cancels in the weights)
    lp = model.loglik(obs, grid) - 0.5 * (du.ravel() ** 2 + dv.ravel() ** 2) / sd**2 - np.log(2 * np.pi * sd**2)
    assert logsumexp(lw) - np.log(n) == pytest.approx(logsumexp(lp) + 2 * np.log(step), abs=0.3)
    g = np.exp(lp - lp.max())
    np.testing.assert_allclose((w @ z[:, :2]) / w.sum(), (g @ grid[:, :2]) / g.sum(), atol=0.2)


# -- tracking ---------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.parametrize("algo", ["lis", "bootstrap", "ls-n-ips", "lls", "avpf"])
def test_tracker_follows_a_moving_coloured_object(algo):
    frames = clip_frames(40)
    t = vistrack.Tracker(model="box", algo=algo, particles=100, seed=0)
    assert t.init(frames[0], obj_box(*path(0)))
    err = []
    for k in range(1, len(frames)):
        ok, (x, y, w, h) = t.update(frames[k])
        err.append(np.hypot(x + w / 2 - (path(k)[0] + 0.5), y + h / 2 - (path(k)[1] + 0.5)))
    assert ok and t.particles.n == 100
    # the bootstrap, AVPF and LLS filters' 100 weights are nearly degenerate under the correlation filter's peaked
    # likelihood (ESS 1-5): with the colour ring's weight κ 0.5 (issue 34) they lag the object by up to 16 px
    # (a third of its width) for 2-3 frames on some seeds (AVPF: 13 px on seed 3 before issue 53, 11 on seed 0
    # after, its mean error over seeds 0-7 1.6 px both times); LIS, the default, stays within 8 px on this seed
    assert np.mean(err) < 3.0 and np.max(err) < (16.0 if algo in ("bootstrap", "lls", "avpf") else 8.0)


@pytest.mark.slow
def test_tracker_on_a_grey_video_and_same_seed_same_track():
    frames = clip_frames(30, grey=True)
    assert frames[0].ndim == 2

    def boxes(seed):
        t = vistrack.Tracker(seed=seed)
        t.init(frames[0], obj_box(*path(0)))
        return np.array([t.update(f)[1] for f in frames[1:]])

    a = boxes(3)
    np.testing.assert_array_equal(a, boxes(3))
    c = a[:, :2] + a[:, 2:] / 2
    truth = np.array([path(k) for k in range(1, 30)]) + 0.5
    assert np.mean(np.hypot(*(c - truth).T)) < 3.0


def test_tracker_bad_input_is_a_clear_error():
    frame = clip_frames(1)[0]
    with pytest.raises(ValueError, match="positive size"):
        vistrack.Tracker().init(frame, (10, 10, 0, 20))
    with pytest.raises(ValueError, match="finite"):
        vistrack.Tracker().init(frame, (np.nan, 10, 5, 20))
    with pytest.raises(ValueError, match="does not run on the box model"):
        vistrack.Tracker(model="box", algo="pf-eis")
    with pytest.raises(ValueError, match="unknown model"):
        vistrack.Tracker(model="nope")
    with pytest.raises(RuntimeError, match="init"):
        vistrack.Tracker().update(frame)


def write_video(path, frames):
    wr = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25, (W, H))
    for f in frames:
        wr.write(f)
    wr.release()


@pytest.mark.slow
def test_run_defaults_to_box_with_init_and_equals_the_python_api(tmp_path, capsys):
    from vistrack.cli import main
    from vistrack.io.clips import read_groundtruth_csv
    from vistrack.io.video import open_video

    video = tmp_path / "clip.avi"
    write_video(video, clip_frames(20))
    x, y, w, h = obj_box(*path(0))
    with pytest.raises(SystemExit) as e:
        main(["run", str(video), "--init", f"{x},{y},{w},{h}", "--seed", "4", "--track", str(tmp_path / "t.csv"),
              "-q"])
    assert e.value.code == 0
    track = read_groundtruth_csv(tmp_path / "t.csv")
    frames = [f for _, f in open_video(video)]  # decoded as run decodes them
    t = vistrack.Tracker(seed=4)
    t.init(frames[0], (x, y, w, h))
    api = [t.box_estimate] + [t.update(f) and t.box_estimate for f in frames[1:]]
    np.testing.assert_allclose(track["cx"], [b[0] + b[2] / 2 for b in api], atol=1e-3)
    np.testing.assert_allclose(track["w"], [b[2] for b in api], atol=1e-3)
    assert list(track)[:8] == ["frame", "visible", "cx", "cy", "w", "h", "angle_deg", "scale"]


@pytest.mark.parametrize("init, message", [("10,10,0,20", "positive"), (f"{W + 5},10,20,20", "outside")])
def test_run_box_bad_init_is_one_line(tmp_path, capsys, init, message):
    from vistrack.cli import main

    video = tmp_path / "clip.avi"
    write_video(video, clip_frames(2))
    with pytest.raises(SystemExit) as e:
        main(["run", str(video), "--init", init])
    assert e.value.code != 0
    err = capsys.readouterr().err
    assert err.startswith("Error:") and message in err and "Traceback" not in err


def test_run_box_on_a_one_frame_video(tmp_path, capsys):
    from vistrack.cli import main

    video = tmp_path / "one.avi"
    write_video(video, clip_frames(1))
    x, y, w, h = obj_box(*path(0))
    with pytest.raises(SystemExit) as e:
        main(["run", str(video), "--init", f"{x},{y},{w},{h}", "--track", str(tmp_path / "t.csv")])
    assert e.value.code == 0
    assert len((tmp_path / "t.csv").read_text().splitlines()) == 2


def test_working_image_places_content_where_to_work_reads_it():
    """A region whose size times ``f`` is not whole (301 px at f = 0.4: 120.4 -> 120 working px):
    a bright square's centroid in the working image is at ``to_work`` of its frame centre on both
    axes. Resizing to the rounded size put it 0.38 / 0.34 working px short (the dashcam plate's
    upward offset, ``docs/experiments.md``)."""
    from vistrack.appearance.cues import AppearanceFrame

    frame = np.full((310, 320, 3), 20, np.uint8)
    frame[250:260, 280:290] = 220
    obs = AppearanceFrame(frame, (0, 0, 301, 301), 0.4, False)
    assert obs.grey.shape == (120, 120)
    bright = obs.grey.astype(float) - 20
    rows, cols = np.mgrid[0:120, 0:120] + 0.5
    centroid = ((bright * cols).sum() / bright.sum(), (bright * rows).sum() / bright.sum())
    np.testing.assert_allclose(centroid, obs.to_work(285.0, 255.0), atol=0.02)


def test_appearance_interpolation_option():
    import cv2

    from vistrack.appearance.cues import Appearance

    frames = clip_frames(1)
    box = obj_box(*path(0))
    app = Appearance(frames[0], box, work_size=16.0, interpolation="linear")
    obs = app.frame(frames[0], (20, 30, 220, 190))
    want = cv2.resize(frames[0][30:190, 20:220], None, fx=app.f, fy=app.f, interpolation=cv2.INTER_LINEAR)
    np.testing.assert_array_equal(obs.image, want)
    with pytest.raises(ValueError, match="interpolation"):
        Appearance(frames[0], box, interpolation="cubic")
