"""The plate LIS proposal's compiled draws (vistrack.models.plate.scan_kernels) against the numpy path.

Tolerance: none — the cells, the drawn points, ``log q`` and the generator's state after the
draws are equal bit for bit (the kernels take the Gumbel and uniform variates drawn by numpy in
the numpy path's order, and sum in its order — for the births' weighted sums, the order of
numpy's ``einsum`` on x86-64, which another architecture may not share).
"""

from __future__ import annotations

import numpy as np
import pytest

from kernel_helpers import both
from vistrack import kernels
from vistrack.appearance.features import FeatureMaps
from vistrack.io.clips import load_clip
from vistrack.registry.builders import build_model

pytestmark = pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    """A plate model, its observation of frame 12 and predicted states about the plate and elsewhere."""
    from vistrack.data_synth.plate_clip import make_plate_clip

    d = tmp_path_factory.mktemp("plate")
    make_plate_clip(d, frames=14, size=(320, 240), seed=2, cars=1)
    clip = load_clip(d)
    model = build_model("plate", clip)
    frame = dict(clip.source)[12]
    obs = model.observe(FeatureMaps(frame), None)
    rng = np.random.default_rng(5)
    prev = model.sample_prior(40, rng)
    prev[:5, :2] = [-30.0, 10.0]  # some out of the frame: border samples
    prev[:, 4:8] = prev[:, :4] + rng.normal(0, 1, (40, 4))  # tracked (not fresh entering draws)
    return model, obs, prev, model.predict(prev, rng)


def _draws(fn, seed=3):
    """``fn(rng)`` on the numpy paths and on the kernels from the same seed, with each generator's
    state after."""
    def run():
        rng = np.random.default_rng(seed)
        return fn(rng), rng.bit_generator.state

    return both(run)


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")
def test_draw_cells_equal_the_numpy_conditional(scene):
    model = scene[0]
    prop = model.lis_proposal()
    vals = np.random.default_rng(1).normal(0, 4, (30, 24))
    vals[3] = -np.inf  # a row with no mass
    vals[4, :5] = np.inf
    for beta in (1.0, 2.0):
        (a, sa), (b, sb) = _draws(lambda rng: prop._conditional(vals.copy(), rng, beta))
        np.testing.assert_array_equal(a[0], b[0])
        np.testing.assert_array_equal(a[1], b[1])
        assert sa == sb


@pytest.mark.parametrize("prior", [True, False])
def test_line_scans_equal_the_numpy_path(scene, prior):
    model, obs, prev, x = scene
    prop = model.lis_proposal()
    centre = prop.kernel.predict_mean(prev)[:, :2]
    half = np.minimum(model.plate_size(x), 3 * model.sigma[:2])
    pri = (centre, model.sigma[:2]) if prior else None
    beta = 1.0 if prior else 2.0
    (a, sa), (b, sb) = _draws(lambda rng: prop._line_scans(x, obs, rng, centre, half, 24, prior=pri, beta=beta))
    np.testing.assert_array_equal(a[0], b[0])  # the same draws
    # the same densities to the last bits: numpy's exp/log are SIMD routines on AVX-512 CPUs, libm's in numba
    np.testing.assert_allclose(a[1], b[1], rtol=1e-13, atol=0)
    assert sa == sb


def test_line_scans_with_an_appearance_map_equal_the_numpy_path(scene):
    """The scans with a learned appearance's map added (``amap``: a map over part of the frame,
    read bilinearly and clamped at its border) draw the same as the numpy path."""
    model, obs, prev, x = scene
    prop = model.lis_proposal()
    centre = prop.kernel.predict_mean(prev)[:, :2]
    half = np.minimum(model.plate_size(x), 3 * model.sigma[:2])
    amap = (np.random.default_rng(2).normal(0, 3, (40, 60)).astype(np.float32), np.array([0.5, -20.0, 0.5, -30.0]))
    (a, sa), (b, sb) = _draws(lambda rng: prop._line_scans(x, obs, rng, centre, half, 24, prior=(centre,
                                                                                                   model.sigma[:2]),
                                                           amap=amap))
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_allclose(a[1], b[1], rtol=1e-13, atol=0)
    assert sa == sb
    (c, _), _ = _draws(lambda rng: prop._line_scans(x, obs, rng, centre, half, 24, prior=(centre, model.sigma[:2])))
    assert not np.array_equal(a[0], c[0])  # the map changes the draws


def test_map_values_bilinear_and_clamped():
    from vistrack.models.plate.proposal import map_values

    m = np.arange(12, dtype=np.float32).reshape(3, 4)  # value 4 i + j at row i, column j
    amap = (m, np.array([1.0, 0.0, 1.0, 0.0]))
    np.testing.assert_allclose(map_values(amap, np.array([1.5, 0.25]), np.array([1.0, 0.5])), [5.5, 2.25])
    np.testing.assert_allclose(map_values(amap, np.array([-3.0, 9.0]), np.array([-1.0, 7.0])), [0.0, 11.0])


def test_plate_proposal_sample_equal_the_numpy_path(scene):
    """The whole proposal — tracked scans and the entering particles' search — draws the same."""
    model, obs, prev, x = scene
    x = x.copy()
    x[30:, 4:8] = x[30:, :4]  # ten fresh entering draws: the births' search
    prop = model.lis_proposal()
    (a, sa), (b, sb) = _draws(lambda rng: prop.sample(x, obs, rng, prev))
    np.testing.assert_array_equal(a[0], b[0])  # the same draws
    for u, v in zip(a[1:], b[1:]):  # the densities to the last bits (AVX-512's exp/log: see above)
        np.testing.assert_allclose(u, v, rtol=1e-13, atol=0)
    assert sa == sb
