"""Closed uniform cubic B-splines, similarity poses, and edge features along measurement lines
(thesis 001, §1.3.1; the contour model's geometry, :mod:`~vistrack.models.contour.model`)."""

from __future__ import annotations

import numpy as np

__all__ = ["BSpline", "ellipse_template", "pose_from", "pose_params", "edge_peaks", "shape_matrices",
           "template_normals"]

_M = np.array([[-1.0, 3, -3, 1], [3, -6, 3, 0], [-3, 0, 3, 0], [1, 4, 1, 0]]) / 6.0


def _basis(t, n, deriv=0):
    """Control-point weights ``(len(t), n)`` of a closed uniform cubic B-spline at ``t``
    (``t`` in units of segments; support point ``i`` sits at ``t = i``)."""
    t = np.asarray(t, dtype=float) % n
    k = np.floor(t).astype(int)
    u = t - k
    if deriv == 0:
        pw = np.stack([u**3, u**2, u, np.ones_like(u)], axis=1)
    else:
        pw = np.stack([3 * u**2, 2 * u, np.ones_like(u), np.zeros_like(u)], axis=1)
    w = pw @ _M  # weights of control points k-1, k, k+1, k+2
    out = np.zeros((len(t), n))
    rows = np.arange(len(t))
    for j in range(4):
        np.add.at(out, (rows, (k - 1 + j) % n), w[:, j])
    return out


class BSpline:
    """Closed uniform cubic B-spline through ``n`` support points (§1.3.1, §4.3.1)."""

    def __init__(self, n):
        if n < 4:
            raise ValueError(f"a closed cubic B-spline needs at least 4 support points, got {n}")
        self.n = n
        a = np.zeros((n, n))
        idx = np.arange(n)
        a[idx, idx] = 4 / 6
        a[idx, (idx + 1) % n] = 1 / 6
        a[idx, (idx - 1) % n] = 1 / 6
        self.A = a
        self.A_inv = np.linalg.inv(a)
        # B = A^-T (1/L ∫ φ φ^T) A^-1, the Gram integral by 64-point-per-segment midpoint rule
        t = (np.arange(64 * n) + 0.5) / 64
        phi = _basis(t, n)
        self.B = self.A_inv.T @ (phi.T @ phi / len(t)) @ self.A_inv

    def curve_matrix(self, t, deriv=0):
        """``C (len(t), n)`` with curve points ``s(t) = C q`` for support points ``q``."""
        return _basis(t, self.n, deriv) @ self.A_inv

    def dense(self, per_segment=8):
        """Curve matrix for ``per_segment`` points per segment (for drawing and sizes)."""
        return self.curve_matrix(np.arange(self.n * per_segment) / per_segment)


def ellipse_template(w, h, n=24):
    """Support points of an axis-aligned ellipse of width ``w`` and height ``h``, centred."""
    phi = 2 * np.pi * np.arange(n) / n
    return np.stack([0.5 * w * np.cos(phi), 0.5 * h * np.sin(phi)], axis=1)


def pose_from(cx, cy, scale, angle_deg):
    """``z = (cx, cy, a, b)`` for a centre, scale and angle (degrees)."""
    th = np.deg2rad(angle_deg)
    return np.array([cx, cy, scale * np.cos(th) - 1.0, scale * np.sin(th)], dtype=float)


def pose_params(z):
    """``(scale, angle_deg)`` of poses ``z (..., 4)``."""
    z = np.asarray(z, float)
    return np.hypot(1 + z[..., 2], z[..., 3]), np.rad2deg(np.arctan2(z[..., 3], 1 + z[..., 2]))


def edge_peaks(gn, thresh):
    """Local maxima of the edge strength ``gn >= 0`` along the last axis above ``thresh`` (edge features)."""
    m = gn
    peak = m > thresh
    peak[..., 1:] &= m[..., 1:] >= m[..., :-1]
    peak[..., :-1] &= m[..., :-1] > m[..., 1:]
    return peak


def template_normals(spline, q0, t):
    """Outward unit normals ``(len(t), 2)`` of the curve of support points ``q0 (n, 2)`` at
    spline parameters ``t``."""
    tang = spline.curve_matrix(t, deriv=1) @ q0
    nrm = np.stack([tang[:, 1], -tang[:, 0]], axis=1)
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    pts = spline.curve_matrix(t) @ q0
    return -nrm if np.sum(np.einsum("ij,ij->i", nrm, pts)) < 0 else nrm


def shape_matrices(spline, q0, measure_per_segment):
    """The contour's fixed matrices for the centred template ``q0 (n, 2)`` (thesis §1.3.1, §4.3.1).

    Returns a dict: ``W (2n, 4)`` (eq. 1.1, ``q = W z + q0``), ``W_plus (4, 2n)``
    (``(Wᵀ U W)⁻¹ Wᵀ U`` with the spline norm ``U = diag(B, B)``), ``normals0 (n, 2)`` (outward
    normals at the support points), ``meas0 (M, 2)`` and ``meas_normals0 (M, 2)`` (the
    ``M = n · measure_per_segment`` measurement points and their normals) and
    ``W_meas_plus (4, 2M)`` (the least-squares pose of measured points).
    """
    n = len(q0)
    qx, qy = q0[:, 0], q0[:, 1]
    one, zero = np.ones(n), np.zeros(n)
    W = np.block([[one[:, None], zero[:, None], qx[:, None], -qy[:, None]],
                  [zero[:, None], one[:, None], qy[:, None], qx[:, None]]])
    U = np.kron(np.eye(2), spline.B)
    t_meas = np.arange(n * measure_per_segment) / measure_per_segment
    meas0 = spline.curve_matrix(t_meas) @ q0
    mx, my = meas0[:, 0], meas0[:, 1]
    one_m, zero_m = np.ones(len(mx)), np.zeros(len(mx))
    w_m = np.block([[one_m[:, None], zero_m[:, None], mx[:, None], -my[:, None]],
                    [zero_m[:, None], one_m[:, None], my[:, None], mx[:, None]]])
    return {"W": W, "W_plus": np.linalg.solve(W.T @ U @ W, W.T @ U),
            "normals0": template_normals(spline, q0, np.arange(n)), "meas0": meas0,
            "meas_normals0": template_normals(spline, q0, t_meas), "W_meas_plus": np.linalg.pinv(w_m)}
