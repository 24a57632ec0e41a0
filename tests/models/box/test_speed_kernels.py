"""The box model's kernels of issue 53 against their numpy paths: the confidence's colour cues, the
correlation filter's adaptation on the search's own patch (``reuse``) and the scale filter's half spectra.

Tolerances: the colour cues' counts are equal and their sums in numpy's order but the back-projection's dot
products in bin order (1e-12 relative); the compiled adaptation computes numpy's complex products (bit for bit
on this machine, asserted to 1e-12); the scale filter's response from half spectra is the full DFT's to 1e-12.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

import vistrack
from box_helpers import moving_box_frames
from kernel_helpers import both
from vistrack import kernels
from vistrack.appearance.correlation import CorrelationFilter
from vistrack.appearance.features import FeatureMaps
from vistrack.models.box.confidence import FEATURES
from vistrack.models.box.scale_filter import ScaleFilter

pytestmark = pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")


@pytest.fixture(scope="module")
def tracked():
    """The default box tracker after 8 frames, with the next frame's observation and a step on it."""
    frames, box = moving_box_frames(10)
    t = vistrack.Tracker(model="box", seed=1)
    t.init(frames[0], box)
    for f in frames[1:8]:
        t.update(f)
    obs = t.model.observe(FeatureMaps(frames[8]), t.particles)
    return t, obs, frames


def test_colour_cues_equal_the_numpy_path(tracked):
    t, obs, _ = tracked
    model = t.model
    est = t.particles.mean()
    names = ("colour_first", "colour", "contrast")
    for shift in ((0.0, 0.0), (3.5, -2.0), (-60.0, 0.0)):  # on the object, beside it, over the region's edge
        s = est.copy()
        s[[0, 3]] += shift[0]
        s[[1, 4]] += shift[1]
        a, b = both(lambda: model.conf.cues(model, obs, s, t.particles, names))
        cols = [FEATURES.index(n) for n in names]
        assert np.all(np.isfinite(a[cols]))
        np.testing.assert_allclose(b[cols], a[cols], rtol=1e-12, atol=1e-14)


def test_only_the_calibrations_cues_are_computed(tracked):
    t, obs, _ = tracked
    conf = t.model.conf
    f = conf.cues(t.model, obs, t.particles.mean(), t.particles, conf.frame_cues)
    read = {FEATURES.index(n) for n in conf.calibration.names}
    assert all(np.isfinite(f[k]) == (k in read) for k in range(len(FEATURES)))
    every = conf.cues(t.model, obs, t.particles.mean(), t.particles)
    assert np.all(np.isfinite(every))
    np.testing.assert_array_equal(f[sorted(read)], every[sorted(read)])  # the same value either way
    assert conf.calibration(f) == conf.calibration(every)


def test_adapting_on_the_searchs_patch_equals_the_numpy_path():
    rng = np.random.default_rng(7)
    frame = rng.integers(0, 256, (120, 160, 3), dtype=np.uint8)
    cf = CorrelationFilter(frame, (50.0, 40.0, 30.0, 36.0), reuse=True, n_scales=1)
    moved = np.roll(frame, (2, -3), axis=(0, 1))
    resp = cf.detect(moved, np.array([65.0, 58.0]), 0.0)

    def adapt():
        twin = copy.deepcopy(cf)
        twin.adapt(moved, np.array([62.3, 60.1]), 0.01, resp)
        return twin.A, twin.B, twin.filter()[0], twin.filter()[1]

    for a, b in zip(*both(adapt)):
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)


def test_scale_filter_half_spectra_give_the_full_dfts_response():
    """The filter learnt and applied on the DFT's first half, made by one matrix product, responds as DSST's
    formulas on the full FFT (the first frame's filter)."""
    rng = np.random.default_rng(3)
    frame = rng.integers(0, 256, (120, 160, 3), dtype=np.uint8)
    sf = ScaleFilter(frame, (50.0, 40.0, 40.0, 30.0))
    fmap = sf.feature_map(frame, np.array([70.0, 55.0]), 0.05)
    samples = sf.samples(fmap, np.array([70.0, 55.0]), 0.05).T  # (d, S)
    full_f = np.fft.fft(sf.samples(sf.feature_map(frame, np.array([70.0, 55.0]), 0.0), np.array([70.0, 55.0]), 0.0).T,
                        axis=1)
    k = np.arange(len(sf.log_steps)) - len(sf.log_steps) // 2
    conj_g = np.conj(np.fft.fft(np.exp(-0.5 * (k / sf.sigma) ** 2)))
    a, b = conj_g * full_f, np.sum((full_f * np.conj(full_f)).real, axis=0)  # the first frame's filter, full DFT
    z = np.fft.fft(samples, axis=1)
    want = np.fft.ifft(np.sum(np.conj(a) * z, axis=0) / (b + sf.lam)).real
    got = sf.detect(frame, np.array([70.0, 55.0]), 0.05).values
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
