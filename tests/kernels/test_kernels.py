"""The compiled kernels (vistrack.kernels) against the numpy paths they replace.

Tolerances: the sampling, the contour's edge strengths, features and likelihood, the plate's map,
pixel-set means and scans, the colour bins and bin integrals are equal bit for bit; the contour
likelihood sums a line's kernel in index order (1e-12 relative); the template correlation sums
its dot products in sample order (1e-12 relative); the contour's local-search grid sums float32
differently from BLAS (1e-5 relative) — tracks are nonetheless identical on the clips below.
"""

from __future__ import annotations

import warnings

import cv2
import numpy as np
import pytest

from kernel_helpers import both
from vistrack import kernels
from vistrack.appearance.features import FeatureMaps, bin_integrals, colour_bins, remap_points
from vistrack.io.clips import load_clip
from vistrack.loop import Stepper, warm_up
from vistrack.registry import make_filter
from vistrack.registry.builders import build_model

pytestmark = pytest.mark.skipif(not kernels.AVAILABLE, reason="numba is not installed")


def track(clip, model_name, algo, n, frames, fast, seed=0, **build):
    """States after each of ``frames`` frames of ``clip``."""
    with kernels.numpy_paths(not fast), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = build_model(model_name, clip, **build)
        stepper = Stepper(make_filter(algo, model), n, np.random.default_rng(seed))
        return model, stepper, [stepper.step(i, f).particles.states.copy()
                                for (i, f), _ in zip(clip.source, range(frames))]


@pytest.fixture(scope="module")
def contour_clip(tmp_path_factory):
    from vistrack.data_synth.contour_clip import make_contour_clip

    d = tmp_path_factory.mktemp("contour")
    make_contour_clip(d, frames=12, size=(320, 240), seed=3)
    return load_clip(d)


@pytest.fixture(scope="module")
def plate_clip(tmp_path_factory):
    from vistrack.data_synth.plate_clip import make_plate_clip

    d = tmp_path_factory.mktemp("plate")
    make_plate_clip(d, frames=40, size=(320, 240), seed=2, cars=1)
    return load_clip(d)


@pytest.mark.parametrize("channels", [1, 2, 3, 4])
def test_sampling_is_cv2_remap_bit_for_bit(channels):
    from vistrack.kernels.sampling import sample

    rng = np.random.default_rng(channels)
    img = (rng.random((30, 40, channels)) * 200 - 100).astype(np.float32)
    x = (rng.random(3000) * 50 - 5).astype(np.float32)  # inside, across the border and outside
    y = (rng.random(3000) * 40 - 5).astype(np.float32)
    x[:200] = np.round(x[:200] * 32) / 32 + 1 / 64  # ties of the 1/32-px rounding
    x[200], y[201] = np.nan, np.inf
    border = np.array([3.5, 0, 0, 0][:channels], np.float32)
    ref = remap_points(img if channels > 1 else img[..., 0], x, y, border=3.5).reshape(3000, channels)
    np.testing.assert_array_equal(sample(img, x, y, border), ref)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_pairwise_sum_is_numpys_order(dtype):
    from vistrack.kernels.sampling import pairwise_sum

    rng = np.random.default_rng(0)
    a = (rng.random(1200) * 10.0 ** rng.uniform(-4, 4, 1200)).astype(dtype)
    for n in (1, 7, 8, 9, 48, 128, 129, 300, 908, 1100):
        assert pairwise_sum(a, 5, n) == np.sum(a[5:5 + n])


def test_contour_kernels_equal_the_numpy_path(contour_clip):
    model, stepper, _ = track(contour_clip, "contour", "ls-n-ips", 30, 6, fast=False, init_gt="")
    obs = FeatureMaps(dict(contour_clip.source)[6])
    x = model.predict(stepper.particles.states, np.random.default_rng(1))
    z = x[:, :4]
    for fn in (lambda: model.edge_profiles(obs, z, model.line_offsets),
               lambda: model._profiles_wide(obs, z, 12.0)[1],
               lambda: model.edge_profiles(obs, z, np.linspace(-1, 1, 9)[None, None] * np.arange(1, 31)[:, None, None],
                                       support=True),
               lambda: model.local_search(obs, x)[0]):
        a, b = both(fn)
        np.testing.assert_array_equal(a, b)
    a, b = both(lambda: model.loglik(obs, x))
    np.testing.assert_allclose(b, a, rtol=1e-12)
    off, gn = model._profiles_wide(obs, z, 12.0)
    grid = model._search_grid()[0]
    nrm = model.measurement_lines(z)[1]
    from vistrack.models.contour.spline import edge_peaks

    thresh = model.feature_threshold(obs)
    ref = model._grid_from_peaks(off, edge_peaks(gn, thresh), nrm, grid)
    np.testing.assert_allclose(model._grid_from_peaks(off, gn, nrm, grid, thresh), ref, rtol=1e-5)


@pytest.mark.parametrize("algo", ["ls-n-ips", "bootstrap", "lis"])
def test_contour_tracks_identical_with_kernels(contour_clip, algo):
    n = 200 if algo == "bootstrap" else 30
    _, _, a = track(contour_clip, "contour", algo, n, 10, fast=False, init_gt="")
    _, _, b = track(contour_clip, "contour", algo, n, 10, fast=True, init_gt="")
    _, _, c = track(contour_clip, "contour", algo, n, 10, fast=True, init_gt="")
    np.testing.assert_array_equal(np.array(b), np.array(a))
    np.testing.assert_array_equal(np.array(c), np.array(b))  # the same seed, the same track


@pytest.mark.slow
def test_plate_kernels_equal_the_numpy_path(plate_clip):
    from vistrack.models.plate.likelihood import plate_map

    model, stepper, _ = track(plate_clip, "plate", "lis", 60, 30, fast=False)
    frame = dict(plate_clip.source)[30]
    a, b = both(lambda: plate_map(FeatureMaps(frame)))
    np.testing.assert_array_equal(a, b)
    obs = model.observe(FeatureMaps(frame), stepper.particles)
    x = model.predict(stepper.particles.states, np.random.default_rng(1))
    offsets = np.random.default_rng(2).normal(0, 8, (len(x), 5, 2))
    lik = model.lik
    for fn in (lambda: lik.features(obs, x), lambda: lik.loglik_sparse(obs, x, offsets),
               lambda: lik.scan(obs, x, "h", offsets), lambda: lik.scan(obs, x, "v", offsets)):
        a, b = both(fn)
        np.testing.assert_array_equal(a, b)


@pytest.mark.slow
def test_plate_tracks_identical_with_kernels(plate_clip):
    _, _, a = track(plate_clip, "plate", "lis", 60, 30, fast=False)
    _, _, b = track(plate_clip, "plate", "lis", 60, 30, fast=True)
    np.testing.assert_array_equal(np.array(b), np.array(a))


def test_appearance_kernels_equal_the_numpy_path():
    from vistrack.appearance.cues import Appearance

    rng = np.random.default_rng(0)
    frame = cv2.GaussianBlur(rng.integers(0, 256, (120, 160, 3), dtype=np.uint8), (0, 0), 2)
    cv2.rectangle(frame, (60, 40), (100, 80), (30, 200, 220), -1)
    a, b = both(lambda: colour_bins(frame))
    np.testing.assert_array_equal(a, b)
    a, b = both(lambda: bin_integrals(colour_bins(frame), 28))
    np.testing.assert_array_equal(a, b)
    app = Appearance(frame, (60, 40, 41, 41))
    obs = app.frame(frame, (20, 10, 150, 110))
    boxes = np.column_stack([80 + rng.normal(0, 6, 50), 60 + rng.normal(0, 6, 50), np.full(50, 41.0),
                             np.full(50, 41.0)])
    boxes[0, :2] = (3.0, 2.0)  # reaching over the region's border
    a, b = both(lambda: app.ncc(obs, boxes))
    np.testing.assert_allclose(b, a, rtol=1e-12)
    a, b = both(lambda: app.loglik(obs, boxes))
    np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)


def test_warm_up_leaves_the_track_as_it_was(contour_clip):
    _, _, a = track(contour_clip, "contour", "ls-n-ips", 30, 5, fast=True, init_gt="")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = build_model("contour", contour_clip, init_gt="")
        filt = make_filter("ls-n-ips", model)
        warm_up(filt, 30, dict(contour_clip.source)[0])
        stepper = Stepper(filt, 30, np.random.default_rng(0))
        b = [stepper.step(i, f).particles.states.copy() for (i, f), _ in zip(contour_clip.source, range(5))]
    np.testing.assert_array_equal(np.array(b), np.array(a))


def test_every_kernel_releases_the_gil():
    """``vistrack run`` decodes in a thread beside the tracking: every compiled entry point must let
    it run (the private and inlined helpers run inside an entry point, which has released the GIL
    already)."""
    import importlib
    import pkgutil

    from numba.core.registry import CPUDispatcher

    import vistrack

    # every compiled module: vistrack.kernels's and each model package's ``*kernels`` modules
    names = [m.name for m in pkgutil.walk_packages(vistrack.__path__, "vistrack.")
             if m.name.startswith("vistrack.kernels.") or m.name.endswith("kernels")]
    assert {"vistrack.kernels.sampling", "vistrack.models.box.kernels",
            "vistrack.models.plate.scan_kernels"} <= set(names)
    kernels = [(m, k, f) for m in names for k, f in vars(importlib.import_module(m)).items()
               if isinstance(f, CPUDispatcher) and f.__module__ == m]
    assert len([k for _, k, _ in kernels if not k.startswith("_")]) > 25
    held = [f"{m}.{k}" for m, k, f in kernels
            if not (k.startswith("_") or f.targetoptions.get("forceinline") or f.targetoptions.get("nogil"))]
    assert held == []
