"""The correlation filter's whole-frame search (issue 53): its channels' correlations summed in the Fourier
domain equal OpenCV's ``filter2D`` of each channel summed, and the taps are made once until the filter adapts."""

from __future__ import annotations

import cv2
import numpy as np
import scipy.fft as sfft

from vistrack.appearance.correlation import CorrelationFilter, dcf_features, shrunk_grey


def _frame(seed, shape=(120, 160, 3)):
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.integers(0, 256, shape, dtype=np.uint8), (0, 0), 1.5)


def test_fourier_sum_equals_filter2d_per_channel():
    cf = CorrelationFilter(_frame(1), (60.0, 40.0, 24.0, 30.0))
    frame = _frame(2)
    for stride, crop in ((2, 1.0), (4, 1.0), (2, None)):
        taps, (ay, ax) = cf.search_taps(stride, crop)
        s = cf.f / stride
        img = shrunk_grey(frame, s)
        feat = dcf_features(img, cf.n_orient)
        want = sum(cv2.filter2D(feat[c].astype(np.float64), -1, taps[c].astype(np.float64), anchor=(int(ax), int(ay)),
                                borderType=cv2.BORDER_CONSTANT) for c in range(len(feat)))
        shape = (sfft.next_fast_len(img.shape[0] + taps.shape[1] - 1, real=True),
                 sfft.next_fast_len(img.shape[1] + taps.shape[2] - 1, real=True))
        corr = sfft.irfft2(np.einsum("cij,cij->ij", sfft.rfft2(feat, s=shape), np.conj(sfft.rfft2(taps, s=shape))),
                           s=shape)
        got = corr[(np.arange(img.shape[0]) - ay) % shape[0]][:, (np.arange(img.shape[1]) - ax) % shape[1]]
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-4 * np.abs(want).max())
        best = np.unravel_index(np.argmax(want), want.shape)
        x, y, _ = cf.search(frame, 0.0, stride=stride, crop=crop)
        assert (x, y) == ((best[1] + 0.5) / s, (best[0] + 0.5) / s)


def test_taps_kept_until_the_filter_adapts():
    frame = _frame(3)
    cf = CorrelationFilter(frame, (60.0, 40.0, 24.0, 30.0))
    first = cf.search_taps(2, 1.0)
    assert cf.search_taps(2, 1.0) is first
    cf.adapt(frame, np.array([72.0, 55.0]), 0.0)
    again = cf.search_taps(2, 1.0)
    assert again is not first and again[1] == first[1]


def test_shrunk_grey_is_the_grey_frame_at_the_scale():
    rng = np.random.default_rng(5)
    frame = cv2.GaussianBlur(rng.integers(0, 256, (360, 640, 3), dtype=np.uint8), (0, 0), 4.0)  # smooth: no aliasing
    grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY).astype(np.float32)
    for s in (0.9, 0.45, 0.2, 0.07):
        img = shrunk_grey(frame, s)
        assert img.shape == (round(360 * s), round(640 * s)) and img.dtype == np.float32
        want = cv2.resize(grey, img.shape[::-1], interpolation=cv2.INTER_AREA)
        assert np.abs(img - want).mean() < 2.0  # grey levels of 0..255
