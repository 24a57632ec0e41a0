"""The scale filter's samples (:mod:`~vistrack.models.box.scale_filter`), compiled and in numpy.

A sample is a box of the grey patch described by the ``nx × ny`` cells it is cut into: each cell's
mean grey level (normalised by the box's mean and deviation) and ``n_orient`` cells of unsigned gradient
orientation (the gradient by central differences, its magnitude soft-binned by orientation; each
cell divided by the root of its mean squared gradient). The ``S`` samples of one frame are boxes of
``S`` sizes about one point of one patch, so the per-pixel channels (:func:`pixel_channels`: grey,
grey², the squared gradient and the orientation bins) are made once, with their summed-area tables,
and every cell of every sample is a box sum read from them (:func:`scale_samples`): bilinear
interpolation of a summed-area table is the exact integral of the pixel-wise constant channels over
a box with fractional corners, so a cell of any size costs four reads per channel.

The orientation is the polynomial of ``atan`` that OpenCV's ``fastAtan32f`` uses (error below 0.005 rad).
:func:`scale_samples_numpy` is the reference (the same arithmetic in numpy; the compiled one equals it
to 1e-9, ``tests``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["pixel_channels", "scale_samples", "scale_samples_numpy", "N_EXTRA"]

_EPS = 1e-2
#: channels besides the orientation bins in :func:`pixel_channels`: grey, grey², squared gradient
N_EXTRA = 3
#: the odd polynomial of ``atan(c)`` on ``[0, 1]`` (OpenCV's ``fastAtan32f``'s, radians)
_A1, _A3, _A5, _A7 = 0.9997878412794807, -0.3258083974640975, 0.1555786518463281, -0.04432655554792128


@njit(cache=True, nogil=True, inline="always")
def _orientation(gx, gy):
    """The unsigned orientation ``[0, π)`` of the gradient ``(gx, gy)`` by the polynomial of ``atan``."""
    ax, ay = abs(gx), abs(gy)
    c = min(ax, ay) / (max(ax, ay) + 1e-12)
    cc = c * c
    a = (((_A7 * cc + _A5) * cc + _A3) * cc + _A1) * c
    a = 0.5 * math.pi - a if ax < ay else a
    a = math.pi - a if (gx < 0.0) != (gy < 0.0) else a
    return a - math.pi if a >= math.pi else a


@njit(cache=True, nogil=True, error_model="numpy")
def pixel_channels(grey, n_orient, ii):
    """The summed-area tables ``ii (H + 1, W + 1, N_EXTRA + n_orient) float64`` of ``grey (H, W) float32``'s
    per-pixel channels: grey, grey², the squared gradient (central differences, edges held) and the
    gradient magnitude's share of each orientation bin (soft, by the distance to the bin, wrapped)."""
    h, w = grey.shape
    nc = N_EXTRA + n_orient
    inv_pi = n_orient / math.pi
    row = np.zeros(nc)
    for c in range(nc):
        for j in range(w + 1):
            ii[0, j, c] = 0.0
    for i in range(h):
        for c in range(nc):
            row[c] = 0.0
            ii[i + 1, 0, c] = 0.0
        iu, idn = max(i - 1, 0), min(i + 1, h - 1)
        for j in range(w):
            jl, jr = max(j - 1, 0), min(j + 1, w - 1)
            v = float(grey[i, j])
            gx = float(grey[i, jr]) - float(grey[i, jl])
            gy = float(grey[idn, j]) - float(grey[iu, j])
            m2 = gx * gx + gy * gy
            mag = math.sqrt(m2)
            pos = _orientation(gx, gy) * inv_pi
            row[0] += v
            row[1] += v * v
            row[2] += m2
            for c in range(n_orient):
                d = abs(pos - c)
                d = min(d, n_orient - d)
                row[N_EXTRA + c] += mag * max(1.0 - d, 0.0)
            for c in range(nc):
                ii[i + 1, j + 1, c] = ii[i, j + 1, c] + row[c]
    return ii


@njit(cache=True, nogil=True, inline="always")
def _at(ii, x, y, c):
    """The summed-area table ``ii`` read bilinearly at ``(x, y)`` (patch px, clamped to the table)."""
    h, w = ii.shape[0] - 1, ii.shape[1] - 1
    x = min(max(x, 0.0), float(w))
    y = min(max(y, 0.0), float(h))
    x0 = min(int(x), w - 1)
    y0 = min(int(y), h - 1)
    a, b = x - x0, y - y0
    return ((ii[y0, x0, c] * (1 - a) + ii[y0, x0 + 1, c] * a) * (1 - b)
            + (ii[y0 + 1, x0, c] * (1 - a) + ii[y0 + 1, x0 + 1, c] * a) * b)


@njit(cache=True, nogil=True, error_model="numpy")
def scale_samples(ii, ax, ay, widths, heights, nx, ny, n_orient, out):
    """The samples ``out (S, n_orient + 1, ny, nx)`` float32: sample ``k`` is the box ``widths[k] ×
    heights[k]`` (patch px) centred on ``(ax, ay)`` (patch px from the patch's corner), cut into
    ``nx × ny`` cells, its channels read from ``pixel_channels``' tables ``ii`` (module docstring)."""
    corners = np.empty((ny + 1, nx + 1, ii.shape[2]))
    for k in range(widths.shape[0]):
        cw, ch = widths[k] / nx, heights[k] / ny
        x0, y0 = ax - 0.5 * widths[k], ay - 0.5 * heights[k]
        for p in range(ny + 1):
            for q in range(nx + 1):
                for c in range(ii.shape[2]):
                    corners[p, q, c] = _at(ii, x0 + q * cw, y0 + p * ch, c)
        area_all = widths[k] * heights[k]
        s0 = corners[ny, nx, 0] - corners[0, nx, 0] - corners[ny, 0, 0] + corners[0, 0, 0]
        s1 = corners[ny, nx, 1] - corners[0, nx, 1] - corners[ny, 0, 1] + corners[0, 0, 1]
        mean = s0 / area_all
        sd = math.sqrt(max(s1 / area_all - mean * mean, 0.0))
        inv_sd = 1.0 / max(sd, 1.0)
        area = cw * ch
        for p in range(ny):
            for q in range(nx):
                energy = corners[p + 1, q + 1, 2] - corners[p, q + 1, 2] - corners[p + 1, q, 2] + corners[p, q, 2]
                norm = 1.0 / math.sqrt(energy / area + _EPS) / area
                s = corners[p + 1, q + 1, 0] - corners[p, q + 1, 0] - corners[p + 1, q, 0] + corners[p, q, 0]
                out[k, 0, p, q] = (s / area - mean) * inv_sd
                for c in range(N_EXTRA, N_EXTRA + n_orient):
                    b = corners[p + 1, q + 1, c] - corners[p, q + 1, c] - corners[p + 1, q, c] + corners[p, q, c]
                    out[k, 1 + c - N_EXTRA, p, q] = b * norm
    return out


def scale_samples_numpy(grey, ax, ay, widths, heights, nx, ny, n_orient):
    """:func:`pixel_channels` and :func:`scale_samples` in numpy: ``(S, n_orient + 1, ny, nx)`` float64."""
    g = grey.astype(np.float64)
    h, w = g.shape
    gp = np.pad(g, 1, mode="edge")
    gx = gp[1:-1, 2:] - gp[1:-1, :-2]
    gy = gp[2:, 1:-1] - gp[:-2, 1:-1]
    m2 = gx * gx + gy * gy
    mag = np.sqrt(m2)
    ax_, ay_ = np.abs(gx), np.abs(gy)
    c = np.minimum(ax_, ay_) / (np.maximum(ax_, ay_) + 1e-12)
    cc = c * c
    ang = (((_A7 * cc + _A5) * cc + _A3) * cc + _A1) * c
    ang = np.where(ax_ < ay_, 0.5 * np.pi - ang, ang)
    ang = np.where((gx < 0) != (gy < 0), np.pi - ang, ang)
    ang = np.where(ang >= np.pi, ang - np.pi, ang)
    pos = ang * (n_orient / np.pi)
    chans = [g, g * g, m2]
    for k in range(n_orient):
        d = np.abs(pos - k)
        d = np.minimum(d, n_orient - d)
        chans.append(mag * np.maximum(1.0 - d, 0.0))
    ii = np.zeros((h + 1, w + 1, len(chans)))
    ii[1:, 1:] = np.cumsum(np.cumsum(np.stack(chans, axis=-1), axis=0), axis=1)

    def at(x, y):
        x = np.clip(x, 0.0, float(w))
        y = np.clip(y, 0.0, float(h))
        x0 = np.minimum(x.astype(int), w - 1)
        y0 = np.minimum(y.astype(int), h - 1)
        a, b = (x - x0)[..., None], (y - y0)[..., None]
        return ((ii[y0, x0] * (1 - a) + ii[y0, x0 + 1] * a) * (1 - b)
                + (ii[y0 + 1, x0] * (1 - a) + ii[y0 + 1, x0 + 1] * a) * b)

    out = np.zeros((len(widths), n_orient + 1, ny, nx))
    for k, (bw, bh) in enumerate(zip(widths, heights)):
        cw, ch = bw / nx, bh / ny
        qx = ax - 0.5 * bw + np.arange(nx + 1) * cw
        qy = ay - 0.5 * bh + np.arange(ny + 1) * ch
        corners = at(qx[None, :] + 0 * qy[:, None], qy[:, None] + 0 * qx[None, :])  # (ny+1, nx+1, C)
        boxes = corners[1:, 1:] - corners[:-1, 1:] - corners[1:, :-1] + corners[:-1, :-1]  # (ny, nx, C)
        whole = corners[-1, -1] - corners[0, -1] - corners[-1, 0] + corners[0, 0]
        area_all, area = bw * bh, cw * ch
        mean = whole[0] / area_all
        sd = np.sqrt(max(whole[1] / area_all - mean * mean, 0.0))
        norm = 1.0 / np.sqrt(boxes[..., 2] / area + _EPS) / area
        out[k, 0] = (boxes[..., 0] / area - mean) / max(sd, 1.0)
        out[k, 1:] = np.moveaxis(boxes[..., N_EXTRA:] * norm[..., None], -1, 0)
    return out
