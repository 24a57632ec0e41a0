"""Synthetic road clips (issue 6 groundwork): ground truth is where the plate is."""

import numpy as np
import pytest

from vistrack.cli import main
from vistrack.io.clips import load_clip
from vistrack.models.plate.layout import LAYOUTS, plate_vertices


@pytest.fixture(scope="module")
def road(tmp_path_factory):
    out = tmp_path_factory.mktemp("road")
    with pytest.raises(SystemExit) as e:
        main(["synth", "plate", "--out", str(out), "--frames", "60", "--size", "320x240", "--cars", "2",
              "--seed", "3", "-q"])
    assert e.value.code == 0
    return out


@pytest.mark.slow
def test_plate_truth_matches_the_rendered_plate(road):
    clip = load_clip(road)
    t = clip.truth
    assert clip.meta["model"] == "plate" and len(t["frame"]) == 60
    vis = np.flatnonzero(t["visible"] > 0)
    assert 10 < len(vis) < 60  # plates in view, and stretches without one
    assert np.all(np.isnan(t["cx"][t["visible"] == 0]))
    frames = dict(clip.source)
    lay = LAYOUTS["jp"]
    for k in vis[:: max(1, len(vis) // 5)]:
        pose = np.array([t["cx"][k], t["cy"][k], np.deg2rad(t["angle_deg"][k]), t["scale"][k]])
        v = plate_vertices(pose, lay.aspect)[0]
        np.testing.assert_allclose(v[:, 0], [t[f"x{i}"][k] for i in range(4)], atol=2e-3)
        # the white plate: bright inside (between the character rows), darker around
        gray = frames[k].mean(axis=2)
        inner = gray[int(pose[1] - 0.3 * pose[3] / lay.aspect), int(pose[0] - 0.3 * pose[3])]
        assert inner > 150


def test_synth_plate_bad_size(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        main(["synth", "plate", "--out", str(tmp_path / "p"), "--size", "100x80"])
    assert e.value.code != 0 and "too small" in capsys.readouterr().err


def test_plate_likelihood_has_a_narrow_dominant_peak_at_the_plate(road):
    """Fig. 1.6: over a (u, w) grid at the true angle and scale, the maximum of r is at the
    true plate, and poses 15 % of the plate width away are far less likely."""
    from vistrack.appearance.features import FeatureMaps
    from vistrack.models.plate.model import PlateLikelihood

    clip = load_clip(road)
    t = clip.truth
    frames = dict(clip.source)
    lik = PlateLikelihood("jp")
    vis = np.flatnonzero(t["visible"] > 0)
    for k in vis[[len(vis) // 4, len(vis) // 2, 3 * len(vis) // 4]]:
        obs = FeatureMaps(frames[k])
        s, th = t["scale"][k], np.deg2rad(t["angle_deg"][k])
        du, dw = np.meshgrid(np.arange(-40, 41, 1.0), np.arange(-30, 31, 1.0))
        poses = np.stack([t["cx"][k] + du.ravel(), t["cy"][k] + dw.ravel(), np.full(du.size, th),
                          np.full(du.size, s)], axis=1)
        ll = lik.loglik(obs, poses)
        dist = np.hypot(du.ravel(), dw.ravel())
        assert dist[np.argmax(ll)] <= 0.08 * s + 1.5
        assert ll.max() - ll[dist > 0.15 * s].max() > 1.0


@pytest.mark.slow
def test_plate_line_scans_read_the_terms_the_weight_uses(road):
    """The LIS scans of ``r^h`` and ``r^v`` (§4.5.2) sum the same features as ``terms`` — the
    extra pixel sets of a term included — so with the scans' point density equal to the full
    one they agree exactly; every feature is in exactly one term."""
    from vistrack.appearance.features import FeatureMaps
    from vistrack.models.plate.model import PlateLikelihood

    clip = load_clip(road)
    t = clip.truth
    k = int(np.flatnonzero(t["visible"] > 0)[0]) + 2
    obs = FeatureMaps(dict(clip.source)[k])
    lik = PlateLikelihood("jp", per_unit=12, scan_per_unit=12)
    assert sorted(np.concatenate(list(lik._terms.values())).tolist()) == list(range(len(lik.FEATURES)))
    assert {"h_edge_gx", "v_edge_gy"} <= set(lik.FEATURES)  # the learnt extra sets are in use
    pose = np.array([t["cx"][k], t["cy"][k], np.deg2rad(t["angle_deg"][k]), t["scale"][k]])
    x = pose + np.array([[0, 0, 0, 0], [6, -3, 0.02, 2], [-20, 9, 0, -4]])
    h, v, _ = lik.terms(obs, x)
    zero = np.zeros((3, 1, 2))
    np.testing.assert_allclose(lik.scan(obs, x, "h", zero)[:, 0], h, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(lik.scan(obs, x, "v", zero)[:, 0], v, rtol=1e-5, atol=1e-5)


def test_plate_scale_banded_weights_interpolate_in_log_s(road):
    """Scale-banded coefficients (``w_0`` at plate width ``s_0``, ``w_1`` at ``s_1``, linear in
    log s between them, constant outside): ``log r`` is the plain likelihood with ``w_0`` below
    ``s_0``, with ``w_1`` above ``s_1`` and the log-s mix of the two between — and it is the
    regression score of :func:`~vistrack.models.plate.fitting.design` with the fitted vector split by
    :func:`~vistrack.models.plate.fitting.split_weights`, so the fit and the filters agree."""
    from vistrack.appearance.features import FeatureMaps
    from vistrack.models.plate.fitting import design, feature_likelihood, split_weights
    from vistrack.models.plate.model import PlateLikelihood

    clip = load_clip(road)
    t = clip.truth
    k = int(np.flatnonzero(t["visible"] > 0)[5])
    obs = FeatureMaps(dict(clip.source)[k])
    names = feature_likelihood("jp").FEATURES
    rng = np.random.default_rng(4)
    s0, s1 = 30.0, 60.0
    wb, b = rng.normal(size=2 * len(names) + 1), -2.0  # the regression's vector on design's inputs
    (c0, c1), (b0, b1) = split_weights(wb, b, len(names), (s0, s1))
    weights = ({n: (c0[i], c1[i]) for i, n in enumerate(names)}, (b0, b1), (s0, s1))
    banded = PlateLikelihood("jp", weights=weights)
    lik0 = PlateLikelihood("jp", weights=(dict(zip(names, c0)), b0))
    lik1 = PlateLikelihood("jp", weights=(dict(zip(names, c1)), b1))
    pose = np.array([t["cx"][k], t["cy"][k], np.deg2rad(t["angle_deg"][k]), 0.0])
    x = np.tile(pose, (5, 1))
    x[:, 3] = [20.0, s0, 42.0, s1, 90.0]
    ll = banded.loglik(obs, x)
    l0, l1 = lik0.loglik(obs, x), lik1.loglik(obs, x)
    a = np.log(42.0 / s0) / np.log(s1 / s0)
    np.testing.assert_allclose(ll, [l0[0], l0[1], (1 - a) * l0[2] + a * l1[2], l1[3], l1[4]], rtol=1e-6, atol=1e-6)
    score = design(banded.features(obs, x), x[:, 3], (s0, s1)) @ wb + b
    np.testing.assert_allclose(ll, score, rtol=1e-6, atol=1e-6)
    # the proposal's scans and its sparse 2-D search read the same per-particle coefficients
    h, v, c = banded.terms(obs, x)
    np.testing.assert_allclose(h + v + c, ll, rtol=1e-6, atol=1e-6)
    sparse = PlateLikelihood("jp", weights=weights, scan_per_unit=24)  # the scans' points = the full ones
    np.testing.assert_allclose(sparse.loglik_sparse(obs, x, np.zeros((5, 1, 2)))[:, 0], ll, rtol=1e-5, atol=1e-5)


@pytest.fixture(scope="module")
def road640(tmp_path_factory):
    """One car at the evaluation suite's frame size (its plates are ~70 px wide, twice ``road``'s)."""
    out = tmp_path_factory.mktemp("road640")
    with pytest.raises(SystemExit) as e:
        main(["synth", "plate", "--out", str(out), "--frames", "50", "--cars", "1", "--seed", "5", "-q"])
    assert e.value.code == 0
    return out


@pytest.mark.slow
def test_plate_log_odds_separate_plates_from_clutter(road640):
    """The learnt log-odds at every plate wholly in view (its best within 2 px and 4 % of the true
    pose, where a tracker's estimate sits) is above every pose of a coarse-to-fine scan of a frame
    without a plate (signs, lane marks, grilles, headlights), and those stay below the report
    threshold: the likelihood's side of "no plate reported where there is none". (The best
    clutter pose here, on a sign above the road, scores 1.64 in a 1-px search. This clip's one
    car crosses the frame in 50 frames, 2.5 times the suite's speed, and its motion-blurred plate scores
    2.0–3.1, so the report threshold of 2.5 — chosen on the training clips, where a sign scores
    up to 2.5 — misses some of its frames; the suite's plates score below 2.5 in under 1 % of
    their frames.)"""
    from vistrack.appearance.features import FeatureMaps
    from vistrack.models.plate.fitting import scan_poses
    from vistrack.models.plate.model import Plate

    clip = load_clip(road640)
    t = clip.truth
    frames = dict(clip.source)
    model = Plate(clip.source.size)
    vis = np.flatnonzero(t["visible"] > 0)
    assert len(vis) >= 10
    # the first frame (before the car enters; the sign above the road scores highest there), scanned
    # coarse to fine: every upright pose on an 8-px grid at 9 widths, then a 1-px grid at 5 widths
    # around each of the 30 best. The fine search finds 1.64 where a dense 4-px scan found 0.87 (the
    # log-odds is sharp at the pixel scale), so the margin to the plates is 0.4, not the 1.9 the 4-px
    # scan suggested; both stay below the report threshold 2.5
    maps = FeatureMaps(frames[np.flatnonzero(t["visible"] == 0)[0]])
    coarse = scan_poses(clip.source.size, step=8)
    ll = model.lik.loglik(maps, coarse)
    d = np.stack(np.meshgrid(np.arange(-4.0, 5), np.arange(-4.0, 5), [0.9, 0.95, 1.0, 1.05, 1.1], indexing="ij"),
                 -1).reshape(-1, 3)
    fine = np.concatenate([np.column_stack([p[0] + d[:, 0], p[1] + d[:, 1], np.zeros(len(d)), p[3] * d[:, 2]])
                           for p in coarse[np.argsort(ll)[-30:]]])
    clutter = max(ll.max(), model.lik.loglik(maps, fine).max())
    assert clutter < model.visible_loglik
    d = np.stack(np.meshgrid([-2.0, 0, 2], [-2.0, 0, 2], [0.96, 1.0, 1.04], indexing="ij"), -1).reshape(-1, 3)
    plates = []
    for k in vis[2:-2]:  # wholly in view, not just touching the border
        pose = np.array([t["cx"][k], t["cy"][k], np.deg2rad(t["angle_deg"][k]), t["scale"][k]])
        near = np.column_stack([pose[0] + d[:, 0], pose[1] + d[:, 1], np.full(len(d), pose[2]), pose[3] * d[:, 2]])
        plates.append(model.lik.loglik(FeatureMaps(frames[k]), near).max())
    assert min(plates) > clutter


@pytest.mark.slow
@pytest.mark.parametrize("entering", [True, False])
def test_plate_lis_proposal_is_a_proper_density_on_the_window(entering):
    """§4.5.2 proposal q = q^h(W') q^v(U'|W') on its box window g: E_q[g / q(Z)] = 1 —
    q integrates to one on the box and log q is exact (the returned log q includes -log g).
    The box is twice the plate size for an entering particle, which also searches log s and θ, and
    3 sigma of the AR(2) noise for a tracked one. (A textured frame and the mild thesis weights keep the importance
    estimate's variance small.)"""
    import cv2

    from vistrack.appearance.features import FeatureMaps
    from vistrack.models.plate.model import Plate

    g = np.random.default_rng(1)
    img = cv2.GaussianBlur((g.random((240, 320)) * 255).astype(np.uint8), (0, 0), 2)
    obs = FeatureMaps(cv2.cvtColor(img, cv2.COLOR_GRAY2BGR))
    model = Plate((320, 240), kappa=0.5, weights="thesis")
    s = 50.0
    prev = (160.0, 120.0) if entering else (159.0, 119.0)
    x = np.array([[160.0, 120.0, 0.05, s, *prev, 0.05, s]])
    xs = np.repeat(x, 8000 if entering else 3000, axis=0)
    prop = type(model.lis_proposal())(model, cells=12)
    z, log_alpha, log_q = prop.sample(xs, obs, np.random.default_rng(0))
    assert np.all(log_alpha == 0)
    half = np.array([s, s / model.layout.aspect])
    if not entering:
        half = np.minimum(half, prop.window_sigmas * model.sigma[:2])
    # an entering particle also draws log s on ± span about X's; g's density of s_X is 1 / (2 span s_X),
    # so over Z the mean of g / q is ∫ ds_Z / (2 span s_X) = sinh(span) / span
    span = prop.scale_span if entering else 0.0
    # within 4 standard errors (the entering search's tempered draws, r², widen the spread), which
    # must themselves be small enough for the check to mean something
    ratio = np.exp(-log_q)
    se = ratio.std() / np.sqrt(len(ratio))
    assert se < 0.03
    assert np.mean(ratio) == pytest.approx(np.sinh(span) / span if span else 1.0, abs=4 * se)
    assert np.all(np.abs(z[:, 0] - 160) <= half[0] + 1e-9) and np.all(np.abs(z[:, 1] - 120) <= half[1] + 1e-9)
    # the angle and the scale move only for an entering particle, within their spans
    assert np.all(np.abs(z[:, 2] - xs[:, 2]) <= (prop.angle_span if entering else 0.0) + 1e-9)
    assert np.all(np.abs(np.log(z[:, 3] / s)) <= span + 1e-9)
    assert np.all(model.entering(z) == entering)


def test_plate_dynamics_entering_branch(rng):
    from vistrack.models.plate.model import Plate

    model = Plate((640, 480))
    prev = model.sample_prior(4000, rng)
    assert np.all(prev[:, 8] == 0)  # every prior draw is a new lineage
    prev[:, 4:8] -= 1.0  # moving plates
    prev[:, 8] = rng.integers(0, 9, len(prev))
    new = model.predict(prev, rng)
    born = model.entering(new)
    assert born.mean() == pytest.approx(0.1, abs=0.02)
    # the lineage age: 0 for a birth, one more than the parent's otherwise
    np.testing.assert_array_equal(new[:, 8], np.where(born, 0, prev[:, 8] + 1))
    lp = model.transition_logpdf(new, prev)
    assert np.all(np.isfinite(lp))
    moved = model.with_local(new, new[:, :2] + 5.0)
    np.testing.assert_array_equal(model.entering(moved), born)
    # the resampling reserve keeps the lineages younger than reserve_age frames
    from vistrack.core.particles import ParticleSet

    np.testing.assert_array_equal(model.reserved(ParticleSet(new)), new[:, 8] < model.reserve_age)
    assert model.reserved(ParticleSet(new)).any() and not model.reserved(ParticleSet(new)).all()


@pytest.mark.slow
def test_plate_entering_search_lands_births_on_the_plate(road640):
    """The entering particles' search (§4.5.2 scans inside a coarse cell, then the angle and the
    fine scale, a second scan, tempered draws) puts births on the plate far more often than
    the translation-and-coarse-scale search alone: births drawn about a plate (25 px, 12 px,
    0.1 rad, 20 % off) end within a third of the plate height (the 'not lost' tolerance) at
    least 1.5 times as often, and are never outside their window."""
    from vistrack.appearance.features import FeatureMaps
    from vistrack.models.plate.model import Plate, PlateLISProposal

    clip = load_clip(road640)
    t = clip.truth
    frames = dict(clip.source)
    model = Plate(clip.source.size)
    vis = np.flatnonzero(t["visible"] > 0)
    hits = {"search": 0, "coarse": 0}
    for k in vis[[len(vis) // 4, len(vis) // 2, 3 * len(vis) // 4]]:
        obs = FeatureMaps(frames[k])
        truth = np.array([t["cx"][k], t["cy"][k], np.deg2rad(t["angle_deg"][k]), t["scale"][k]])
        tv = np.array([[t[f"x{i}"][k], t[f"y{i}"][k]] for i in range(4)])
        g = np.random.default_rng(int(k))
        n = 600
        x = np.tile(np.r_[truth, truth, 0.0], (n, 1))
        x[:, :4] += g.normal(0, 1, (n, 4)) * [25, 12, 0.1, 0]
        x[:, 3] *= np.exp(0.2 * g.standard_normal(n))
        x[:, 4:8] = x[:, :4]
        for name, kw in (("search", {}),
                         ("coarse", dict(angle_cells=1, scale_fine=1, rescan=False, birth_beta=1.0))):
            prop = PlateLISProposal(model, **kw)
            z, _, log_q = prop.sample(x, obs, np.random.default_rng(1))
            assert np.all(np.isfinite(log_q)) and np.all(model.entering(z))
            err = np.linalg.norm(model.vertices(z) - tv, axis=2).sum(axis=1)
            hits[name] += int(np.sum(err < t["scale"][k] / model.layout.aspect / 3))
    assert hits["search"] >= 1.5 * hits["coarse"] and hits["search"] > 0.1 * 3 * 600, hits


@pytest.mark.slow
def test_plate_lls_grid_finds_the_plate_and_lls_tracks_it(road):
    """LLS's grid on plates (the sparse likelihood at shifted poses): from a pose 1/4 plate
    off, the grid's best cell is within a cell of the true plate; and LLS-100 started at the
    first true plate stays on it: over 4 seeds, the centre within half a plate width in at least
    85 % of the plate frames, and there the four vertices' errors add up to less than the plate
    height on average. (This clip's
    cars cross a 320-px frame in 15 frames, so its 35-px plates are motion-blurred and score
    log-odds 0.4–1.2, below the report threshold: births on road clutter scoring as much take
    the lead now and then — in 1 of 8 seeds with N = 100, 5 of 8 with N = 50.)"""
    from vistrack.appearance.features import FeatureMaps
    from vistrack.loop import Stepper
    from vistrack.models.plate.model import Plate
    from vistrack.registry import make_filter

    clip = load_clip(road)
    t = clip.truth
    frames = dict(clip.source)
    model = Plate(clip.source.size)
    win = model.lls_window()
    vis = np.flatnonzero(t["visible"] > 0)
    k = int(vis[len(vis) // 2])
    s = t["scale"][k]
    truth = np.array([t["cx"][k], t["cy"][k], np.deg2rad(t["angle_deg"][k]), s])
    x = np.concatenate([truth + [0.25 * s, -0.1 * s, 0, 0]] * 2)[None]
    ll = model.loglik_local_grid(FeatureMaps(frames[k]), x, win.offsets)
    assert ll.shape == (1, len(win.offsets))
    best = x[0, :2] + win.offsets[np.argmax(ll[0])]
    assert np.all(np.abs(best - truth[:2]) <= win.cell + 1e-9)
    # tracking from the first frame with a plate
    k0 = int(vis[0])
    model.start = (np.array([t["cx"][k0], t["cy"][k0], np.deg2rad(t["angle_deg"][k0]), t["scale"][k0]]),
                   np.array([2.0, 1.0, 0.01, 1.0]))
    filt = make_filter("lls", model)
    src = [(i, f) for i, f in clip.source if k0 <= i < k0 + 15]
    on, errs = [], []
    for seed in range(4):
        for res in Stepper(filt, 100, np.random.default_rng(seed)).steps(src):
            i = res.index
            if t["visible"][i] > 0:
                on.append(np.hypot(res.estimate[0] - t["cx"][i], res.estimate[1] - t["cy"][i]) < 0.5 * t["scale"][i])
                if on[-1]:
                    tv = np.array([[t[f"x{j}"][i], t[f"y{j}"][i]] for j in range(4)])
                    errs.append(np.linalg.norm(model.vertices(res.estimate)[0] - tv, axis=1).sum() / t["scale"][i]
                                * model.layout.aspect)
    assert len(on) >= 40 and np.mean(on) >= 0.85
    assert np.mean(errs) < 1.0


def test_plate_sharpness_scales_log_r_but_not_the_report(road):
    """``sharpness`` multiplies ``log r`` (the learnt log-odds) everywhere the filters read it —
    full, sparse and line-scan evaluations — while ``visible`` still thresholds the log-odds."""
    from vistrack.appearance.features import FeatureMaps
    from vistrack.models.plate.model import Plate

    clip = load_clip(road)
    t = clip.truth
    k = int(np.flatnonzero(t["visible"] > 0)[0]) + 3
    obs = FeatureMaps(dict(clip.source)[k])
    pose = np.array([t["cx"][k], t["cy"][k], np.deg2rad(t["angle_deg"][k]), t["scale"][k]])
    x = np.concatenate([pose, pose])[None] + np.array([[0, 0, 0, 0, 0, 0, 0, 0], [9, 4, 0, 0, 9, 4, 0, 0]])
    m1, m3 = Plate(clip.source.size), Plate(clip.source.size, sharpness=3.0)
    off = np.zeros((2, 3, 2))
    off[:, 1, 0], off[:, 2, 1] = 5.0, -3.0
    np.testing.assert_allclose(m3.loglik(obs, x), 3 * m1.loglik(obs, x), rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(m3.lik.loglik_sparse(obs, x, off), 3 * m1.lik.loglik_sparse(obs, x, off), rtol=1e-6,
                               atol=1e-9)
    np.testing.assert_allclose(m3.lik.scan(obs, x, "h", off), 3 * m1.lik.scan(obs, x, "h", off), rtol=1e-6, atol=1e-9)
    for row in x:
        assert m3.visible(obs, row) == m1.visible(obs, row)


def test_plate_estimate_is_the_main_mode_not_the_mean_of_two(rng):
    """A posterior split between a plate and a plate-like sign: the estimate is the weighted
    mean of the heavier cluster (within half a plate of the best particle), not a point between."""
    from vistrack.core.particles import ParticleSet
    from vistrack.models.plate.model import Plate

    model = Plate((640, 480))
    plate = np.array([300.0, 320.0, 0.0, 80.0])
    sign = np.array([500.0, 150.0, 0.0, 70.0])
    a = plate + rng.normal(0, [2, 1, 0.01, 2], (60, 4))
    b = sign + rng.normal(0, [2, 1, 0.01, 2], (40, 4))
    x = np.concatenate([np.hstack([a, a]), np.hstack([b, b])])
    logw = np.log(np.r_[np.full(60, 0.9 / 60), np.full(40, 0.1 / 40)])
    logw[0] += 0.5  # the best particle is in the plate cluster
    ps = ParticleSet(x, logw)
    est = model.estimate(ps)
    w = ps.weights[:60]
    np.testing.assert_allclose(est, (w @ x[:60]) / w.sum())
    assert np.hypot(*(est[:2] - plate[:2])) < 3 and np.hypot(*(ps.mean()[:2] - plate[:2])) > 15


def test_run_plate_clip_default_model_writes_vertices(road, tmp_path, capsys):
    import csv

    track = tmp_path / "t.csv"
    with pytest.raises(SystemExit) as e:
        main(["run", str(road / "video.mp4"), "--algo", "lis", "-n", "20", "--max-frames", "6", "--track", str(track),
              "-q"])
    assert e.value.code == 0, capsys.readouterr().err
    with open(track, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 6
    assert list(rows[0])[:8] == ["frame", "visible", "cx", "cy", "w", "h", "angle_deg", "scale"]
    assert {"x0", "y3", "ess", "ms"} <= set(rows[0]) and set(r["visible"] for r in rows) <= {"0", "1"}


@pytest.mark.slow
def test_plate_lis_weights_match_a_brute_force_posterior(road):
    """Proper weighting on a real frame: one LIS step from the entering-style start (the §4.5.2
    window twice the plate size, plus the search over log s) from a Gaussian prior on (u, w, s)
    about the plate, the angle known. The mean weight estimates the evidence ∫ r p0 and the
    weighted mean of (u, w, s) the posterior mean — both also computed by brute force on a grid."""
    from vistrack.appearance.features import FeatureMaps
    from vistrack.core.particles import logsumexp
    from vistrack.models.plate.model import Plate

    clip = load_clip(road)
    t = clip.truth
    vis = np.flatnonzero(t["visible"] > 0)
    k = int(vis[len(vis) // 2])
    obs = FeatureMaps(dict(clip.source)[k])
    model = Plate(clip.source.size)
    s = t["scale"][k]
    # the prior is broader than the window: the weights have finite variance
    su, sw, ss = 0.4 * s, 0.2 * s, 0.1 * s
    pose = np.array([t["cx"][k] + 0.05 * s, t["cy"][k] - 0.03 * s, np.deg2rad(t["angle_deg"][k]), 1.05 * s])
    model.start = (pose, np.array([su, sw, 1e-9, ss]))
    n = 6000
    rng = np.random.default_rng(0)
    x = model.sample_prior(n, rng)
    # the angle is known here (prior sd 1e-9): the search's angle cells are off. Untempered draws
    # (birth_beta=1): with r² the weights are heavy-tailed and 6000 of them do not pin the evidence
    # to 0.5 nats; log q is exact for any β (test_plate_lis_proposal_is_a_proper_density_on_the_window)
    z, log_alpha, log_q = type(model.lis_proposal())(model, angle_cells=1, birth_beta=1.0).sample(x, obs, rng)
    assert np.ptp(z[:, 3] - x[:, 3]) > 0.2 * s  # the scale is searched
    lw = log_alpha + model.loglik(obs, z) - log_q + model.prior_logpdf(z) - model.prior_logpdf(x)
    w = np.exp(lw - lw.max())
    evidence = logsumexp(lw) - np.log(n)
    steps = (1.0, 0.5, 0.25 * ss)
    # ±3 prior sds: the posterior's mass is the likelihood's, near the true pose (0.05 s away); the
    # prior beyond 3 sds holds < 1 % (and ±4 sds cost 2.4x the time)
    du, dw, ds = np.meshgrid(np.arange(-3 * su, 3 * su, steps[0]), np.arange(-3 * sw, 3 * sw, steps[1]),
                             np.arange(-3 * ss, 3 * ss, steps[2]), indexing="ij")
    grid = np.tile(pose, (du.size, 1))
    grid[:, 0] += du.ravel()
    grid[:, 1] += dw.ravel()
    grid[:, 3] += ds.ravel()
    ll = np.concatenate([model.loglik(obs, grid[i:i + 10000]) for i in range(0, len(grid), 10000)])
    lp = ll - 0.5 * ((du.ravel() / su) ** 2 + (dw.ravel() / sw) ** 2 + (ds.ravel() / ss) ** 2) \
        - np.log((2 * np.pi) ** 1.5 * su * sw * ss)
    g = np.exp(lp - lp.max())
    assert evidence == pytest.approx(logsumexp(lp) + np.log(np.prod(steps)), abs=0.5)
    cols = [0, 1, 3]
    mean = (g @ grid[:, cols]) / g.sum()
    sd = np.sqrt((g @ (grid[:, cols] - mean) ** 2) / g.sum())
    ess = w.sum() ** 2 / (w @ w)
    # the importance estimate's error is about sd / sqrt(ESS): 4 of those (ESS ~ 40 here)
    assert np.all(np.abs((w @ z[:, cols]) / w.sum() - mean) < 4 * sd / np.sqrt(ess))
    # and the plate, not clutter, dominates this posterior
    np.testing.assert_allclose((g @ grid[:, :2]) / g.sum(), [t["cx"][k], t["cy"][k]], atol=0.1 * s)


@pytest.mark.slow
def test_plate_lis_dynamics_window_weights_match_a_brute_force_posterior(road):
    """Proper weighting of the tracked-particle proposal (window = the AR(2) kernel's own (u, w)
    factors about the predicted mean): one LIS step from a particle that follows the plate, with
    the angle and scale known. The mean weight is the evidence ∫ r N_uw and the weighted mean of
    (u, w) the posterior mean, both also by brute force on a grid; the box window agrees too."""
    from vistrack.appearance.features import FeatureMaps
    from vistrack.core.particles import logsumexp
    from vistrack.models.plate.model import Plate, PlateLISProposal

    clip = load_clip(road)
    t = clip.truth
    vis = np.flatnonzero(t["visible"] > 0)
    k = int(vis[len(vis) // 2])
    obs = FeatureMaps(dict(clip.source)[k])
    s = t["scale"][k]
    model = Plate(clip.source.size, enter_weight=1e-300)  # no entering draws
    model.sigma = np.array([0.1 * s, 0.05 * s, 1e-9, 1e-9])
    pose = np.array([t["cx"][k] + 0.05 * s, t["cy"][k] - 0.03 * s, np.deg2rad(t["angle_deg"][k]), s])
    n = 6000
    prev = np.tile(np.concatenate([pose, pose]), (n, 1))  # at rest: the predicted mean is `pose`
    su, sw = model.sigma[:2]
    du, dw = np.meshgrid(np.arange(-6 * su, 6 * su, 0.25), np.arange(-6 * sw, 6 * sw, 0.25), indexing="ij")
    grid = np.tile(pose, (du.size, 1))
    grid[:, 0] += du.ravel()
    grid[:, 1] += dw.ravel()
    lp = model.loglik(obs, grid) - 0.5 * ((du.ravel() / su) ** 2 + (dw.ravel() / sw) ** 2) - np.log(2 * np.pi * su * sw)
    g = np.exp(lp - lp.max())
    evidence_grid = logsumexp(lp) + np.log(0.25 * 0.25)
    mean_grid = (g @ grid[:, :2]) / g.sum()
    ess = {}
    for window, tol_mean, tol_evidence in (("dynamics", 0.15, 0.1), ("box", 1.0, 0.5)):
        rng = np.random.default_rng(1)
        x = model.predict(prev, rng)
        assert not model.entering(x).any()
        z, log_alpha, log_q = PlateLISProposal(model, window=window).sample(x, obs, rng, prev)
        lw = log_alpha + model.loglik(obs, z) - log_q
        lw += model.transition_logpdf(z, prev) - model.transition_logpdf(x, prev)
        w = np.exp(lw - lw.max())
        assert logsumexp(lw) - np.log(n) == pytest.approx(evidence_grid, abs=tol_evidence), window
        np.testing.assert_allclose((w @ z[:, :2]) / w.sum(), mean_grid, atol=tol_mean)
        ess[window] = w.sum() ** 2 / (w @ w)
    # integrating out the prediction's translation noise: most particles count (box: a few %)
    assert ess["dynamics"] > 0.4 * n and ess["dynamics"] > 5 * ess["box"]


def test_plate_run_same_seed_same_track_and_bad_layout(road, tmp_path, capsys):
    tracks = []
    for name in ("a.csv", "b.csv"):
        with pytest.raises(SystemExit) as e:
            main(["run", str(road), "--algo", "lis", "-n", "30", "--max-frames", "8", "--seed", "5",
                  "--track", str(tmp_path / name), "-q"])
        assert e.value.code == 0
        rows = [r.split(",") for r in (tmp_path / name).read_text().splitlines()]
        ms = rows[0].index("ms")
        tracks.append([r[:ms] + r[ms + 1:] for r in rows])  # all but the ms column
    assert tracks[0] == tracks[1]
    capsys.readouterr()
    with pytest.raises(SystemExit) as e:
        main(["run", str(road), "--algo", "lis", "-n", "30", "--max-frames", "8"])
    assert e.value.code == 0 and "vs ground truth: plate lost in" in capsys.readouterr().out
    with pytest.raises(SystemExit) as e:
        main(["run", str(road), "--layout", "us", "-q"])
    assert e.value.code != 0 and "us" in capsys.readouterr().err


@pytest.mark.slow
def test_reproduce_plate_and_eval_plate_on_a_tiny_suite(road, tmp_path, capsys):
    import json
    import shutil

    from cli_helpers import run

    suite = tmp_path / "suite"
    shutil.copytree(road, suite / "road")
    js = tmp_path / "p.json"
    code, out, err = run(["reproduce", "plate", "--clips", str(suite), "--runs", "2", "--algos", "lis:30,bootstrap:60",
                          "--in-process", "--workers", "2", "--out", str(tmp_path / "res"), "--json", str(js),
                          "--plots", str(tmp_path / "plots"), "-q"], capsys)
    assert code == 0, err
    assert "P(lost)" in out and "false rep." in out
    data = json.loads(js.read_text())
    assert [(r["algo"], r["particles"]) for r in data["results"]] == [("lis", 30), ("bootstrap", 60)]
    for r in data["results"]:
        assert r["runs"] == 2 and 0.0 <= r["p_lost"] <= 1.0 and r["frames_per_s"] > 0
        assert r["appearances"] > 0 and r["false_reports"] >= 0
    assert (tmp_path / "plots" / "p_lost_vs_frame.png").read_bytes()[:4] == b"\x89PNG"
    code, _, err = run(["eval", str(suite), "--model", "plate", "--algos", "lis", "--particles", "30", "--runs", "1",
                        "--in-process", "--workers", "1", "--out", str(tmp_path / "ev"), "-q"], capsys)
    assert code == 0, err
    res = json.loads((tmp_path / "ev" / "results.json").read_text())
    assert res["config"]["model"] == "plate" and res["results"][0]["success_auc"] > 0


@pytest.mark.slow
@pytest.mark.parametrize("kind, model", [("plate", "plate"), ("landmarks", "landmarks")])
def test_synth_suite_makes_every_kind(kind, model, tmp_path, capsys):
    import json

    from cli_helpers import run

    code, _, err = run(["synth-suite", "--kind", kind, "--clips", "2", "--seed", "4", "--frames", "3",
                        "--out", str(tmp_path / "s"), "-q"], capsys)
    assert code == 0, err
    metas = sorted((tmp_path / "s").glob("*/meta.json"))
    assert [m.parent.name for m in metas] == [f"{kind}-04", f"{kind}-05"]
    assert all(json.loads(m.read_text())["model"] == model for m in metas)


@pytest.mark.slow
def test_fit_plate_separates_plates_from_background_and_prints_the_coefficients(tmp_path, capsys):
    """``vistrack fit-plate``: the library fit (:func:`fit_plate_coefficients`) on one short clip scores
    most true plates above log-odds 0 and almost no random or nearby pose; the command prints every
    feature's coefficient."""
    from cli_helpers import run
    from vistrack.models.plate.fitting import fit_plate_coefficients
    from vistrack.models.plate.model import PlateLikelihood

    code, _, err = run(["synth", "plate", "--out", str(tmp_path / "c1"), "--frames", "12", "--size", "320x240",
                        "--seed", "101"], capsys)
    assert code == 0, err
    fit = fit_plate_coefficients(tmp_path, "jp", rounds=0)
    s = fit["samples"]
    assert s["plate"]["n"] > 0 and s["plate"]["above_0"] > 0.8
    assert s["random"]["above_0"] < 0.05 and s["near"]["above_0"] < 0.2
    code, out, err = run(["fit-plate", str(tmp_path), "--rounds", "0"], capsys)
    assert code == 0, err
    assert all(f'"{n}":' in out for n in PlateLikelihood("jp").FEATURES) and "bias = " in out
    code, _, err = run(["fit-plate", str(tmp_path / "c1" / "nothing")], capsys)
    assert code != 0
