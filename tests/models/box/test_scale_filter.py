"""The box model's scale filter (DSST's, issue 43): its compiled samples equal the numpy path, its
response peaks at the object's new size, and the correlation proposal drawn about its peak is still
properly weighted (the density integrates to 1; the weighting test is in ``test_box_dcf.py``)."""

import cv2
import numpy as np
import pytest

from vistrack import kernels
from vistrack.models.box.correlation_proposal import CorrelationProposal
from vistrack.models.box.scale_filter import ScaleFilter
from vistrack.models.box.scale_kernels import N_EXTRA, pixel_channels, scale_samples, scale_samples_numpy


def _textured(rng, size=(160, 200)):
    return cv2.GaussianBlur(rng.integers(0, 255, size + (3,)).astype(np.uint8), (0, 0), 1.5)


def _scaled_scene(obj, bg, centre, scale):
    """``bg`` with ``obj`` resized by ``scale`` pasted about ``centre``."""
    h, w = obj.shape[:2]
    sw, sh = int(round(w * scale)), int(round(h * scale))
    f = bg.copy()
    x0, y0 = int(round(centre[0] - sw / 2)), int(round(centre[1] - sh / 2))
    f[y0:y0 + sh, x0:x0 + sw] = cv2.resize(obj, (sw, sh), interpolation=cv2.INTER_LINEAR)
    return f


def test_compiled_samples_equal_the_numpy_path():
    rng = np.random.default_rng(3)
    grey = rng.random((57, 73)).astype(np.float32) * 255
    n_orient, nx, ny = 6, 5, 4
    widths, heights = 20 * np.exp(np.linspace(-0.3, 0.3, 9)), 16 * np.exp(np.linspace(-0.3, 0.3, 9))
    ii = pixel_channels(grey, n_orient, np.empty((58, 74, N_EXTRA + n_orient)))
    got = scale_samples(ii, 36.3, 28.7, widths, heights, nx, ny, n_orient,
                        np.empty((9, n_orient + 1, ny, nx), np.float32))
    want = scale_samples_numpy(grey, 36.3, 28.7, widths, heights, nx, ny, n_orient)
    assert got.shape == want.shape == (9, n_orient + 1, ny, nx)
    np.testing.assert_allclose(got, want, atol=1e-6, rtol=1e-6)


@pytest.mark.parametrize("scale", [0.9, 1.0, 1.12])
@pytest.mark.parametrize("compiled", [True, False])
def test_response_peaks_at_the_objects_new_size(scale, compiled, monkeypatch):
    """The object learnt at size 1 and shown at ``scale`` on the same background: the peak moves towards
    ``log(scale)`` (the scales' Hann window holds it back from far scales), and detecting again about
    each peak reaches ``log(scale)`` within a step (3 %; the upsampled object is blurrier than the one learnt)."""
    monkeypatch.setattr(kernels, "use", lambda: compiled)
    rng = np.random.default_rng(5)
    obj = _textured(rng, (40, 56))
    centre = (100.0, 80.0)
    bg = _textured(rng)
    sf = ScaleFilter(_scaled_scene(obj, bg, centre, 1.0), (72, 60, 56, 40))
    frame = _scaled_scene(obj, bg, centre, scale)
    resp = sf.detect(frame, np.array(centre), 0.0)
    step = np.log(1.03)
    first = resp.peak_log_scale
    assert abs(first - np.log(scale)) < abs(np.log(scale)) / 2 + step / 3
    ls = first
    for _ in range(6):
        ls = sf.detect(frame, np.array(centre), ls).peak_log_scale
    assert ls == pytest.approx(np.log(scale), abs=step)
    assert resp.peak == pytest.approx(resp.values.max()) and 0.3 < resp.peak < 1.5
    assert resp.read(np.array([resp.log_scales[0] - 1.0]))[0] == pytest.approx(resp.values[0])  # held beyond the ends


def test_adapted_filter_follows_a_growing_object():
    """Grown 3 % a frame for 20 frames (1.8x), detected and adapted each frame: the scale read lags
    the truth by less than a step (3 %)."""
    rng = np.random.default_rng(8)
    obj, bg = _textured(rng, (30, 42)), _textured(rng, (200, 240))
    centre = (120.0, 100.0)
    sf = ScaleFilter(_scaled_scene(obj, bg, centre, 1.0), (99, 85, 42, 30))
    ls = 0.0
    for t in range(1, 21):
        f = _scaled_scene(obj, bg, centre, 1.03 ** t)
        ls = sf.detect(f, np.array(centre), ls).peak_log_scale
        sf.adapt(f, np.array(centre), ls)
    assert ls == pytest.approx(20 * np.log(1.03), abs=np.log(1.03))


class _Stub:
    dcf_tempering = (3.0, 0.1)
    dcf_scale_std = 0.05


def test_proposal_about_the_scale_filters_peak_integrates_to_one():
    from vistrack.appearance.correlation import DCFResponse

    rng = np.random.default_rng(0)
    resp = DCFResponse(rng.random((3, 5, 6)).astype(np.float32), [-0.1, 0.0, 0.1], centre=(40.0, 30.0),
                       anchor=(3.0, 2.0), px=[0.55, 0.5, 0.45])
    prop = CorrelationProposal(_Stub(), kernel=None)
    (ox, oy), a = resp.cell_origin()
    centre = 0.137  # the scale filter's peak, off the translation filter's scales
    ls = np.linspace(centre - 0.5, centre + 0.5, 4001)
    at = np.stack([np.full_like(ls, ox), np.full_like(ls, oy), ls], 1)
    line = np.exp(prop.log_density(resp, at, centre))
    cell = np.exp(prop.log_density(resp, np.array([[ox, oy, centre]]), centre))[0] * np.sqrt(2 * np.pi) * 0.05
    assert np.trapezoid(line, ls) == pytest.approx(cell, rel=1e-6)
    assert ls[np.argmax(line)] == pytest.approx(centre, abs=1e-3)
    z = prop.draw(resp, rng.random((20000, 3)), rng.standard_normal(20000), centre)
    assert z[:, 2].mean() == pytest.approx(centre, abs=0.002) and z[:, 2].std() == pytest.approx(0.05, rel=0.03)
