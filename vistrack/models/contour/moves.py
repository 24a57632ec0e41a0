"""The contour model's local moves (thesis 001): ``LS_λ`` for LS-N-IPS (§4.3, eq. 4.1; LMS of
§4.3.1) and the translation moves of LLS and LIS (§4.4.3) from one set of long measurement
lines (:mod:`~vistrack.models.contour.model` module docstring)."""

from __future__ import annotations

import numpy as np

from ... import kernels
from ...core.transition import is_prior
from ...proposals import GaussMixtureProposal, Window
from .nn import nn_candidates
from .spline import edge_peaks, pose_params

__all__ = ["ContourMoves"]


class ContourMoves:
    """Mixin of :class:`~vistrack.models.contour.model.Contour`: local search and local moves."""

    # per-frame caches, made on first use
    _search_cache = None
    _scratch = None
    _grid_cache = None
    _pair_cache = None

    #: the LMS search in two fused compiled passes (:meth:`_search_compiled`) where the kernels are
    #: on and there is no colour term; ``False``: the step-by-step path (the reference in the tests)
    fused_search = True

    # -- local search LS_λ (LS-N-IPS, §4.3.1) ------------------------------------
    def _lms_fit(self, obs, z, samples, reach_factor=1.0):
        """One LMS step: on each normal within the search length, the edge feature
        nearest to the predicted curve, projected with ``W⁺`` (normals without an
        edge keep their predicted point)."""
        scale, _ = pose_params(z)
        reach = self.search_length * scale * reach_factor  # (N,)
        off = reach[:, None, None] * np.linspace(-1.0, 1.0, samples)  # (N, 1, L)
        gn = self.edge_profiles(obs, z, off, support=True)
        peaks = edge_peaks(gn, self.feature_threshold(obs))
        score = np.where(peaks, -np.abs(off), -np.inf)
        best = np.argmax(score, axis=-1)  # (N, n)
        found = peaks.any(axis=-1)
        nu = np.where(found, np.take_along_axis(np.broadcast_to(off, peaks.shape), best[..., None], -1)[..., 0], 0.0)
        q_hat = self.support_points(z) + nu[..., None] * self.normals(z)
        d = np.concatenate([q_hat[..., 0] - self.q0[:, 0], q_hat[..., 1] - self.q0[:, 1]], axis=1)
        return d @ self.W_plus.T

    def local_search(self, obs, states, search=None):
        """``LS_λ`` of §4.3 / eq. 4.1 for contours: refine predicted poses ``z_t``.

        ``search``: ``"lms"`` (below) or ``"nn"`` (:mod:`~vistrack.models.contour.nn`, Fig. 4.5, from
        the prediction); default :attr:`search`. Both go through the same ``λ`` bound and eq. 4.1 check.

        One set of measurement lines, long enough for every move, serves both steps:

        1. translation: the argmax of ``r`` over a grid of shifts ``δ`` within
           ``(λ_x, λ_y)`` (the grid likelihood of :meth:`loglik_local_grid`);
        2. the LMS fit of §4.3.1 from there: on each normal the edge nearest to the
           shifted curve within ``l = l0 · scale / 2``, fitted in the least-squares
           sense, ``ẑ = W_m⁺ (p̂ - p0)`` with ``W_m`` the matrix ``W`` of eq. 1.1 on the
           measurement points (two per spline segment, a discretisation of the
           spline norm ``U``; normals without an edge keep the shifted point).

        The LMS result is used only if it is within ``λ`` of the prediction (max
        norm per coordinate; else the translation step alone), and the move is
        kept only if it raises the exact likelihood, so ``r(y|LS_λ(x, y)) >= r(y|x)``.
        With a colour term the search itself reads the edges only (the colour on its grid
        cost 3x the time and lost accuracy on the real clips) and the check uses the full ``r``.
        Returns the states and their log-likelihoods.
        """
        z = states[:, :4]
        if (search or self.search) == "nn":
            return self._accept(obs, states, nn_candidates(self, obs, z), z, lambda: self.loglik(obs, states))
        grid, step = self._search_grid()
        reach_lms = step
        if kernels.use() and self.colour is None and self.fused_search:
            return self._search_compiled(obs, states, grid, step)
        pts, nrm = self.measurement_lines(z)
        off, gn = self._profiles_wide(obs, z, np.hypot(*self.search_lambda[:2]) + reach_lms, lines=(pts, nrm))
        thresh, fast = self.feature_threshold(obs), kernels.use()
        peaks = None if fast else edge_peaks(gn, thresh)
        ll_grid = self._grid_from_peaks(off, gn if fast else peaks, nrm, grid, thresh if fast else None)
        delta = grid[np.argmax(ll_grid, axis=1)]  # (N, 2)
        z_t = z.copy()
        z_t[:, :2] += delta
        # LMS: nearest feature to the shifted curve on each line (offsets along the old line)
        shift = np.einsum("kmd,kd->km", nrm, delta)  # (N, M)
        if fast:
            from .kernels import nearest_edge

            nu = nearest_edge(gn, np.float32(thresh), off, shift, reach_lms, np.empty(shift.shape))
        else:
            dist = np.where(peaks, np.abs(off - shift[..., None]), np.inf)
            j = np.argmin(dist, axis=-1)
            found = np.take_along_axis(dist, j[..., None], -1)[..., 0] <= reach_lms
            nu = np.where(found, off[j] - shift, 0.0)
        # the edge found on the old line, moved along the contour with the shift
        # (edges are locally parallel to the contour): p + δ + (ν - n·δ) n
        p_hat = pts + delta[:, None, :] + nu[..., None] * nrm
        d = np.concatenate([p_hat[..., 0] - self.meas0[:, 0], p_hat[..., 1] - self.meas0[:, 1]], axis=1)
        z_hat = d @ self.W_meas_plus.T

        def ll_prediction():  # r at the prediction, exactly as loglik: the middle samples of the long lines
            ll_x = self._loglik_from_profiles(gn, thresh, lo=(len(off) - len(self.line_offsets)) // 2)
            return ll_x + self.colour_loglik(obs, z) if self.colour is not None else ll_x

        return self._accept(obs, states, z_hat, z_t, ll_prediction)

    def _search_compiled(self, obs, states, grid, reach_lms):
        """:meth:`local_search` (LMS, no colour term) in two compiled passes around the matrix product
        (:mod:`vistrack.models.contour.search_kernels`; equal bit for bit to the steps below)."""
        from .search_kernels import accept, search_lines

        gxy, thresh = obs.gradient(self.gradient_sigma)[0], np.float32(self.feature_threshold(obs))
        k = self._search_consts(grid, reach_lms)
        gn, d, z_t, ll_x = self._search_scratch(len(states), len(k["off"]))
        pol, cos2 = self.polarity or 0, np.float32(self.cos_min**2)
        search_lines(gxy, states, self.meas0, self.meas_normals0, k["off"], k["line"], pol, cos2, thresh, grid,
                     k["grid32"], k["pair"], k["c32"], k["pairs"], reach_lms, gn, d, z_t, ll_x)
        return accept(gxy, states, d @ self.W_meas_plus.T, z_t, self.search_lambda, self.meas0, self.meas_normals0,
                      k["off_line"], pol, cos2, thresh, *k["line"][1:], self.search_check, ll_x, states.copy(),
                      np.empty(len(states)))

    def _search_consts(self, grid, reach_lms):
        """What :meth:`_search_compiled` passes every frame: the long lines' offsets, the likelihood's
        middle samples, kernel and constant, the grid's float32 cast, pair kernel and table of
        two-feature terms (filled as frames need it; all cached while the model's parameters stay)."""
        key = (tuple(self.search_lambda), reach_lms, self.half_line, self.sigma_edge, self.log_c)
        cached = self._search_cache
        if cached is None or cached[0] != key:
            h = int(np.ceil(np.hypot(*self.search_lambda[:2]) + reach_lms)) + self.half_line
            off = np.arange(-h, h + 1, dtype=float)
            line = ((len(off) - len(self.line_offsets)) // 2, self._line_kernel(), np.exp(self.log_c))
            cached = self._search_cache = (key, {
                "off": off, "line": line, "grid32": np.asarray(grid, np.float32), "pair": self._pair_kernel(off),
                "c32": np.float32(np.exp(self.log_c)), "off_line": self.line_offsets.astype(np.float32),
                "pairs": np.full((len(off), len(off)), np.nan, np.float32)})
        return cached[1]

    def _search_scratch(self, n, n_samples):
        """Work arrays of :meth:`_search_compiled` for ``n`` poses, reused from frame to frame:
        edge strengths, ``p̂ - p0``, the translated poses and ``log r`` at the prediction."""
        m = len(self.meas0)
        key = (n, m, n_samples)
        cached = self._scratch
        if cached is None or cached[0] != key:
            cached = self._scratch = (key, (np.empty((n, m, n_samples), np.float32), np.empty((n, 2 * m)),
                                            np.empty((n, 4)), np.empty(n)))
        return cached[1]

    def _accept(self, obs, states, z_hat, z_else, ll_prediction):
        """The searched poses ``z_hat`` where within ``λ`` of the prediction (max norm per
        coordinate; else ``z_else``), kept only where they do not lower ``r`` (eq. 4.1, with
        :attr:`search_check`; ``ll_prediction()``: ``log r`` at ``states``). Returns the states
        and their log-likelihoods."""
        near = np.all(np.abs(z_hat - states[:, :4]) <= self.search_lambda, axis=1)
        cand = states.copy()
        cand[:, :4] = np.where(near[:, None], z_hat, z_else)
        ll = self.loglik(obs, cand)
        if not self.search_check:
            return cand, ll
        ll_x = ll_prediction()
        keep = ll < ll_x  # the move lowered r: stay at the prediction
        cand[keep] = states[keep]
        return cand, np.where(keep, ll_x, ll)

    def searcher(self, search):
        """``local_search`` with ``search`` (``"lms"`` or ``"nn"``) whatever :attr:`search` is."""
        if search not in ("lms", "nn"):
            raise ValueError(f"unknown local search {search!r}; choose lms or nn")
        return lambda obs, states: self.local_search(obs, states, search=search)

    def _search_grid(self):
        """The local search's grid of translations ``(G, 2)`` within ``(λ_x, λ_y)`` and its step
        (cached while ``search_lambda``, ``grid_step`` and ``sigma_edge`` stay)."""
        lx, ly = self.search_lambda[:2]
        step = max(1.0, self.grid_step * self.sigma_edge)
        cached = self._grid_cache
        if cached is None or cached[0] != (lx, ly, step):
            gx = np.arange(-np.floor(lx / step), np.floor(lx / step) + 1) * step
            gy = np.arange(-np.floor(ly / step), np.floor(ly / step) + 1) * step
            self._grid_cache = ((lx, ly, step), np.stack(np.meshgrid(gx, gy), axis=-1).reshape(-1, 2))
        return self._grid_cache[1], step

    def lms_step(self, obs, states, samples=33):
        """The plain LMS step of §4.3.1 at the support points: the edge nearest to the
        curve on each normal within ``l = l0 · scale``, ``ẑ = W⁺ (q̂ - q0)`` with the
        spline norm. Returns new states (not checked against ``λ``)."""
        out = states.copy()
        out[:, :4] = self._lms_fit(obs, states[:, :4], samples)
        return out

    # -- local moves on translation (LLS / LIS, §4.4.3) ---------------------------
    def window_std(self, kernel=None):
        """Window std on translation: the spread of ``kernel`` (``K``, or ``p_0`` on the first
        step: :mod:`~vistrack.core.transition`)."""
        return self.prior_std[:2] if is_prior(kernel) else self.sigma[:2]

    def _profiles_wide(self, obs, z, reach, lines=None):
        """Offsets and edge strengths on lines long enough for shifts up to ``reach`` px
        (:attr:`line_offsets` are their middle samples); ``lines``: :meth:`measurement_lines` of ``z``."""
        h = int(np.ceil(reach)) + self.half_line
        off = np.arange(-h, h + 1, dtype=float)
        return off, self.edge_profiles(obs, z, off, lines=lines)

    def _peaks_wide(self, obs, z, reach):
        """Edge features on lines long enough for shifts up to ``reach`` px."""
        off, gn = self._profiles_wide(obs, z, reach)
        return off, edge_peaks(gn, self.feature_threshold(obs))

    def loglik_local_grid(self, obs, states, offsets):
        """``log r`` at ``states`` translated by each of ``offsets (G, 2)``: ``(N, G)``.

        From one set of lines: a translation ``δ`` shifts the edge distances on
        normal ``i`` by ``-n_i · δ``, so ``Σ_j exp(-(ν_j - n_i·δ)² / 2σ²)`` is the
        feature train smoothed by the Gaussian, read at ``n_i · δ``.
        """
        z = states[:, :4]
        off, peaks = self._peaks_wide(obs, z, np.max(np.abs(offsets)) * np.sqrt(2))
        ll = self._grid_from_peaks(off, peaks, self.measurement_lines(z)[1], offsets)
        if self.colour is not None:
            ll = ll + self.colour_loglik(obs, z, offsets)
        return ll

    def _grid_from_peaks(self, off, peaks, nrm, offsets, thresh=None):
        """``log r`` of each pose moved by each of ``offsets (G, 2)`` from the edge features
        ``peaks (N, M, L)`` on lines at ``off``; with ``thresh``, ``peaks`` are the edge strengths
        and the features are found here (the compiled path, :func:`vistrack.models.contour.kernels.grid`)."""
        kern = self._pair_kernel(off)
        if thresh is not None:
            from .kernels import grid

            out = np.empty((len(peaks), len(offsets)), np.float32)
            return grid(peaks, np.float32(thresh), np.float32(off[0] - 0.5), nrm.astype(np.float32),
                        np.asarray(offsets, np.float32), kern, np.float32(np.exp(self.log_c)), out)
        smooth = peaks.astype(np.float32) @ kern  # (N, M, L): S_i(ν') at ν' = off
        shift = nrm.astype(np.float32) @ np.asarray(offsets, np.float32).T  # (N, M, G): n_i · δ
        # nearest line sample (1 px apart; index = floor(n_i · δ - off[0] + 0.5)): one flat gather
        shift -= off[0] - 0.5
        np.clip(shift, 0, len(off) - 1, out=shift)
        idx = shift.astype(np.intp)
        n, m, L = smooth.shape
        idx += (np.arange(n * m) * L).reshape(n, m, 1)
        val = smooth.reshape(-1)[idx]
        val *= np.float32(np.exp(self.log_c))
        return np.sum(np.log1p(val, out=val), axis=1)

    def _pair_kernel(self, off):
        """``exp(-(ν_j - ν_k)² / 2σ²)`` float32 ``(L, L)`` of the line offsets ``off`` (cached per ``off``, ``σ``)."""
        key = (len(off), float(off[0]), self.sigma_edge)
        cached = self._pair_cache
        if cached is None or cached[0] != key:
            kern = np.exp(-0.5 * ((off[:, None] - off[None, :]) / self.sigma_edge) ** 2).astype(np.float32)
            self._pair_cache = (key, kern)
        return self._pair_cache[1]

    def local_mixture(self, obs, states, defensive=0.2):
        """LIS proposal on translation: a Gaussian from the edges nearest to the predicted
        contour (least squares along the normals, precision ``Σ n nᵀ / σ_edge²``), mixed
        with a broad defensive component ``N(x, 4 Σ_g)`` of weight ``defensive``.

        Returns ``log_p (N, 1, 2)``, ``mu (N, 1, 2, 2)``, ``cov (N, 1, 2, 2, 2)``.
        """
        z = states[:, :4]
        win = self.window_std()
        off, peaks = self._peaks_wide(obs, z, 3 * np.max(win))
        dist = np.where(peaks, np.abs(off), np.inf)
        j = np.argmin(dist, axis=-1)
        found = np.isfinite(np.take_along_axis(dist, j[..., None], -1)[..., 0])  # (N, n)
        nu = np.where(found, off[j], 0.0)
        nrm = self.measurement_lines(z)[1]
        wgt = found.astype(float)
        prec = np.einsum("ki,kia,kib->kab", wgt, nrm, nrm) / self.sigma_edge**2 + np.eye(2) * 1e-6
        rhs = np.einsum("ki,ki,kia->ka", wgt, nu, nrm) / self.sigma_edge**2
        cov_fit = np.linalg.inv(prec)
        # the fit needs edges on at least ~two directions; else lean on the prior spread
        cov_fit = cov_fit + np.eye(2) * self.sigma_edge**2
        mu_fit = states[:, :2] + np.einsum("kab,kb->ka", np.linalg.inv(prec), rhs)
        n = len(states)
        big = np.broadcast_to(np.diag(4 * win**2), (n, 2, 2))
        mu = np.stack([mu_fit, states[:, :2]], axis=1)[:, None]
        cov = np.stack([cov_fit, big], axis=1)[:, None]
        log_p = np.log(np.array([1 - defensive, defensive]))
        return np.broadcast_to(log_p, (n, 1, 2)).copy(), mu, cov

    def lis_proposal(self, kernel=None):
        """LIS with the edge-fit translation proposal and a Gaussian window (:meth:`window_std`)."""
        return GaussMixtureProposal(self, np.diag(self.window_std(kernel) ** 2), kernel)

    def lls_window(self, kernel=None):
        """Box window of half-width ``2 σ`` on translation, 7×7 grid (§4.4.3)."""
        return Window("box", 2.0 * self.window_std(kernel), grid=7)
