"""The siam model (issue 51): NanoTrack v3's network, its response as ``log r`` and as LIS's proposal, and the
tracker built on them."""

import numpy as np
import pytest
from reference_crops import REFERENCE, pattern
from scipy import stats

import vistrack
from vistrack import kernels
from vistrack.models.siam.network import EXEMPLAR, INSTANCE, SiamNetwork, cell_points, context_side, crop
from vistrack.models.siam.observation import SiamFrame, cell_boxes
from vistrack.models.siam.proposal import ResponseProposal, mixture_logpdf, mixture_parts


def test_the_network_equals_the_authors_files_on_a_fixed_crop():
    """The shipped networks on onnxruntime (batch and crop sizes made free) against the stored outputs of the
    authors' files on OpenCV's DNN module: the exemplar's features and the head's logits and distances."""
    ref = np.load(REFERENCE)
    net = SiamNetwork()
    z = net.set_exemplar(pattern(EXEMPLAR, 0.3))
    np.testing.assert_allclose(z[0], ref["z_features"], atol=1e-4)
    logit, ltrb = net.search(pattern(INSTANCE, 1.1))
    np.testing.assert_allclose(logit[0], ref["cls"][1] - ref["cls"][0], atol=1e-4)
    np.testing.assert_allclose(ltrb[0], ref["loc"], atol=1e-4)
    # a batch gives each crop's own answer; the wide head maps a 511 crop to 31 x 31 cells
    batch = np.stack([pattern(INSTANCE, 1.1), pattern(INSTANCE, 2.0)])
    lb, tb = net.search(batch)
    np.testing.assert_allclose(lb[0], logit[0], atol=1e-5)
    assert lb.shape == (2, 15, 15) and tb.shape == (2, 4, 15, 15)
    assert net.search(pattern(511, 0.7), wide=True)[0].shape == (1, 31, 31)


def test_the_weights_are_package_data():
    from importlib.resources import files

    weights = files("vistrack.models.siam").joinpath("weights")
    for name in ("nanotrack_backbone.onnx", "nanotrack_head.onnx", "nanotrack_head_wide.onnx", "LICENSE"):
        assert weights.joinpath(name).is_file(), name
    assert "Apache License" in weights.joinpath("LICENSE").read_text()


@pytest.mark.slow
def test_a_non_editable_install_finds_the_weights(tmp_path):
    """A wheel of the project holds the networks, and vistrack imported from it (not from the source tree) builds
    the siam model's network from them."""
    import subprocess
    import sys
    import zipfile

    from path_helpers import ROOT as root  # the checkout (vistrack itself may be installed from it, not edited)

    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w",
                    str(tmp_path), str(root)], check=True)
    wheel = next(tmp_path.glob("vistrack-*.whl"))
    site = tmp_path / "site"
    zipfile.ZipFile(wheel).extractall(site)
    code = ("import sys, vistrack, vistrack.models.siam.network as n; "
            "assert vistrack.__file__.startswith(sys.argv[1]), vistrack.__file__; "
            "net = n.SiamNetwork(); print(n.WEIGHTS)")
    out = subprocess.run([sys.executable, "-c", code, str(site)], cwd=tmp_path,
                         env={"PYTHONPATH": str(site), "PATH": ""}, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert str(site) in out.stdout


def test_the_crop_cuts_the_square_about_the_centre_and_pads_with_the_fill():
    frame = np.zeros((40, 60, 3), np.uint8)
    frame[..., 0] = np.arange(60)[None, :]  # blue: the column
    frame[..., 1] = np.arange(40)[:, None]  # green: the row
    c = crop(frame, (30.0, 20.0), 11, 11, fill=(9, 9, 9))
    assert c.shape == (3, 11, 11) and c.dtype == np.float32
    # side 11 about (30, 20): first pixel floor(30 - 6 + 0.5) = 24
    assert c[0, 0, 0] == 24 and c[1, 0, 0] == 14 and c[0, 0, 10] == 34
    edge = crop(frame, (2.0, 2.0), 9, 9, fill=(7, 8, 9))
    assert edge[:, 0, 0].tolist() == [7, 8, 9]  # the corner lies outside the frame
    assert edge[0, 4, 4] == 1 and edge[1, 4, 4] == 1
    assert crop(frame, (500.0, 500.0), 9, 5, fill=(5, 5, 5)).max() == 5  # wholly outside: the fill


def test_cell_boxes_put_the_heads_distances_about_each_cells_point():
    ltrb = np.zeros((4, 15, 15))
    ltrb[:] = np.array([10.0, 20.0, 30.0, 40.0])[:, None, None]
    boxes = cell_boxes(ltrb, np.array([100.0, 50.0]), 2.0, np.array([20.0, 30.0]))
    pts = cell_points(15)
    k = 7 * 15 + 7  # the centre cell: its point is the crop's centre
    assert pts[k].tolist() == [0.0, 0.0]
    # x from 100 - 10/2 to 100 + 30/2: centre 105, width 20 px; y from 50 - 20/2 to 50 + 40/2: centre 55, 30 px
    np.testing.assert_allclose(boxes[k], [105.0, 55.0, np.log(20 / 20), np.log(30 / 30)])
    np.testing.assert_allclose(boxes[0, :2], [100 + (-112 + 10) / 2, 50 + (-112 + 10) / 2])


def _frame(rng, m=15, apart=0.0):
    """A synthetic response: a logit bump at cell (6, 8), boxes pointing at (120, 80) of 30 x 40 px (``apart``:
    each cell's box that many px from its neighbours' instead)."""
    ii, jj = np.mgrid[0:m, 0:m]
    logit = 6.0 * np.exp(-((ii - 6) ** 2 + (jj - 8) ** 2) / 4.0) - 3.0 + 0.3 * rng.standard_normal((m, m))
    boxes = np.zeros((m * m, 4))
    boxes[:, 0] = 120 + apart * (jj.ravel() - 8) + rng.normal(0, 1.0, m * m)
    boxes[:, 1] = 80 + apart * (ii.ravel() - 6) + rng.normal(0, 1.0, m * m)
    boxes[:, 2] = np.log(30 / 25) + rng.normal(0, 0.03, m * m)
    boxes[:, 3] = np.log(40 / 35) + rng.normal(0, 0.03, m * m)
    return SiamFrame(np.zeros((160, 240, 3), np.uint8), np.array([116.0, 84.0]), 255 / 120, logit, boxes,
                     np.array([25.0, 35.0]))


class _Stub:
    share, cells, tempering, spread = 0.6, 6, 1.5, (0.1, 0.05)


def test_the_response_mixture_integrates_to_one():
    """``q_Y`` summed over a fine 4-D grid about its components (each within 7 stds) gives 1."""
    obs = _frame(np.random.default_rng(0))
    log_pi, mu, sd = mixture_parts(obs, 6, 1.5, (0.1, 0.05))
    assert np.exp(log_pi).sum() == pytest.approx(1.0)
    lo, hi = (mu - 7 * sd).min(axis=0), (mu + 7 * sd).max(axis=0)
    axes = [np.linspace(a, b, k) for a, b, k in zip(lo, hi, (48, 48, 40, 40))]
    steps = [ax[1] - ax[0] for ax in axes]
    g = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 4)
    total = np.exp(mixture_logpdf(g, log_pi, mu, sd)).sum() * np.prod(steps)
    assert total == pytest.approx(1.0, abs=2e-3)


def test_the_response_mixtures_draws_follow_its_density():
    obs = _frame(np.random.default_rng(1), apart=40.0)  # components 10 stds apart: each draw's is its nearest
    prop = ResponseProposal(_Stub(), kernel=None)
    log_pi, mu, sd = prop.parts(obs)
    rng = np.random.default_rng(2)
    n = 40000
    z = prop.draw(obs, rng.random(n), rng.standard_normal((n, 4)))
    # the component of each draw: the nearest mean in std units (the components lie apart)
    d = ((z[:, None, :] - mu[None]) / sd[None]) ** 2
    comp = d.sum(axis=2).argmin(axis=1)
    counts = np.bincount(comp, minlength=len(log_pi))
    assert stats.chisquare(counts, n * np.exp(log_pi)).pvalue > 1e-3
    k = int(np.argmax(log_pi))
    for j in range(4):
        assert stats.kstest((z[comp == k, j] - mu[k, j]) / sd[k, j], "norm").pvalue > 1e-3


def _scene(x, y, rng_seed=3):
    """A 240 x 180 frame of textured clutter with a textured 30 x 30 object at (x, y)."""
    import cv2

    rng = np.random.default_rng(rng_seed)
    bg = cv2.GaussianBlur(rng.integers(60, 200, (180, 240, 3)).astype(np.uint8), (0, 0), 2.0)
    obj = np.random.default_rng(99).integers(0, 255, (30, 30, 3)).astype(np.uint8)
    obj = cv2.GaussianBlur(obj, (0, 0), 1.0)
    obj[::6] = (20, 60, 220)
    f = bg.copy()
    f[int(y):int(y) + 30, int(x):int(x) + 30] = obj
    return f


def test_lis_weights_match_a_brute_force_posterior():
    """Proper weighting: one LIS step from particles at rest; the mean weight is the evidence ``∫ r K`` and the
    weighted mean pose the posterior mean, both also by brute force on a grid of centres and log-sizes."""
    from vistrack.appearance.features import FeatureMaps
    from vistrack.core.particles import ParticleSet, logsumexp
    from vistrack.models.siam.model import Siam
    from vistrack.registry import make_filter

    model = Siam(_scene(100, 70), (100, 70, 30, 30), sigma_xy=0.1, sigma_scale=0.03, sigma_aspect=0.04,
                 confidence=False)
    pose = np.array([115.0, 85.0, 0.0, 0.0])
    n = 40000
    prev = np.tile(np.concatenate([pose, pose]), (n, 1))
    obs = model.observe(FeatureMaps(_scene(103, 68)), ParticleSet(prev))
    filt = make_filter("lis", model)
    z, lw, _, _ = filt.propose(prev, obs, np.random.default_rng(0), filt.kernel)
    assert np.all(np.isfinite(lw))
    sc, ss, sa = model.sigma_xy * model.side0, model.sigma_scale, model.sigma_aspect
    cs = np.arange(-4 * sc, 4 * sc + 1e-9, 0.5)
    ls = np.arange(-4 * ss, 4 * ss + 1e-9, ss / 3)
    la = np.arange(-4 * sa, 4 * sa + 1e-9, sa / 3)
    du, dv, dl, da = (a.ravel() for a in np.meshgrid(cs, cs, ls, la, indexing="ij"))
    grid = np.tile(np.concatenate([pose, pose]), (du.size, 1))
    grid[:, 0] += du
    grid[:, 1] += dv
    grid[:, 2] += dl + da / 2
    grid[:, 3] += dl - da / 2
    lp = model.loglik(obs, grid) + model.transition_logpdf(grid, prev[:1].repeat(len(grid), 0))
    vol = 0.5 * 0.5 * (ss / 3) * (sa / 3)  # (lw, lh) = (l + a/2, l - a/2): Jacobian 1
    assert logsumexp(lw) - np.log(n) == pytest.approx(logsumexp(lp) + np.log(vol), abs=0.1)
    w, g = np.exp(lw - lw.max()), np.exp(lp - lp.max())
    mean_is, mean_grid = (w @ z[:, :4]) / w.sum(), (g @ grid[:, :4]) / g.sum()
    np.testing.assert_allclose(mean_is[:2], mean_grid[:2], atol=0.15)
    np.testing.assert_allclose(mean_is[2:], mean_grid[2:], atol=0.004)
    assert np.hypot(*(mean_grid[:2] - pose[:2])) > 1.0  # the posterior moved towards the object (+3, -2)


def test_the_compiled_step_and_estimate_equal_the_numpy_path():
    from vistrack.appearance.features import FeatureMaps
    from vistrack.core.particles import ParticleSet
    from vistrack.models.siam.model import Siam
    from vistrack.registry import make_filter

    model = Siam(_scene(100, 70), (100, 70, 30, 30), confidence=False)
    rng = np.random.default_rng(4)
    prev = np.tile(np.r_[115.0, 85.0, 0.0, 0.0, 113.0, 86.0, 0.0, 0.0], (300, 1))
    prev += rng.normal(0, [3, 3, 0.05, 0.05, 3, 3, 0.05, 0.05], prev.shape)
    obs = model.observe(FeatureMaps(_scene(104, 69)), ParticleSet(prev))
    filt = make_filter("lis", model)
    fast = filt.propose(prev, obs, np.random.default_rng(5), filt.kernel)
    with kernels.numpy_paths():
        slow = filt.propose(prev, obs, np.random.default_rng(5), filt.kernel)
        est_slow = model.estimate(ParticleSet(fast[0], fast[1]))
    for a, b in zip(fast, slow):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(model.estimate(ParticleSet(fast[0], fast[1])), est_slow, rtol=1e-12)


def _clip(n=30):
    """A textured object moving right and down over clutter, with a jump at frame 15: ``(frames, truth)``."""
    xs = [40 + 3 * k + (25 if k >= 15 else 0) for k in range(n)]
    ys = [50 + 2 * k for k in range(n)]
    return [_scene(x, y) for x, y in zip(xs, ys)], np.array([[x, y, 30, 30] for x, y in zip(xs, ys)], float)


def test_the_tracker_follows_a_synthetic_object_and_the_same_seed_gives_the_same_track():
    from vistrack.scoring.metrics import iou

    frames, truth = _clip()

    def track(seed):
        t = vistrack.Tracker(model="siam", seed=seed, confidence=False)
        t.init(frames[0], tuple(truth[0]))
        return np.array([truth[0]] + [t.update(f)[1] for f in frames[1:]])

    a, b, c = track(1), track(1), track(2)
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert iou(a, truth).min() > 0.5
    assert np.abs((a[:, :2] + a[:, 2:] / 2) - (truth[:, :2] + 15)).max() < 6.0


def test_the_search_crop_follows_the_authors_size_rule():
    from vistrack.models.siam.model import Siam

    model = Siam(_scene(100, 70), (100, 70, 30, 20), confidence=False)
    s_z = context_side(30, 20)
    assert s_z == pytest.approx(np.sqrt(55 * 45))
    assert model.search_side(np.array([0.0, 0.0, 0.0, 0.0])) == pytest.approx(s_z * 255 / 127)


@pytest.mark.parametrize("algo", ["lis", "bootstrap", "condensation", "avpf"])
def test_every_algorithm_the_siam_model_lists_tracks(algo):
    """AVPF's first step asks ``p_0`` for its mean (``prior_mean``), which the siam model lacked."""
    from vistrack.registry import get_model_spec

    assert algo in get_model_spec("siam").algos
    t = vistrack.Tracker(model="siam", algo=algo, particles=50, seed=1)
    frame = _scene(100, 70)
    t.init(frame, (100, 70, 30, 30))  # the object's box (_scene's x, y: its top-left corner)
    visible, box = t.update(_scene(103, 68))  # moved by (+3, -2): its centre (118, 83)
    assert visible and abs(box[0] + box[2] / 2 - 118) < 3 and abs(box[1] + box[3] / 2 - 83) < 3
