"""B-spline contour tracking (thesis 001, §1.3.1, §4.3.1, §4.4.3).

Contour
    A closed uniform cubic B-spline through ``n`` support points ``q`` (they lie
    on the curve): ``s(t) = Φ(t) A^-1 q`` with ``A`` the circulant
    ``(1/6, 4/6, 1/6)`` mapping control to support points.
Pose (eq. 1.1)
    ``q = W z + q0`` with ``W = [[1, 0, q0x, -q0y], [0, 1, q0y, q0x]]`` and the
    template ``q0`` centred on its support points' mean, so ``z = (cx, cy, a, b)``
    is the centre and ``(1 + a) + i b = scale · e^{i angle}``. ``z = 0`` is the
    template at the origin (the identity similarity).
State
    ``(z_t, z_{t-1})``, shape ``(N, 8)``; AR(2) dynamics
    ``z_t = z_{t-1} + d (z_{t-1} - z_{t-2}) + σ ε`` with the velocity carried over
    (``d = 0.8``) on translation and a random walk (``d = 0``) on ``a, b``.
Likelihood (Blake and Isard; §1.3.1)
    Along the outward unit normal ``n_i`` at each measurement point (two per spline
    segment) the gradient component along the normal, ``g · n_i``, is sampled bilinearly at
    offsets ``ν_k = k`` px, ``|k| <= half_line`` (``g``: Sobel of the frame
    smoothed by a Gaussian of std ``gradient_sigma`` = 1 px, which damps sensor
    noise and the loss of motion-blurred edges). Edge features are the local
    maxima of ``|g · n_i|`` above ``τ = edge_threshold · mean|∇I|`` of the
    frame whose direction is within ~32° of the contour's (``|g · n| >= 0.85 |g|``). With non-detection
    probability ``q`` and clutter density ``λ``
    (features per pixel of line), each line contributes

        log(1 + (1 / (sqrt(2π) σ q λ)) Σ_j exp(-ν_j² / (2 σ²)))

    and lines are independent: ``log r = Σ_i`` of that. One array operation
    covers N particles × n normals × L samples.
Local search ``LS_λ`` (§4.3, eq. 4.1; LMS of §4.3.1)
    The best translation on a grid within ``λ`` (from one set of long lines),
    then an LMS fit of the nearest edges for scale and rotation
    (:meth:`Contour.local_search`); the move is rejected when ``|ẑ - z| > λ`` in
    any coordinate, ``λ = (7, 7, 0.15, 0.1)`` (§4.3.2) for (cx, cy, a, b) with the
    translation part scaled by frame width / 240. The plain LMS step at the
    support points, ``ẑ = W⁺ (q̂ - q0)`` with ``W⁺ = (WᵀUW)⁻¹WᵀU`` and
    ``U = diag(B, B)`` the spline norm, search length ``l = l0 · (size/60) · scale``
    (``l0 = 16``), is :meth:`Contour.lms_step`.
Colour term (real footage; beyond the seeds; :meth:`Contour.learn_colour`)
    On colour video ``log r = log r_edges + log r_c``, the box model's colour term on points
    inside the curve against a band outside it (:mod:`~vistrack.models.contour.colour`);
    ``colour=None`` (the class default, and the thesis experiments): edges only.
Local moves for LLS and LIS act on translation only (§4.4.3): the edge
    features along the normals already sampled give, for a translation ``δ``,
    the shifted edge distances ``ν_j - n_i · δ``, so ``r`` on a whole grid of
    translations costs one matrix product (an approximation of ``r`` used
    only inside the proposal; weights use the exact ``r`` at the final point).
Lost
    ``visible=0`` where the curve shrinks below 0.3 of its first scale, its centre leaves the
    frame or ``log r`` at the estimate falls under 0.15 of its running level
    (:mod:`~vistrack.models.collapse`).
"""

from __future__ import annotations

import numpy as np

from ... import kernels
from ...appearance.features import remap_points
from ...core.gaussian import diag_logpdf
from ...proposals.translation import TranslationMoves
from ..collapse import CollapseCheck
from ..innovation import ARInnovation
from ..protocol import VideoModelBase
from .colour import ContourColour
from .moves import ContourMoves
from .spline import BSpline, edge_peaks, ellipse_template, pose_from, pose_params, shape_matrices

__all__ = ["BSpline", "Contour", "ellipse_template", "pose_from", "pose_params"]


class Contour(CollapseCheck, ContourMoves, ContourColour, TranslationMoves, ARInnovation, VideoModelBase):
    """Contour tracking model with similarity pose and AR(2) dynamics.

    Parameters
    ----------
    template : array_like of shape (n, 2)
        Support points ``q0`` of the template (pixels); centred here.
    init_pose : array_like of shape (4,)
        Pose ``z = (cx, cy, a, b)`` of the object in the first frame (prior mean).
    frame_size : tuple of int
        ``(width, height)``; scales the thesis's pixel parameters (240×180 frames).
    sigma_xy, sigma_a, sigma_b : float
        Process noise std of translation (default ``0.08 · size``), ``a`` and ``b``.
    damping : float
        Velocity carried over, ``d`` in ``z_t = z_{t-1} + d (z_{t-1} - z_{t-2}) + σ ε``.
    prior_std : array_like of shape (4,), optional
        Std of ``p_0`` around ``init_pose`` (default ``(σ_xy, σ_xy, 0.03, 0.03)``).
    sigma_edge : float
        Std (px) of the edge position along a normal (default ``2 · size / 60``, at least 1.5).
    half_line : int
        Likelihood measurement lines span ``±half_line`` px (default ``ceil(3 σ_edge) + 1``).
    q_miss, clutter_density : float
        Non-detection probability ``q`` and clutter features per px ``λ``.
    edge_threshold : float
        Edge features need ``|g · n| > edge_threshold · mean|∇I|``.
    cos_min : float
        ... and an edge direction within ``arccos(cos_min)`` of the contour's
        (``|g · n| >= cos_min |g|``; 0.85 is about 32°).
    search_length : float
        ``l0`` of the local search at the thesis's 60-px scale (16).
    search_lambda : array_like of shape (4,)
        ``λ`` of ``LS_λ`` for ``(cx, cy, a, b)`` at 240-px frame width.
    search_grid_step : float
        Spacing of the local search's translation grid, in units of ``sigma_edge``.
    search_check : bool
        Keep a local-search move only if the exact likelihood does not drop
        (eq. 4.1's ``r(y|LS_λ(x, y)) >= r(y|x)``; ``r(y|x)`` comes from the search's
        own measurement lines, so the check costs no extra likelihood evaluation).
    measure_per_segment : int
        Measurement lines per spline segment (2: ``M = 2n`` lines).
    polarity : {None, 1, -1}
        Edge polarity along the outward normal (see :meth:`learn_polarity`);
        ``None`` for unsigned edges.
    gradient_sigma : float
        Std (px) of the Gaussian that smooths the image before the Sobel gradient
        that every measurement line reads (0: the raw Sobel maps).
    search : {"lms", "nn"}
        The local search of LS-N-IPS (§4.3.1): the LMS fit, or the neural network trained on
        simulated measurements (:mod:`~vistrack.models.contour.nn`, Fig. 4.5).
    """

    dim = 8
    #: lost (``visible=0``) when the scale falls below 0.3 of the first frame's, or ``log r``
    #: at the estimate under 0.15 of its running level (:mod:`~vistrack.models.collapse`): the
    #: edge evidence of a curve on nothing but clutter (an object that vanishes: 0.05-0.08;
    #: the lowest while tracking girl, hand and car4, in a motion-blurred hand frame: 0.24)
    collapse_options = {"ratio": 0.15}

    def __init__(self, template, init_pose, frame_size, *, sigma_xy=None, sigma_a=0.02, sigma_b=0.03,
                 damping=0.8, prior_std=None, sigma_edge=None, half_line=None, q_miss=0.1,
                 clutter_density=0.05, edge_threshold=2.0, cos_min=0.85, search_length=16.0,
                 search_lambda=(7.0, 7.0, 0.15, 0.1), search_grid_step=1.5,
                 search_check=True, measure_per_segment=2, polarity=None, gradient_sigma=1.0, search="lms"):
        q0 = np.asarray(template, dtype=float)
        if q0.ndim != 2 or q0.shape[1] != 2 or len(q0) < 4:
            raise ValueError("template must be an (n, 2) array of at least 4 support points")
        self.q0 = q0 - q0.mean(axis=0)
        self.n = len(q0)
        self.spline = BSpline(self.n)
        self.frame_size = (int(frame_size[0]), int(frame_size[1]))
        dense = self.spline.dense() @ self.q0
        self.size = float(np.mean(dense.max(axis=0) - dense.min(axis=0)))
        if not self.size > 0:
            raise ValueError("template has zero size")
        ref = self.size / 60.0
        m = shape_matrices(self.spline, self.q0, measure_per_segment)  # W, W⁺ (eq. 1.1, §4.3.1), normals
        self.W, self.W_plus, self.normals0 = m["W"], m["W_plus"], m["normals0"]
        self.meas0, self.meas_normals0, self.W_meas_plus = m["meas0"], m["meas_normals0"], m["W_meas_plus"]
        self.dense_matrix = self.spline.dense()
        self.polarity = polarity
        self.gradient_sigma = float(gradient_sigma)
        self.init_pose = np.asarray(init_pose, dtype=float).reshape(4)
        self.sigma = np.array([sigma_xy if sigma_xy is not None else 0.08 * self.size,
                               0, sigma_a, sigma_b], dtype=float)
        self.sigma[1] = self.sigma[0]
        self.damping = np.array([damping, damping, 0.0, 0.0])
        ps = np.array(prior_std if prior_std is not None else (self.sigma[0], self.sigma[0], 0.03, 0.03), float)
        self.prior_std = ps
        self.prior_mean = np.concatenate([self.init_pose, self.init_pose])
        self.sigma_edge = float(sigma_edge if sigma_edge is not None else max(1.5, 2.0 * ref))
        self.half_line = int(half_line if half_line is not None else np.ceil(3 * self.sigma_edge) + 1)
        self.line_offsets = np.arange(-self.half_line, self.half_line + 1, dtype=float)
        self.log_c = -np.log(np.sqrt(2 * np.pi) * self.sigma_edge * q_miss * clutter_density)
        self.edge_threshold = float(edge_threshold)
        self.cos_min = float(cos_min)
        self.search_length = float(search_length) * ref
        self.grid_step = float(search_grid_step)
        self.search_check = bool(search_check)
        frame_ref = self.frame_size[0] / 240.0
        lam = np.asarray(search_lambda, dtype=float).copy()
        lam[:2] *= frame_ref
        self.search_lambda = lam
        if search not in ("lms", "nn"):
            raise ValueError(f"unknown local search {search!r}; choose lms or nn")
        self.search = search
        self.nn_search = None  # the network of search="nn", trained or loaded on first use (contour_nn)
        self.point_keys = [f"qx{i}" for i in range(self.n)] + [f"qy{i}" for i in range(self.n)]  # describe()'s

    @classmethod
    def from_box(cls, box, frame_size, *, n=24, **kwargs):
        """An ellipse template fitted to the box ``(x, y, w, h)``, starting there."""
        x, y, w, h = (float(v) for v in box)
        if not (w > 0 and h > 0):
            raise ValueError(f"init box needs positive width and height, got {w}x{h}")
        return cls(ellipse_template(w, h, n), (x + w / 2, y + h / 2, 0.0, 0.0), frame_size, **kwargs)

    @classmethod
    def from_template(cls, support, frame_size, *, cx, cy, scale=1.0, angle_deg=0.0, **kwargs):
        """Template support points (scale 1, angle 0) starting at pose ``(cx, cy, scale, angle)``."""
        return cls(support, pose_from(cx, cy, scale, angle_deg), frame_size, **kwargs)

    # -- geometry ---------------------------------------------------------------
    @staticmethod
    def _rot(z):
        """``(1 + a, b)`` per pose: the similarity's linear part."""
        return 1.0 + z[..., 2], z[..., 3]

    def place_points(self, z, pts0):
        """Template points ``pts0 (m, 2)`` under poses ``z (N, 4)``: ``(N, m, 2)``."""
        c, s = self._rot(z)
        px, py = pts0[:, 0], pts0[:, 1]
        x = z[:, 0:1] + c[:, None] * px - s[:, None] * py
        y = z[:, 1:2] + s[:, None] * px + c[:, None] * py
        return np.stack([x, y], axis=-1)

    def _turn(self, z, n0):
        """Unit vectors ``n0 (m, 2)`` rotated by the poses' angles: ``(N, m, 2)``."""
        c, s = self._rot(z)
        r = np.maximum(np.hypot(c, s), 1e-12)
        c, s = (c / r)[:, None], (s / r)[:, None]
        nx, ny = n0[:, 0], n0[:, 1]
        return np.stack([c * nx - s * ny, s * nx + c * ny], axis=-1)

    def _placed(self, z, pts0, n0):
        """:meth:`place_points` and :meth:`_turn` of ``pts0, n0`` (compiled where the kernels are on; equal)."""
        if kernels.use():
            from .kernels import place
            return place(z, pts0, n0, *(np.empty((len(z),) + pts0.shape) for _ in "qn"))
        return self.place_points(z, pts0), self._turn(z, n0)

    def support_points(self, z):
        """Support points ``q = W z + q0`` as ``(N, n, 2)`` for poses ``z (N, 4)``."""
        return self._placed(z, self.q0, self.normals0)[0] if kernels.use() else self.place_points(z, self.q0)

    def normals(self, z):
        """Unit outward normals ``(N, n, 2)`` at the support points."""
        return self._turn(z, self.normals0)

    def measurement_lines(self, z):
        """Measurement points and unit normals ``(N, M, 2)`` each (likelihood lines)."""
        return self._placed(z, self.meas0, self.meas_normals0)

    def outline(self, states, per_segment=8):
        """Dense curve points ``(N, n·per_segment, 2)`` of the contours of ``states``."""
        z = np.atleast_2d(states)[:, :4]
        q = self.support_points(z)
        mat = self.dense_matrix if per_segment == 8 else self.spline.dense(per_segment)
        return np.matmul(mat, q)  # (m, n) @ (N, n, 2); 14x faster than the einsum for one state

    def box(self, states):
        """Bounding boxes ``(N, 4)`` as ``(x, y, w, h)`` of the contours."""
        pts = self.outline(states)
        lo, hi = pts.min(axis=1), pts.max(axis=1)
        return np.concatenate([lo, hi - lo], axis=1)

    # -- dynamics ---------------------------------------------------------------
    def sample_prior(self, n, rng):
        """``n`` states ``(n, 8)`` from ``p_0``: a Gaussian about the initial pose, zero velocity (previous =
        current)."""
        z = self.init_pose + self.prior_std * rng.standard_normal((n, 4))
        return np.concatenate([z, z], axis=1)

    def prior_logpdf(self, states):
        """``log p_0`` of the current pose of ``states (N, 8)`` -> ``(N,)``."""
        return diag_logpdf(states[:, :4], self.init_pose, self.prior_std)

    def predict_mean(self, states):
        """The mean of the AR(2) ``K`` (thesis 001 §1.3.1): ``z + d (z - z')``, with ``z`` as the new previous pose;
        ``(N, 8)`` -> ``(N, 8)``."""
        z1, z2 = states[:, :4], states[:, 4:]
        return np.concatenate([z1 + self.damping * (z1 - z2), z1], axis=1)

    def predict(self, states, rng):
        """A draw from ``K`` (§1.3.1): the mean plus ``σ ε`` on the pose ``(cx, cy, a, b)``; ``(N, 8)`` ->
        ``(N, 8)``."""
        out = self.predict_mean(states)
        out[:, :4] += self.sigma * rng.standard_normal((len(states), 4))
        return out

    def transition_logpdf(self, new, old):
        """``log K(new|old)``: Gaussian in ``z_t``; ``z_{t-1}`` of ``new`` is ``z_t`` of ``old``."""
        return diag_logpdf(new[:, :4], self.predict_mean(old)[:, :4], self.sigma)

    def innovation_std(self, old):
        """Std ``(N, 4)`` of ``z_t`` given ``old`` (:class:`~vistrack.models.innovation.ARInnovation`)."""
        return np.broadcast_to(self.sigma, (len(old), 4))

    # -- likelihood -------------------------------------------------------------
    def _lines32(self, obs, z, support=False, lines=None):
        """The gradient map and the float32 points and unit normals ``(N, M, 2)`` of the
        measurement lines (at the support points with ``support=True``; ``lines``: the lines
        of ``z`` already placed)."""
        if lines is None:
            lines = (self.support_points(z), self.normals(z)) if support else self.measurement_lines(z)
        q, nrm = lines
        return obs.gradient(self.gradient_sigma)[0], q.astype(np.float32), nrm.astype(np.float32)

    def edge_profiles(self, obs, z, offsets, support=False, lines=None):
        """Edge strength along the measurement lines ``(N, M, L)`` at ``offsets``
        (``(L,)`` or ``(N, 1, L)``; at the support points with ``support=True``).

        The normal gradient ``|g · n|`` (or ``polarity · g · n`` clipped at 0 when
        the model has a polarity), zeroed where the edge direction is more than
        ``arccos(cos_min)`` off the contour's (``|g · n| < cos_min · |g|``).
        Compiled (:func:`vistrack.models.contour.kernels.profiles`, equal) where numba is.
        """
        gxy, q, nrm = self._lines32(obs, z, support, lines)
        off = np.asarray(offsets, dtype=np.float32)
        if kernels.use():
            from .kernels import profiles

            out = np.empty(q.shape[:2] + off.shape[-1:], np.float32)
            return profiles(gxy, q, nrm, off.reshape(-1, off.shape[-1]), self.polarity or 0,
                            np.float32(self.cos_min**2), out)
        nx, ny = nrm[..., 0:1], nrm[..., 1:2]
        g = remap_points(gxy, q[..., 0:1] + nx * off, q[..., 1:2] + ny * off)
        gx, gy = g[..., 0], g[..., 1]
        gn = gx * nx
        gn += gy * ny
        if self.polarity:
            gn *= self.polarity
            np.maximum(gn, 0.0, out=gn)
        else:
            np.abs(gn, out=gn)
        gx *= gx
        gy *= gy
        gx += gy
        gx *= self.cos_min**2  # cos² · |g|²
        gy = np.multiply(gn, gn, out=gy)  # (g · n)²
        np.copyto(gn, 0.0, where=gy < gx)
        return gn

    def learn_polarity(self, obs, agree=0.75):
        """Set ``polarity`` from the first frame at the initial pose: the sign of ``g · n``
        at the strongest edge near each measurement point, if at least ``agree`` of
        them share it (an object darker or brighter than its surroundings); else
        leave edges unsigned. Returns the polarity (``+1``, ``-1`` or ``None``)."""
        saved, self.polarity = self.polarity, None
        z = self.init_pose[None]
        off = np.arange(-2.0, 2.5, 0.5)
        q, nrm = self.measurement_lines(z)
        g = obs.sample_gradient(q[..., 0:1] + nrm[..., 0:1] * off, q[..., 1:2] + nrm[..., 1:2] * off,
                                self.gradient_sigma)
        gn = (g[..., 0] * nrm[..., 0:1] + g[..., 1] * nrm[..., 1:2])[0]  # (M, L)
        best = np.take_along_axis(gn, np.argmax(np.abs(gn), axis=1)[:, None], 1)[:, 0]
        strong = np.abs(best) > self.feature_threshold(obs)
        self.polarity = saved
        if strong.sum() < 0.5 * len(best):
            return self.polarity
        frac = np.mean(best[strong] > 0)
        if frac >= agree:
            self.polarity = 1
        elif frac <= 1 - agree:
            self.polarity = -1
        return self.polarity

    def feature_threshold(self, obs):
        return self.edge_threshold * max(obs.gradient(self.gradient_sigma)[1], 1e-6)

    def loglik(self, obs, states):
        """Blake–Isard measurement-line log-likelihood (module docstring) ``(N,)``."""
        z = states[:, :4]
        if kernels.use():
            from .kernels import loglik

            gxy, q, nrm = self._lines32(obs, z)
            ll = loglik(gxy, q, nrm, self.line_offsets.astype(np.float32), self.polarity or 0,
                        np.float32(self.cos_min**2), np.float32(self.feature_threshold(obs)), self._line_kernel(),
                        np.exp(self.log_c), np.empty(len(z)))
        else:
            ll = self._loglik_from_profiles(self.edge_profiles(obs, z, self.line_offsets), self.feature_threshold(obs))
        if self.colour is not None:
            ll = ll + self.colour_loglik(obs, z)
        return ll

    def _line_kernel(self):
        """The Gaussian of the edge position at :attr:`line_offsets`."""
        return np.exp(-0.5 * (self.line_offsets / self.sigma_edge) ** 2)

    def _loglik_from_profiles(self, gn, thresh, lo=0):
        """``log r`` from edge strengths ``(N, M, L')`` whose samples ``lo .. lo + L`` are at
        :attr:`line_offsets`."""
        n = len(self.line_offsets)
        if kernels.use():
            from .kernels import loglik_profiles

            return loglik_profiles(gn, lo, n, np.float32(thresh), self._line_kernel(), np.exp(self.log_c),
                                   np.empty(len(gn)))
        peaks = edge_peaks(gn[..., lo:lo + n], thresh)
        return np.sum(np.log1p(np.exp(self.log_c) * (peaks @ self._line_kernel())), axis=1)

    # -- output -------------------------------------------------------------------
    def collapse_pose(self, state):
        """``(scale, cx, cy)`` of ``state`` as :meth:`describe` gives them, without the outline."""
        return float(pose_params(np.asarray(state, float).reshape(-1)[:4])[0]), state[0], state[1]

    def describe(self, state):
        """Track-file fields of one state: centre, box, angle, scale, support points (Python floats)."""
        z = np.asarray(state, float).reshape(-1)[:4]
        q = self.support_points(z[None])[0]
        pts = self.dense_matrix @ q  # the outline, as box() draws it
        x, y = pts[:, 0], pts[:, 1]
        scale, angle = pose_params(z)
        row = dict(zip(("cx", "cy"), z[:2].tolist()), w=float(x.max() - x.min()), h=float(y.max() - y.min()),
                   angle_deg=float(angle), scale=float(scale))
        row.update(zip(self.point_keys, q.T.ravel().tolist()))
        return row
