"""The §4.5.2 LIS proposal of the plate model: line scans of ``r^h`` then ``r^v`` on the window,
with a coarse-to-fine search for entering cars (thesis 001, §4.5.2)."""

from __future__ import annotations

import numpy as np

from ... import kernels
from ...core.gaussian import diag_logpdf
from ...core.transition import Transition
from .likelihood import BORDER
from .observation import PlateObservation

__all__ = ["PlateLISProposal", "map_values"]


def map_values(amap, x, y):
    """Bilinear values of a map at frame points ``x, y`` (arrays of one shape): ``amap = (m (H', W')
    float32, a (4,))`` with frame ``x`` at map column ``a[0] x + a[1]`` and ``y`` at row ``a[2] y +
    a[3]``, clamped to the map (:meth:`PlateLISProposal.appearance_map`); float64, the arithmetic of
    :func:`vistrack.models.plate.scan_kernels.map_value` (equal)."""
    m, a = amap
    hh, ww = m.shape
    u = np.minimum(np.maximum(a[0] * x + a[1], 0.0), ww - 1.0)
    v = np.minimum(np.maximum(a[2] * y + a[3], 0.0), hh - 1.0)
    j0, i0 = np.floor(u).astype(np.intp), np.floor(v).astype(np.intp)
    j1, i1 = np.minimum(j0 + 1, ww - 1), np.minimum(i0 + 1, hh - 1)
    fu, fv = u - j0, v - i0
    m00, m01 = m[i0, j0].astype(float), m[i0, j1].astype(float)
    m10, m11 = m[i1, j0].astype(float), m[i1, j1].astype(float)
    top = m00 + fu * (m01 - m00)
    bot = m10 + fu * (m11 - m10)
    return top + fv * (bot - top)


class PlateLISProposal:
    """The §4.5.2 proposal: ``W' ~ r^h(Y|U, ·, θ) g_1(·)``, then ``U' ~ r^v(Y|·, W', θ) g_0(·)``.

    Two kinds of window ``g``:

    * ``window="dynamics"`` (default) for a particle that follows a plate: ``g_1``, ``g_0`` are the
      (w, u) factors of the AR(2) kernel itself, ``N(·; m, σ)`` about the predicted mean ``m``
      (from ``prev``), over ``± window_sigmas σ`` (at most the plate size; the 0.3 % of ``K``'s
      mass per axis beyond 3σ is left out: 4σ was worse, with coarser cells). Then
      ``q(Z) = K_{θ,s}(Z) q^h(W') q^v(U'|W')`` and the weight is ``r(Z) N_{u,w}(Z) / (q^h q^v)``:
      the draw of ``X``'s translation is integrated out, so its factor ``K(Z)/K(X)`` — which spans
      e^±4.5 over a ±3σ box and was the largest part of the log-weight variance (6.1 of 14.6
      on tracked plate frames) — is gone (ESS 28 instead of 10 of 100 on the synthetic suite).
    * ``window="box"``, and always for a particle of the entering-car component: boxes about ``X``
      with half-widths ``window_sigmas`` σ of the AR(2) noise (tracked; at most the plate size) or
      the plate's width and height (entering: over twice the plate size the entering density is
      nearly flat), with ``g`` the box's uniform density in the weight
      ``r(Z) g / (q^h q^v) · K(Z)/K(X)`` — boxes of different sizes would otherwise favour the
      particles with the larger box. An entering particle first draws a cell of its window from
      a coarse grid, ∝ the full likelihood at the cell centres (sparsely sampled), then a cell
      of ``log s`` ∝ the same at that centre, then runs the line scans inside it (:meth:`_search`).

    All conditionals are sampled on grids of ``cells`` cells per line (the density is piecewise
    constant and used exactly). ``filters/lis.py`` computes ``α r / q · K(Z)/K(X)`` with
    ``α = 1``; the returned ``log q`` is set so that this is the weight above.
    """

    def __init__(self, model, cells=24, window_sigmas=3.0, coarse=(12, 6), fine=8, window="dynamics",
                 scale_cells=5, scale_span=0.35, scale_fine=5, angle_cells=9, angle_span=0.25, rescan=True,
                 birth_beta=2.0, kernel=None):
        if window not in ("dynamics", "box"):
            raise ValueError(f"window must be 'dynamics' or 'box', got {window!r}")
        self.model = model
        #: the step's kernel (:mod:`~vistrack.core.transition`): the dynamics window is centred
        #: on its mean (``p_0``'s on the first step); ``None``: the model's ``K``
        self.kernel = Transition(model) if kernel is None else kernel
        #: entering particles also search the scale: ``scale_cells`` cells of ``log s`` over
        #: ``± scale_span`` about the drawn scale (1 cell, or span 0: translation only), each
        #: refined into ``scale_fine`` sub-cells after the line scans
        self.scale_cells = int(scale_cells) if scale_span > 0 else 1
        self.scale_span = float(scale_span) if self.scale_cells > 1 else 0.0
        self.scale_fine = max(int(scale_fine), 1)
        #: ... and the angle: ``angle_cells`` cells over ``± angle_span`` rad about the drawn angle
        self.angle_cells = int(angle_cells) if angle_span > 0 else 1
        self.angle_span = float(angle_span) if self.angle_cells > 1 else 0.0
        #: scan (u, w) again inside the coarse cell at the refined angle and scale
        self.rescan = bool(rescan)
        #: the entering search draws its cells ∝ r^β (β > 1: tempered towards the best cell)
        self.birth_beta = float(birth_beta)
        self.cells = int(cells)
        self.window = window
        self.window_sigmas = float(window_sigmas)
        self.coarse = tuple(int(c) for c in coarse)
        self.fine = int(fine)

    def _conditional(self, log_vals, rng, beta=1.0):
        """Draw a cell per row ∝ exp(log_vals) and return (index, log prob of the cell)."""
        from ...core.particles import logsumexp

        if kernels.use():
            from .scan_kernels import draw_cells

            n, k = log_vals.shape
            return draw_cells(np.ascontiguousarray(log_vals, float), float(beta), rng.gumbel(size=(n, k)),
                              np.empty(n, np.int64), np.empty(n))
        log_vals = beta * log_vals

        lz = logsumexp(log_vals, axis=1)
        j = np.argmax(log_vals + rng.gumbel(size=log_vals.shape), axis=1)
        return j, log_vals[np.arange(len(j)), j] - lz

    def sample(self, x, obs, rng, prev=None):
        """Draw ``z (N, 9)`` about the predictions ``x (N, 9)`` (class docstring).

        Returns ``(z (N, 9), log_alpha (N,), log_q (N,))`` with ``log_alpha = 0`` and ``log_q`` set so
        that LIS's ``α r / q · K(Z)/K(X)`` is the weight of the chosen window; ``prev (N, 9)`` (the
        resampled ``Z_{t-1}``) centres the dynamics window.
        """
        m = self.model
        n = len(x)
        ent = m.entering(x)
        uv, log_q = np.empty((n, 2)), np.zeros(n)
        half = m.plate_size(x)
        dyn = ~ent & (self.window == "dynamics") & (prev is not None)
        box = ~ent & ~dyn
        if dyn.any():
            sig = m.sigma[:2]
            mean = self.kernel.predict_mean(prev[dyn])[:, :2]
            half[dyn] = np.minimum(half[dyn], self.window_sigmas * sig)
            amap = self.appearance_map(obs, x[dyn], mean, half[dyn])
            uv[dyn], lq = self._line_scans(x[dyn], obs, rng, mean, half[dyn], self.cells, prior=(mean, sig),
                                           amap=amap)
            # LIS adds K(Z)/K(X) = N_uw(Z)/N_uw(X) (same θ, s): take N_uw(X) out of q
            log_q[dyn] = lq - diag_logpdf(x[dyn, :2], mean, sig)
        if box.any():
            half[box] = np.minimum(half[box], self.window_sigmas * m.sigma[:2])
            amap = self.appearance_map(obs, x[box], x[box, :2], half[box])
            uv[box], log_q[box] = self._line_scans(x[box], obs, rng, x[box, :2], half[box], self.cells, amap=amap)
        angle, scale = x[:, 2].copy(), x[:, 3].copy()
        if ent.any():
            uv[ent], angle[ent], scale[ent], log_q[ent] = self._search(x[ent], obs, rng)
        # a box window g is the box's uniform density, 1 / area: with boxes of different sizes
        # (entering or not, plate scale) it must be in the weight, w = r g K(Z) / (K(X) q)
        log_q[~dyn] += np.log(4 * half[~dyn, 0] * half[~dyn, 1])
        z = self.kernel.with_local(x, uv)
        z[ent, 2] = z[ent, 6] = angle[ent]  # an entering particle stays a zero-velocity start
        z[ent, 3] = z[ent, 7] = scale[ent]
        return z, np.zeros(n), log_q

    def appearance_map(self, obs, x, centre, half):
        """The learned appearance's term for the line scans of the poses ``x (n, 9)`` over the windows
        ``centre ± half`` (``(n, 2)`` each), as ``(map, a)`` for :func:`map_values`; ``None`` without
        a learned appearance (:meth:`~vistrack.models.plate.model.Plate.learn_appearance`).

        The map is :meth:`Appearance.proposal_map <vistrack.appearance.cues.Appearance.proposal_map>`
        (the box model's LIS map: template correlation and back-projection contrast) for the
        median box of ``x``, over the windows. The scans of ``r_plate^h``, ``r_plate^v`` alone
        put most draws on the rendered-plate likelihood's modes: on a plate unlike the rendered
        ones those can be a character pitch off the plate (tests/models/plate/test_plate_appearance.py: the
        yellow plate's ``log r_plate`` is 3.4 higher 8 px to the side, where the appearance's is
        14 lower), and with 100 particles no draw was left on the plate.

        With the correlation filter (:attr:`Plate.cf <vistrack.models.plate.Plate.cf>`), its term
        ``λ_dcf y`` of ``log r`` is added to the map (read at each map pixel's frame position and the
        poses' median width): the scans then draw where the filter responds, as the box model's
        proposal does (from the first box, the dashcam clip with all stresses: AUC 0.922 against 0.829
        without the term; shaken 6 px: 0.918 against 0.903; docs/experiments.md)."""
        app, m = (obs.appearance if isinstance(obs, PlateObservation) else None), self.model
        if m.app is None or app is None or len(x) == 0:
            return None
        b = m.app_boxes(x)
        lo, hi = app.to_work(*(centre - half).T), app.to_work(*(centre + half).T)
        span = (float(lo[0].min()), float(hi[0].max()), float(lo[1].min()), float(hi[1].max()))
        pm = m.app.proposal_map(app, float(np.median(b[:, 2])), float(np.median(b[:, 3])), span=span)
        if pm is None:
            return None
        mp, u0, v0, stride = pm
        f = app.f / stride
        a = np.array([f, -(app.x0 * app.f + u0) / stride, f, -(app.y0 * app.f + v0) / stride])
        resp = obs.dcf
        if resp is not None and m.lambda_dcf:  # the correlation filter's term of log r, at the poses' median scale
            hh, ww = mp.shape
            jj, ii = np.meshgrid(np.arange(ww, dtype=float), np.arange(hh, dtype=float))
            at = np.stack([(jj.ravel() - a[1]) / a[0], (ii.ravel() - a[3]) / a[2],
                           np.full(jj.size, float(np.median(m.dcf_states(x)[:, 2])))], axis=1)
            mp = mp + m.lambda_dcf * resp.read(at).reshape(hh, ww)
        return np.ascontiguousarray(mp, np.float32), a

    def _line_scans(self, x, obs, rng, centre, half, k, prior=None, beta=1.0, amap=None):
        """§4.5.2: ``W'`` from ``r^h`` along the vertical line through ``centre`` (``± half[:, 1]``),
        then ``U'`` from ``r^v`` along the horizontal line at ``W'`` (``± half[:, 0]``); ``k`` cells
        per line, each ∝ the scan likelihood at its centre (times the Gaussian ``prior = (mean, std)``
        of (u, w) there, if given; plus the learned appearance's map ``amap`` there,
        :meth:`appearance_map`). Returns the new ``(u, w)`` and their log density."""
        if kernels.use() and (prior is None or prior[0] is centre):
            return self._compiled_scans(x, obs, rng, centre, half, k, prior, beta, amap)
        n = len(x)
        frac = (np.arange(k) + 0.5) / k * 2 - 1  # cell centres in [-1, 1]
        off = np.zeros((n, k, 2))
        wc = centre[:, 1:2] + frac * half[:, 1:2]  # (n, k) cell centres on the vertical line
        off[:, :, 0] = (centre[:, 0] - x[:, 0])[:, None]
        off[:, :, 1] = wc - x[:, 1:2]
        app = None if amap is None else map_values(amap, np.broadcast_to(centre[:, :1], wc.shape), wc)
        w_new, lqh, cell_h = self._scan_draw(obs, x, rng, beta, "h", off, wc, 1, prior, half, k, app)
        uc = centre[:, 0:1] + frac * half[:, 0:1]
        off[:, :, 0] = uc - x[:, 0:1]
        off[:, :, 1] = (w_new - x[:, 1])[:, None]
        app = None if amap is None else map_values(amap, uc, np.broadcast_to(w_new[:, None], uc.shape))
        u_new, lqv, cell_v = self._scan_draw(obs, x, rng, beta, "v", off, uc, 0, prior, half, k, app)
        return np.stack([u_new, w_new], axis=1), lqh - np.log(cell_h) + lqv - np.log(cell_v)

    def _compiled_scans(self, x, obs, rng, centre, half, k, prior, beta, amap=None):
        """:meth:`_line_scans` in one compiled call (:func:`vistrack.models.plate.scan_kernels.line_scans`),
        the Gumbel and uniform variates drawn first in the numpy path's order (equal to it)."""
        from .scan_kernels import line_scans

        lik, n = self.model.lik, len(x)
        gum, unif = np.empty((2, n, k)), np.empty((2, n))
        for i in range(2):
            gum[i], unif[i] = rng.gumbel(size=(n, k)), rng.random(n)
        pose = np.ascontiguousarray(x[:, :4])
        w = lik.coef(pose)[0]
        (tab_h, idx_h), (tab_v, idx_v) = lik.scan_table("h"), lik.scan_table("v")
        sig = np.ones(2) if prior is None else np.asarray(prior[1], float)
        uv, log_q = np.empty((n, 2)), np.empty(n)
        amap_m, amap_a = (np.zeros((1, 1), np.float32), np.zeros(4)) if amap is None else amap
        return line_scans(lik.maps(obs), pose, np.tan(pose[:, 2]), float(lik.layout.aspect), tab_h,
                          np.ascontiguousarray(w[:, idx_h]), tab_v, np.ascontiguousarray(w[:, idx_v]),
                          np.ascontiguousarray(centre, float), np.ascontiguousarray(half, float), int(k),
                          prior is not None, sig, float(beta), gum, unif, lik.learnt, BORDER, uv, log_q,
                          amap is not None, amap_m, amap_a)

    def _scan_draw(self, obs, x, rng, beta, which, off, centres, axis, prior, half, k, app=None):
        """One line scan of ``_line_scans``: ``log r^which`` at the cell centres ``(n, k)`` (times the
        prior's factor on ``axis``; plus the appearance map's values ``app (n, k)``), a cell drawn ∝
        it, a point uniform in the cell. Returns the coordinate ``(n,)``, the log probability of its
        cell and the cell's width ``(n,)``."""
        n = len(x)
        log_r = self.model.lik.scan(obs, x, which, off)
        if app is not None:
            log_r = log_r + app
        if prior is not None:
            log_r = log_r - 0.5 * ((centres - prior[0][:, axis:axis + 1]) / prior[1][axis]) ** 2
        j, lq = self._conditional(log_r, rng, beta)
        cell = 2 * half[:, axis] / k
        return centres[np.arange(n), j] + cell * (rng.random(n) - 0.5), lq, cell

    def _draw_cell(self, obs, x, col, values, rng, offsets=None):
        """For each pose of ``x``, one of ``values (n, k)`` of its state column ``col``, drawn ∝ the
        sparse ``r^β`` with that value (at ``offsets (n, 2)`` px from the pose, if given).
        Returns (index, log prob of the cell)."""
        n, k = values.shape
        xs = np.repeat(x, k, axis=0)
        xs[:, col] = values.ravel()
        at = np.zeros((n * k, 1, 2)) if offsets is None else np.repeat(offsets, k, axis=0)[:, None]
        return self._sparse_cells(obs, xs, at, rng, n, k)

    def _sparse_cells(self, obs, x, offsets, rng, n, k):
        """``_conditional`` (β = ``birth_beta``) of the sparse ``r`` at the poses ``x`` shifted by
        ``offsets (P, C, 2)``, read as ``n`` rows of ``k`` cells; compiled where the kernels are
        (:func:`vistrack.models.plate.scan_kernels.sparse_draw`, equal)."""
        lik = self.model.lik
        if not kernels.use():
            return self._conditional(lik.loglik_sparse(obs, x, offsets).reshape(n, k), rng, self.birth_beta)
        from .scan_kernels import sparse_draw

        pose = np.ascontiguousarray(x[:, :4])
        w, b = lik.coef(pose)
        return sparse_draw(lik.maps(obs), pose, np.tan(pose[:, 2]), float(lik.layout.aspect),
                           lik.kernel_table(lik.scan_points), np.ascontiguousarray(offsets, float),
                           np.ascontiguousarray(w), np.ascontiguousarray(b, float), lik.learnt, int(k),
                           self.birth_beta, rng.gumbel(size=(n, k)), BORDER, np.empty(n, np.int64), np.empty(n))

    def _search(self, x, obs, rng):
        """Entering particles: a coarse cell of the window drawn ∝ the sparse full ``r`` at its
        centre — the line scans alone lock onto bumpers and grilles, which have the plate's
        horizontal edges but no characters — then the line scans inside that cell.

        1. One of the ``coarse`` cells in (u, w) about ``X`` (± the plate size at ``X``'s scale),
           ∝ the sparse ``r`` at its centre.
        2. One of ``scale_cells`` cells of ``log s`` (± ``scale_span`` about ``X``'s), ∝ the sparse
           ``r`` at that centre: an entering scale 20 % off the plate's scores far below it (the
           entering density's scale sd is 23 %).
        3. The line scans inside the (u, w) cell, at the scale cell's centre.
        4. One of ``angle_cells`` cells of ``θ`` (± ``angle_span`` about ``X``'s), ∝ the sparse ``r``
           at the scanned (u, w), uniform inside the cell.
        5. One of ``scale_fine`` sub-cells of the scale cell, ∝ the same, uniform in ``log s`` inside.
        6. With ``rescan``, the line scans of step 3 again at the refined angle and scale. The
           first scan's ``(u, w)`` is then an auxiliary variable whose backward kernel is its
           own density (a function of ``X`` and of the cells that hold ``Z``), so it cancels:
           ``q`` counts the second scan only.

        Every cell is drawn ∝ ``r^β`` (``birth_beta``; β = 2 tempers the draws towards the best
        cell, and ``q`` is that distribution; steps 4–5 are measured against steps 1–3 alone in
        ``docs/experiments.md``, plates). Every step draws a cell of a
        fixed partition, so ``q`` is exact: the product of the cells' probabilities over their
        sizes (``1 / s_Z`` for the uniform density in ``log s``). For the weight, the backward
        window ``g(X|Z)`` is the box of the plate size at ``X``'s scale about ``Z`` times the
        uniform densities of ``log s_X`` on ``log s_Z ± scale_span`` (``1 / (2 span s_X)`` in
        ``s_X``) and of ``θ_X`` on ``θ_Z ± angle_span``. Returns ``(u, w)``, the angle, the scale
        and ``log q(Z|X) - log g_{θ,s}(X|Z)``."""
        m = self.model
        cu, cw = self.coarse
        n = len(x)
        rows = np.arange(n)
        half = m.plate_size(x)
        gu = ((np.arange(cu) + 0.5) / cu * 2 - 1)
        gw = ((np.arange(cw) + 0.5) / cw * 2 - 1)
        du, dw = np.meshgrid(gu, gw, indexing="ij")
        offs = np.stack([du.ravel(), dw.ravel()], axis=1)[None] * half[:, None, :]  # (n, C, 2) px
        j, log_q = self._sparse_cells(obs, x, offs, rng, n, cu * cw)
        centre = x[:, :2] + offs[rows, j]
        xz = x.copy()
        k, span = self.scale_cells, self.scale_span
        log_s = np.log(x[:, 3])
        if k > 1:
            gs = ((np.arange(k) + 0.5) / k * 2 - 1) * span  # log-scale cell centres
            js, lqs = self._draw_cell(obs, x, 3, x[:, 3:4] * np.exp(gs), rng, centre - x[:, :2])
            log_s = log_s + gs[js]
            xz[:, 3] = np.exp(log_s)
            log_q += lqs
        cell_half = half / np.array([cu, cw])
        uv, lq = self._line_scans(xz, obs, rng, centre, cell_half, self.fine, beta=self.birth_beta)
        if not self.rescan:
            log_q += lq
        xz[:, :2] = uv
        log_s = self._refine_angle_scale(obs, x, xz, log_s, log_q, rng)
        if self.rescan:
            uv, lq = self._line_scans(xz, obs, rng, centre, cell_half, self.fine, beta=self.birth_beta)
            log_q += lq
            xz[:, :2] = uv
        return xz[:, :2], xz[:, 2], xz[:, 3], log_q

    def _refine_angle_scale(self, obs, x, xz, log_s, log_q, rng):
        """Steps 4–5 of :meth:`_search` on the scanned poses ``xz``: an angle cell, then a
        sub-cell of the scale cell about ``log_s``, each uniform inside. ``xz`` and ``log_q``
        (``log q - log g_{θ,s}``) are updated in place; returns the new ``log_s``."""
        n, k, span = len(x), self.scale_cells, self.scale_span
        if self.angle_cells > 1:
            ka, span_a = self.angle_cells, self.angle_span
            ga = ((np.arange(ka) + 0.5) / ka * 2 - 1) * span_a
            ja, lqa = self._draw_cell(obs, xz, 2, xz[:, 2:3] + ga, rng)
            cell = 2 * span_a / ka
            xz[:, 2] += ga[ja] + cell * (rng.random(n) - 0.5)
            log_q += lqa - np.log(cell) + np.log(2 * span_a)
        if k > 1:
            cell = 2 * span / k  # the scale cell about log_s, in kf sub-cells
            kf = self.scale_fine
            gf = ((np.arange(kf) + 0.5) / kf - 0.5) * cell
            jf, lqf = self._draw_cell(obs, xz, 3, np.exp(log_s[:, None] + gf), rng)
            sub = cell / kf
            log_s = log_s + gf[jf] + sub * (rng.random(n) - 0.5)
            xz[:, 3] = np.exp(log_s)
            # q's density of s_Z in its sub-cell over g's density of s_X: (1 / (sub s_Z)) / (1 / (2 span s_X))
            log_q += lqf - np.log(sub) - log_s + np.log(2 * span) + np.log(x[:, 3])
        return log_s
