"""The box model's correlation filter, its LIS proposal and re-detection after a loss (issue 34)."""

import csv

import cv2
import numpy as np
import pytest
from scipy import stats

import vistrack
from box_helpers import BACK, GONE, reappearing_clip
from cli_helpers import run
from vistrack.appearance.correlation import CorrelationFilter, DCFResponse, dcf_features
from vistrack.models.box.correlation_proposal import CorrelationProposal


class _Stub:
    dcf_tempering = (3.0, 0.1)
    dcf_scale_std = 0.05
    dcf_share = 0.5


def _response(rng, shape=(5, 6)):
    maps = rng.random((3,) + shape).astype(np.float32)
    maps[1, 2, 3] = 2.0  # the best scale is the middle one
    return DCFResponse(maps, [-0.1, 0.0, 0.1], centre=(40.0, 30.0), anchor=(3.0, 2.0), px=[0.55, 0.5, 0.45])


def test_proposal_density_integrates_to_one_over_the_search_region():
    resp = _response(np.random.default_rng(0))
    prop = CorrelationProposal(_Stub(), kernel=None)
    (ox, oy), a = resp.cell_origin()
    assert a == pytest.approx(2.0) and (ox, oy) == pytest.approx((34.0, 26.0))
    h, w = resp.maps.shape[1:]
    k = 8  # midpoints of k x k sub-cells: the density is constant on each cell
    xs = ox - a / 2 + a * (np.arange(w * k) + 0.5) / k
    ys = oy - a / 2 + a * (np.arange(h * k) + 0.5) / k
    ls = np.linspace(-0.5, 0.5, 2001)
    gx, gy = np.meshgrid(xs, ys)
    pts = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], axis=1)
    # over the centres at l = l* (= 0): 1 / (sqrt(2 pi) sigma_l), the log-scale's density there
    area = np.exp(prop.log_density(resp, pts)).sum() * (a / k) ** 2
    assert area * np.sqrt(2 * np.pi) * _Stub.dcf_scale_std == pytest.approx(1.0, rel=1e-9)
    # over the log-scale at one centre: that centre's density
    line = np.exp(prop.log_density(resp, np.stack([np.full_like(ls, ox), np.full_like(ls, oy), ls], 1)))
    at = np.exp(prop.log_density(resp, np.array([[ox, oy, 0.0]])))[0] * np.sqrt(2 * np.pi) * _Stub.dcf_scale_std
    assert np.trapezoid(line, ls) == pytest.approx(at, rel=1e-6)
    outside = np.array([[ox - a, oy, 0.0], [ox, oy + a * h, 0.0]])
    assert np.all(np.isneginf(prop.log_density(resp, outside)))


def test_proposal_draws_follow_its_density():
    resp = _response(np.random.default_rng(1))
    prop = CorrelationProposal(_Stub(), kernel=None)
    rng = np.random.default_rng(2)
    n = 40000
    z = prop.draw(resp, rng.random((n, 3)), rng.standard_normal(n))
    (ox, oy), a = resp.cell_origin()
    h, w = resp.maps.shape[1:]
    j = np.floor((z[:, 0] - ox) / a + 0.5).astype(int)
    i = np.floor((z[:, 1] - oy) / a + 0.5).astype(int)
    counts = np.bincount(i * w + j, minlength=h * w)
    p = np.exp(resp.cell_log_p(*_Stub.dcf_tempering))
    assert p.sum() == pytest.approx(1.0)
    assert stats.chisquare(counts, n * p).pvalue > 1e-3
    # inside each cell uniform: the offsets from the cell centre fill (-a/2, a/2) evenly
    off = (z[:, 0] - ox) / a + 0.5 - j
    assert stats.kstest(off, "uniform").pvalue > 1e-3
    assert stats.kstest((z[:, 2] - 0.0) / _Stub.dcf_scale_std, "norm").pvalue > 1e-3


def _textured(rng, shape):
    return cv2.GaussianBlur(rng.integers(0, 255, shape).astype(np.uint8), (0, 0), 1.5)


def test_filter_response_peaks_where_the_object_moved():
    rng = np.random.default_rng(3)
    frame = _textured(rng, (120, 160, 3))
    box = (60.0, 40.0, 24.0, 30.0)
    cf = CorrelationFilter(frame, box)
    moved = np.roll(frame, (-3, 5), axis=(0, 1))  # the scene 5 px right, 3 px up
    r = cf.detect(moved, np.array([72.0, 55.0]), 0.0)
    assert r.best == 1 and r.peak > 0.5
    assert r.peak_xy == pytest.approx((77.0, 52.0), abs=0.75)
    assert r.read(np.array([[77.0, 52.0, 0.0]]))[0] > 0.8 * r.peak
    x, y, val = cf.search(moved, 0.0)
    assert (x, y) == pytest.approx((77.0, 52.0), abs=3.0) and val > 0


def test_orientation_kernel_equals_the_numpy_path():
    from vistrack import kernels

    rng = np.random.default_rng(5)
    patch = cv2.GaussianBlur(rng.random((37, 52)).astype(np.float32) * 255, (0, 0), 1.2)
    patch[5:9, :] = 0.0  # flat rows: zero gradient
    a = dcf_features(patch, n_orient=6).copy()
    with kernels.numpy_paths():
        b = dcf_features(patch, n_orient=6).copy()
    np.testing.assert_array_equal(a, b)
    with kernels.numpy_paths():
        c = dcf_features(patch, n_orient=9).copy()
    np.testing.assert_array_equal(dcf_features(patch, n_orient=9), c)


def test_features_known_answers():
    flat = np.full((16, 20), 90.0, np.float32)
    f = dcf_features(flat)
    assert f.shape == (7, 16, 20) and np.allclose(f, 0.0)
    ramp = np.tile(np.arange(20, dtype=np.float32) * 3, (16, 1))  # a horizontal gradient: orientation 0
    f = dcf_features(ramp)
    assert np.all(f[1, 4:-4, 4:-4] > 0.1) and np.allclose(f[3:6, 4:-4, 4:-4], 0.0, atol=1e-6)
    bright = dcf_features(ramp * 1.6 + 20)  # light changes scale the features little
    assert np.allclose(bright[1:], f[1:], rtol=0.02, atol=1e-3) and np.allclose(bright[0], f[0], atol=1e-5)



def _track(frames, box, seed=1):
    t = vistrack.Tracker(model="box", particles=100, seed=seed)
    t.init(frames[0], box)
    out = [(True, t.box, False)]
    for f in frames[1:]:
        ok, b = t.update(f)
        out.append((ok, b, t.result.redetected))
    return out


@pytest.mark.slow
def test_redetection_finds_the_object_back_within_five_frames():
    frames, boxes = reappearing_clip()
    out = _track(frames, boxes[0])
    assert not any(ok for ok, _, _ in out[GONE + 3:BACK])  # reported lost while it is gone
    back = next(t for t in range(BACK, len(out)) if out[t][0])
    assert back <= BACK + 5 and out[back][2]  # found again, and that frame says so
    cx, cy = np.array(out[back][1][:2]) + np.array(out[back][1][2:]) / 2
    x, y, w, h = boxes[back]
    assert np.hypot(cx - x - w / 2, cy - y - h / 2) < 5
    assert all(ok for ok, _, _ in out[back:])
    assert sum(r for _, _, r in out) == 1  # the column is 1 on the frame of recovery only


def test_same_seed_same_track():
    frames, boxes = reappearing_clip(24)
    a, b = _track(frames, boxes[0], seed=7), _track(frames, boxes[0], seed=7)
    assert [x[1] for x in a] == [x[1] for x in b]


@pytest.mark.slow
def test_track_csv_has_the_redetected_column(tmp_path, capsys):
    frames, boxes = reappearing_clip()
    video = tmp_path / "clip"
    video.mkdir()
    for k, f in enumerate(frames):
        cv2.imwrite(str(video / f"{k:04d}.png"), f)
    track = tmp_path / "t.csv"
    code, _, err = run(["run", str(video), "--init", ",".join(map(str, boxes[0])), "--seed", "1", "--track",
                        str(track)], capsys)
    assert code == 0, err
    with open(track, newline="") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0])[-5:] == ["redetected", "ess", "ms", "lost_reason", "confidence"]
    found = [int(r["frame"]) for r in rows if r["redetected"] == "1"]
    assert len(found) == 1 and BACK <= found[0] <= BACK + 5
    assert rows[found[0]]["visible"] == "1" and rows[found[0]]["lost_reason"] == ""
    assert rows[found[0] - 1]["visible"] == "0" and rows[found[0] - 1]["lost_reason"] != ""


@pytest.mark.slow
def test_correlation_proposal_weights_match_a_brute_force_posterior():
    """Proper weighting: one LIS step with the correlation proposal from particles at rest; the mean
    weight is the evidence ∫ r K and the weighted mean pose the posterior mean, both also by brute
    force on a grid of centres and log-scales."""
    from vistrack.appearance.features import FeatureMaps
    from vistrack.core.particles import ParticleSet, logsumexp
    from vistrack.models.box.model import Box
    from vistrack.registry import make_filter

    rng = np.random.default_rng(6)
    bg = cv2.GaussianBlur(rng.integers(70, 180, (120, 160, 3)).astype(np.uint8), (0, 0), 3)
    obj = np.zeros((20, 20, 3), np.uint8)
    obj[:] = (30, 120, 230)
    obj[::5] = 20

    def scene(x, y):
        f = bg.copy()
        f[y:y + 20, x:x + 20] = obj
        return f

    model = Box(scene(60, 50), (60, 50, 20, 20), adapt_rate=0, sigma_xy=0.15, lambda_dcf=20.0,
                dcf_tempering=(20.0, 0.05), lambda_colour=6.0, lambda_template=4.0)
    pose = np.array([70.0, 60.0, 0.0])
    n = 30000
    prev = np.tile(np.concatenate([pose, pose]), (n, 1))
    obs = model.observe(FeatureMaps(scene(62, 49)), ParticleSet(prev))
    filt = make_filter("lis", model)
    z, lw, _, _ = filt.propose(prev, obs, np.random.default_rng(0), filt.kernel)
    assert np.all(np.isfinite(lw))
    w = np.exp(lw - lw.max())
    sd, sl = model.sigma[0], model.sigma[2]
    cs = np.arange(-4 * sd, 4 * sd + 1e-9, 0.25)
    ls = np.arange(-4 * sl, 4 * sl + 1e-9, sl / 12)  # the scale filter's term is sharp in l
    du, dv, dl = (a.ravel() for a in np.meshgrid(cs, cs, ls, indexing="ij"))
    grid = np.tile(np.concatenate([pose, pose]), (du.size, 1))
    grid[:, 0] += du
    grid[:, 1] += dv
    grid[:, 2] += dl
    lp = model.loglik(obs, grid) + model.transition_logpdf(grid, prev[:1].repeat(len(grid), 0))
    vol = 0.25 * 0.25 * (sl / 12)
    assert logsumexp(lw) - np.log(n) == pytest.approx(logsumexp(lp) + np.log(vol), abs=0.1)
    g = np.exp(lp - lp.max())
    mean_is, mean_grid = (w @ z[:, :3]) / w.sum(), (g @ grid[:, :3]) / g.sum()
    np.testing.assert_allclose(mean_is[:2], mean_grid[:2], atol=0.15)
    assert mean_is[2] == pytest.approx(mean_grid[2], abs=0.003)
    assert np.hypot(*(mean_grid[:2] - pose[:2])) > 1.0  # the posterior moved towards the object (2, -1)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the numpy path casts the non-finite points
def test_response_read_kernel_equals_the_numpy_path():
    from kernel_helpers import both

    rng = np.random.default_rng(11)
    resp = _response(rng)
    (ox, oy), a = resp.cell_origin()
    n = 4000
    states = np.stack([rng.uniform(ox - 4 * a, ox + 10 * a, n), rng.uniform(oy - 4 * a, oy + 8 * a, n),
                       rng.uniform(-0.2, 0.2, n)], axis=1)
    states[:5, 2] = [-0.1, 0.0, 0.1, -0.3, 0.3]  # on the scales and beyond the ends
    states[5:10, :2] = [[ox, oy], [ox + a, oy], [1e30, oy], [-np.inf, oy], [ox, np.inf]]
    a_np, a_k = both(lambda: resp.read(states))
    np.testing.assert_array_equal(a_np, a_k)
    one = DCFResponse(resp.maps[1:2], [0.05], resp.centre, resp.anchor, resp.px[1:2])
    b_np, b_k = both(lambda: one.read(states))
    np.testing.assert_array_equal(b_np, b_k)


def test_compiled_detect_and_adapt_equal_the_numpy_path():
    """``correlate`` and ``adapt_filter`` (complex products as numpy's fused multiply-adds): the same filter,
    the same responses."""
    import copy

    from vistrack import kernels

    rng = np.random.default_rng(12)
    frames = [_textured(rng, (120, 160, 3)) for _ in range(4)]
    cf = CorrelationFilter(frames[0], (60.0, 40.0, 24.0, 30.0), rate=0.3)
    both_cf = {}
    for name, on in (("numpy", True), ("kernels", False)):
        c = copy.deepcopy(cf)
        with kernels.numpy_paths(on):
            maps = []
            for k, f in enumerate(frames[1:]):
                maps.append(c.detect(f, np.array([72.0 + k, 55.0]), 0.01 * k).maps)
                c.adapt(f, np.array([73.0 + k, 54.5]), 0.02 * k)
            maps.append(c.detect(frames[0], np.array([72.0, 55.0]), 0.0).maps)
        both_cf[name] = (c, maps)
    (a, ma), (b, mb) = both_cf["numpy"], both_cf["kernels"]
    np.testing.assert_array_equal(a.A, b.A)
    np.testing.assert_array_equal(a.B, b.B)
    for x, y in zip(ma, mb):
        np.testing.assert_array_equal(x, y)


def test_compiled_correlation_draws_equal_the_numpy_path():
    from types import SimpleNamespace

    from kernel_helpers import both

    class _K:
        def logpdf(self, new, old):
            return -0.5 * np.sum((new[:, :3] - old[:, :3]) ** 2, axis=1)

    resp = _response(np.random.default_rng(13))
    prop = CorrelationProposal(_Stub(), kernel=_K())
    (ox, oy), a = resp.cell_origin()
    rng = np.random.default_rng(14)
    prev = np.column_stack([rng.uniform(ox - 3 * a, ox + 9 * a, 500), rng.uniform(oy - 3 * a, oy + 7 * a, 500),
                            rng.normal(0, 0.1, 500), np.zeros((500, 3))])
    x = prev + rng.normal(0, 1.0, prev.shape)
    for beta, centre in ((0.0, None), (0.5, None), (1.0, None), (0.5, 0.037)):  # centre: the scale filter's peak
        obs = SimpleNamespace(dcf=resp, dcf_share=beta, scale_centre=centre)
        got = both(lambda: prop._sample(x, obs, np.random.default_rng(15), prev))
        for p, k in zip(*got):
            np.testing.assert_array_equal(p, k)


@pytest.mark.slow
def test_gradient_kernel_equals_opencv():
    """``gradient_cells`` (the Sobel gradient, ``cartToPolar`` and the binning in one pass) gives what OpenCV's
    calls and ``orientation_cells`` give, on every integer gradient a grey patch can have and on fractional
    patches of odd sizes (where the CPU's OpenCV computes as the kernel does: ``POLAR_EXACT``)."""
    from vistrack.appearance import dcf_kernels as dk

    if not dk.POLAR_EXACT:
        pytest.skip("OpenCV's cartToPolar here is not the fused-multiply-add polynomial")
    v = np.arange(-255, 256, dtype=np.float32)
    gx, gy = (a.reshape(511, 511).copy() for a in np.meshgrid(v, v))
    mag, ang = np.empty_like(gx), np.empty_like(gx)
    dk.polar(gx, gy, mag, ang)
    want_mag, want_ang = cv2.cartToPolar(gx, gy)
    np.testing.assert_array_equal(mag, want_mag)
    np.testing.assert_array_equal(ang, want_ang)
    rng = np.random.default_rng(8)
    for shape in ((72, 75), (37, 52), (5, 3), (1, 9), (9, 1)):
        for patch in (rng.integers(0, 256, shape).astype(np.float32), (rng.random(shape) * 255).astype(np.float32)):
            bins, sq = np.empty(shape + (6,), np.float32), np.empty(shape, np.float32)
            dk.gradient_cells(patch, 6, bins, sq)
            gx = cv2.Sobel(patch, cv2.CV_32F, 1, 0, ksize=1, borderType=cv2.BORDER_REFLECT)
            gy = cv2.Sobel(patch, cv2.CV_32F, 0, 1, ksize=1, borderType=cv2.BORDER_REFLECT)
            want_bins, want_sq = np.empty_like(bins), np.empty_like(sq)
            dk.orientation_cells(*cv2.cartToPolar(gx, gy), 6, want_bins, want_sq)
            np.testing.assert_array_equal(bins, want_bins)
            np.testing.assert_array_equal(sq, want_sq)


def test_grey_patch_kernel_equals_opencv():
    """``grey_gradient_cells`` makes the grey patch as ``cv2.cvtColor`` does (on every colour) and its sums give
    ``cv2.meanStdDev``'s mean and deviation; the features of a BGR patch are those of its grey float patch."""
    from vistrack.appearance import dcf_kernels as dk

    v = np.arange(256)
    grey, sq = np.empty((256, 256), np.float32), np.empty((256, 256), np.float32)
    bins = np.empty((256, 256, 6), np.float32)
    for b in range(256):  # every colour: blue b, green and red over the image
        colours = np.stack([np.full((256, 256), b), *np.meshgrid(v, v, indexing="ij")], -1).astype(np.uint8)
        dk.grey_gradient_cells(colours, 6, grey, bins, sq)
        np.testing.assert_array_equal(grey, cv2.cvtColor(colours, cv2.COLOR_BGR2GRAY).astype(np.float32))
    rng = np.random.default_rng(9)
    for shape in ((72, 75, 3), (13, 29, 3), (1, 1, 3)):
        bgr = rng.integers(0, 256, shape).astype(np.uint8)
        g = np.empty(shape[:2], np.float32)
        total, squares = dk.grey_gradient_cells(bgr, 6, g, np.empty(shape[:2] + (6,), np.float32),
                                                np.empty(shape[:2], np.float32))
        m, s = cv2.meanStdDev(g)
        n = g.size
        assert total * (1.0 / n) == m[0, 0]
        assert np.sqrt(max(squares * (1.0 / n) - (total / n) ** 2, 0.0)) == pytest.approx(s[0, 0], rel=1e-15)
        np.testing.assert_array_equal(dcf_features(bgr), dcf_features(g))


def test_cumulative_kernel_equals_numpy_cumsum():
    from vistrack.appearance.dcf_kernels import cumulative

    rng = np.random.default_rng(10)
    for n in (0, 1, 2, 99, 5400):
        for x in (rng.random(n), np.exp(rng.uniform(-700, 0, n)), rng.standard_normal(n)):
            np.testing.assert_array_equal(cumulative(x, np.empty(n)), np.cumsum(x))


def test_cell_probabilities_equal_the_numpy_path():
    """``DCFResponse.cell_log_p`` and ``cell_cumulative`` with the compiled arithmetic about numpy's exp and
    log (``cell_scores``, ``cell_probabilities``, ``cumulative``) against the numpy path, bit for bit."""
    from vistrack import kernels
    from vistrack.appearance.correlation import DCFResponse

    rng = np.random.default_rng(11)
    maps = rng.standard_normal((3, 72, 75)).astype(np.float32)
    out = {}
    for on in (True, False):
        with kernels.numpy_paths(on):
            r = DCFResponse(maps, np.array([-0.04, 0.0, 0.04]), (50.0, 60.0), (37.0, 36.0), np.full(3, 0.5))
            out[on] = (r.cell_log_p(8.0, 0.05).copy(), r.cell_cumulative(8.0, 0.05).copy())
    for a, b in zip(out[True], out[False]):
        np.testing.assert_array_equal(a, b)
