"""The contour's LMS local search in two fused compiled passes (:mod:`vistrack.models.contour.search_kernels`)
against the step-by-step kernels and numpy steps it replaces (``Contour.fused_search = False``):
equal bit for bit, states and log-likelihoods, and so are the tracks."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from vistrack import kernels
from vistrack.appearance.features import FeatureMaps
from vistrack.io.clips import load_clip
from vistrack.loop import Stepper
from vistrack.registry import make_filter
from vistrack.registry.builders import build_model

pytestmark = pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")


@pytest.fixture(scope="module")
def clip(synth_clip):
    return load_clip(synth_clip("contour", frames=10, size=(320, 240), seed=5))


def searched(model, obs, states, fused):
    model.fused_search = fused
    with kernels.numpy_paths(False):
        return model.local_search(obs, states)


@pytest.mark.parametrize("polarity, check", [(None, True), (1, True), (-1, False)])
def test_fused_search_equals_the_step_by_step_path(clip, polarity, check):
    model = build_model("contour", clip, init_gt="")
    model.polarity, model.search_check = polarity, check
    obs = model.observe(FeatureMaps(dict(clip.source)[4]), None)
    rng = np.random.default_rng(2)
    x = model.predict(model.sample_prior(60, rng), rng)
    x[:, :2] += rng.normal(0.0, 6.0, (60, 2))
    x[:6, :2] = [[2, 3], [318, 120], [160, 238], [-5, 50], [330, 250], [160, 1]]  # lines across the border
    x[6, 2] = -0.999999999999  # a pose of almost zero scale
    a, la = searched(model, obs, x, True)
    b, lb = searched(model, obs, x, False)
    assert (a[:, :4] != x[:, :4]).any(axis=1).mean() > 0.5  # most poses moved
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(la, lb)
    a2, la2 = searched(model, obs, x, True)  # the reused work arrays leave no trace
    np.testing.assert_array_equal(a2, a)
    np.testing.assert_array_equal(la2, la)


def test_fused_search_tracks_identical(clip):
    def states(fused):
        with warnings.catch_warnings(), kernels.numpy_paths(False):
            warnings.simplefilter("ignore")
            model = build_model("contour", clip, init_gt="")
            model.fused_search = fused
            stepper = Stepper(make_filter("ls-n-ips", model), 30, np.random.default_rng(7))
            return np.array([stepper.step(i, f).particles.states for i, f in clip.source])

    np.testing.assert_array_equal(states(True), states(False))


@pytest.mark.slow
def test_grid_tables_equal_the_direct_sum():
    """The grid's tables (one feature: by distance; two: by both distances, kept across calls; more:
    per line) give each line's term exactly as summing the kernel over its features there."""
    from numba import njit

    from vistrack.models.contour.kernels import _is_peak, grid

    @njit(cache=False)
    def direct(gn, thresh, start, nrm, offsets, kern, c, out):
        n_samples = gn.shape[2]
        out[:] = 0.0
        for n in range(gn.shape[0]):
            for m in range(gn.shape[1]):
                g = gn[n, m]
                for j in range(offsets.shape[0]):
                    v = nrm[n, m, 0] * offsets[j, 0] + nrm[n, m, 1] * offsets[j, 1] - start
                    i = int(min(max(v, np.float32(0.0)), np.float32(n_samples - 1)))
                    acc, nf = np.float32(0.0), 0
                    for k in range(n_samples):
                        if _is_peak(g[k], g[k - 1] if k > 0 else g[k], g[k + 1] if k < n_samples - 1 else g[k], k,
                                    n_samples, thresh):
                            acc += kern[k, i]
                            nf += 1
                    if nf:
                        out[n, j] += np.log1p(acc * c)
        return out

    rng = np.random.default_rng(4)
    n_samples = 41
    off = np.arange(n_samples, dtype=float) - 20
    kern = np.exp(-0.5 * ((off[:, None] - off[None, :]) / 2.0) ** 2).astype(np.float32)
    gn = (rng.random((12, 40, n_samples)) ** 6 * 10).astype(np.float32)  # 0 to 10+ features per line
    nrm = rng.normal(size=(12, 40, 2)).astype(np.float32)
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    g = np.arange(-4, 5, dtype=np.float32) * 2.5
    offsets = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    args = (np.float32(2.0), np.float32(off[0] - 0.5), nrm, offsets, kern, np.float32(31.0))
    ref = direct(gn, *args, np.empty((12, len(offsets)), np.float32))
    np.testing.assert_array_equal(grid(gn, *args, np.empty_like(ref)), ref)
