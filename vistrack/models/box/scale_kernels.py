"""The scale filter's samples (:mod:`~vistrack.models.box.scale_filter`), compiled and in numpy.

:func:`scale_samples` resamples a grey patch at ``S`` sizes about a point and describes each sample by
its feature cells: the cells' mean grey level (normalised by the sample's mean and deviation) and
``n_orient`` cells of unsigned gradient orientation (central differences, soft-binned magnitude),
each divided by the root of its cell's mean squared gradient (the orientation by the polynomial of
``atan`` that OpenCV's ``fastAtan32f`` uses). :func:`scale_samples_numpy` is the same
arithmetic in numpy (the reference; the compiled one equals it to float32 rounding, ``tests``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["scale_samples", "scale_samples_numpy"]

_EPS = 1e-2
#: the odd polynomial of ``atan(c)`` on ``[0, 1]`` (OpenCV's ``fastAtan32f``'s, radians; error < 0.005 rad)
_A1, _A3, _A5, _A7 = 0.9997878412794807, -0.3258083974640975, 0.1555786518463281, -0.04432655554792128


@njit(cache=True, nogil=True, inline="always")
def _orientation(gx, gy):
    """The unsigned orientation ``[0, π)`` of the gradient ``(gx, gy)`` by the polynomial of ``atan``."""
    ax, ay = abs(gx), abs(gy)
    c = min(ax, ay) / (max(ax, ay) + 1e-12)
    cc = c * c
    a = (((_A7 * cc + _A5) * cc + _A3) * cc + _A1) * c
    if ax < ay:
        a = 0.5 * math.pi - a
    if (gx < 0.0) != (gy < 0.0):
        a = math.pi - a
    if a >= math.pi:
        a -= math.pi
    return a


@njit(cache=True, nogil=True, error_model="numpy")
def scale_samples(grey, ax, ay, scales, nx, ny, cell, n_orient, out):
    """Samples ``out (S, n_orient + 1, ny, nx) float32`` of ``grey (H, W) float32`` about ``(ax, ay)``
    (patch px, pixel centres at ``+0.5``): sample ``k`` is the patch read bilinearly (edges held) on a
    grid of ``(nx cell + 2) × (ny cell + 2)`` points ``scales[k]`` patch px apart, then described by its
    cells (module docstring)."""
    h, w = grey.shape
    ws, hs = nx * cell + 2, ny * cell + 2
    g = np.empty((hs, ws), np.float32)
    inv_pi = n_orient / math.pi
    area = float(cell * cell)
    for k in range(scales.shape[0]):
        s = scales[k]
        # the sample's grey levels
        total = 0.0
        squares = 0.0
        for i in range(hs):
            v = ay + (i - hs / 2 + 0.5) * s - 0.5
            if v < 0.0:
                v = 0.0
            if v > h - 1:
                v = float(h - 1)
            y0 = min(int(v), h - 2)
            b = v - y0
            for j in range(ws):
                u = ax + (j - ws / 2 + 0.5) * s - 0.5
                if u < 0.0:
                    u = 0.0
                if u > w - 1:
                    u = float(w - 1)
                x0 = min(int(u), w - 2)
                a = u - x0
                val = ((grey[y0, x0] * (1 - a) + grey[y0, x0 + 1] * a) * (1 - b)
                       + (grey[y0 + 1, x0] * (1 - a) + grey[y0 + 1, x0 + 1] * a) * b)
                g[i, j] = val
                if 0 < i < hs - 1 and 0 < j < ws - 1:
                    total += val
                    squares += val * val
        n = (hs - 2) * (ws - 2)
        mean = total / n
        sd = math.sqrt(max(squares / n - mean * mean, 0.0))
        inv_sd = 1.0 / max(sd, 1.0)
        for ci in range(ny):
            for cj in range(nx):
                for c in range(n_orient + 1):
                    out[k, c, ci, cj] = 0.0
                energy = 0.0
                grey_sum = 0.0
                for di in range(cell):
                    i = 1 + ci * cell + di
                    for dj in range(cell):
                        j = 1 + cj * cell + dj
                        gx = g[i, j + 1] - g[i, j - 1]
                        gy = g[i + 1, j] - g[i - 1, j]
                        m2 = gx * gx + gy * gy
                        mag = math.sqrt(m2)
                        pos = _orientation(gx, gy) * inv_pi
                        lo = int(pos)
                        frac = pos - lo
                        lo = lo % n_orient
                        hi = (lo + 1) % n_orient
                        out[k, 1 + lo, ci, cj] += mag * (1.0 - frac)
                        out[k, 1 + hi, ci, cj] += mag * frac
                        energy += m2
                        grey_sum += g[i, j]
                norm = 1.0 / math.sqrt(energy / area + _EPS)
                for c in range(n_orient):
                    out[k, 1 + c, ci, cj] *= norm / area
                out[k, 0, ci, cj] = (grey_sum / area - mean) * inv_sd
    return out


def scale_samples_numpy(grey, ax, ay, scales, nx, ny, cell, n_orient):
    """:func:`scale_samples` in numpy (the same arithmetic, in float64): ``(S, n_orient + 1, ny, nx)``."""
    h, w = grey.shape
    ws, hs = nx * cell + 2, ny * cell + 2
    g0 = grey.astype(np.float64)
    out = np.zeros((len(scales), n_orient + 1, ny, nx))
    for k, s in enumerate(scales):
        v = np.clip(ay + (np.arange(hs) - hs / 2 + 0.5) * s - 0.5, 0, h - 1)
        u = np.clip(ax + (np.arange(ws) - ws / 2 + 0.5) * s - 0.5, 0, w - 1)
        y0 = np.minimum(v.astype(int), h - 2)
        x0 = np.minimum(u.astype(int), w - 2)
        b, a = (v - y0)[:, None], (u - x0)[None, :]
        yy, xx = y0[:, None], x0[None, :]
        g = ((g0[yy, xx] * (1 - a) + g0[yy, xx + 1] * a) * (1 - b)
             + (g0[yy + 1, xx] * (1 - a) + g0[yy + 1, xx + 1] * a) * b)
        inner = g[1:-1, 1:-1]
        mean = inner.mean()
        sd = np.sqrt(max((inner ** 2).mean() - mean ** 2, 0.0))
        gx = g[1:-1, 2:] - g[1:-1, :-2]
        gy = g[2:, 1:-1] - g[:-2, 1:-1]
        mag = np.sqrt(gx ** 2 + gy ** 2)
        ax_, ay_ = np.abs(gx), np.abs(gy)
        c = np.minimum(ax_, ay_) / (np.maximum(ax_, ay_) + 1e-12)
        cc = c * c
        ang = (((_A7 * cc + _A5) * cc + _A3) * cc + _A1) * c
        ang = np.where(ax_ < ay_, 0.5 * np.pi - ang, ang)
        ang = np.where((gx < 0) != (gy < 0), np.pi - ang, ang)
        ang = np.where(ang >= np.pi, ang - np.pi, ang)
        pos = ang * (n_orient / np.pi)
        lo = pos.astype(int)
        frac = pos - lo
        lo %= n_orient
        hi = (lo + 1) % n_orient
        cells = lambda a_: a_.reshape(ny, cell, nx, cell).sum(axis=(1, 3))  # noqa: E731
        area = cell * cell
        norm = 1.0 / np.sqrt(cells(gx ** 2 + gy ** 2) / area + _EPS)
        for c in range(n_orient):
            hist = cells(np.where(lo == c, mag * (1 - frac), 0.0) + np.where(hi == c, mag * frac, 0.0))
            out[k, 1 + c] = hist * norm / area
        out[k, 0] = (cells(inner) / area - mean) / max(sd, 1.0)
    return out
