"""Landmark shape model of seed 000 (Vaswani & Das), §3.1–3.2.

A configuration of ``K`` landmarks is the complex ``K``-vector
``h = z e^{s + jθ}``: shape ``z`` (centred, unit norm), log-scale ``s`` and
rotation ``θ``. Dynamics (5):

    s_t = α_s s_{t-1} + ν_s,       θ_t = α_θ θ_{t-1} + ν_θ,
    c_t = A_c c_{t-1} + ν_c,       ν_c ~ N(0, Σ_c),       c_t ∈ R^{2K-4}
    U_t = g(U_{t-1}, z_{t-1})      (Gram–Schmidt: ⟂ z_{t-1} and ⟂ 1_K)
    z_t = f(z_{t-1}, U_t, c_t) = (1 - c_tᵀc_t)^{1/2} z_{t-1} + U_t [I jI] c_t

Observation (6): each landmark independently,

    Y_k ~ (1 - p) CN(h_k, σ_o²) + p CN(0, σ_clutter²),   σ_clutter² = 100 σ_o² by default,

with the circular complex Gaussian ``CN(y; μ, σ²) = exp(-|y - μ|²/σ²)/(πσ²)``.
A NaN observation (a landmark with no candidate, from video) contributes nothing.

The particle state is packed into one float row (the core contract, docs/architecture.md):
``[s, θ, c (2K-4), Re z (K), Im z (K), Re U (K(K-2)), Im U (K(K-2))]``;
``U`` and ``z`` are carried because ``g`` and ``f`` depend on them.

For the Laplace proposals (PF-Doucet, PF-EIS) the model gives the negative log
of ``p*`` — eq. (8) — with its exact gradient and Hessian in the free variables
(``c``, or ``(s, θ, c)``) and a batched damped-Newton mode search
(:meth:`Landmarks.laplace`).
"""

from __future__ import annotations

import numpy as np

from .shape_space import initial_basis, per_entry, regular_polygon, shape_step, tangent_basis
from .sim import sample_observations, simulate

__all__ = ["Landmarks", "VIDEO_DYNAMICS", "regular_polygon", "tangent_basis", "shape_step",
           "initial_basis", "simulate", "sample_observations"]

#: dynamics of the synthetic landmark clips (per frame at 30 frames/s): slow zoom, rotation of a few
#: degrees per frame, gentle deformation
VIDEO_DYNAMICS = {"alpha_s": 0.95, "sigma2_s": 2.5e-4, "alpha_theta": 0.98, "sigma2_theta": 0.0025,
                  "a_c": 0.6, "sigma_c": 1e-5}

_LOG_PI = np.log(np.pi)


class Landmarks:
    """The model of §3: dynamics (5), observation likelihood (6), Laplace pieces (8).

    Parameters
    ----------
    k : int
        Number of landmarks ``K`` (at least 3).
    z0 : complex array (K,), optional
        Initial shape (centred and normalised here); default the regular K-gon.
    s0, theta0 : float
        Initial log-scale and rotation. ``X_0`` is known (the prior is a point mass).
    alpha_s, alpha_theta, sigma2_s, sigma2_theta : float
        AR(1) coefficients and noise variances of ``s`` and ``θ``.
    a_c : float or array (2K-4,)
        Diagonal of ``A_c``.
    sigma_c : float or array (2K-4,)
        Diagonal of ``Σ_c``.
    sigma2_o, p : float
        Observation noise variance and clutter probability of (6).
    clutter_var : float, optional
        Variance of the clutter component; default ``100 σ_o²`` (eq. 6).
    newton_iters : int
        Damped-Newton iterations of the mode search (:meth:`laplace`).
    """

    def __init__(self, k=5, *, z0=None, s0=0.0, theta0=0.0, alpha_s=0.9, alpha_theta=0.9, sigma2_s=1e-4,
                 sigma2_theta=0.25, a_c=0.6, sigma_c=0.0025, sigma2_o=0.04, p=0.2, clutter_var=None,
                 newton_iters=10):
        if k < 3:
            raise ValueError(f"the landmark model needs K >= 3 landmarks, got {k}")
        if not 0.0 <= p < 1.0:
            raise ValueError(f"clutter probability p must be in [0, 1), got {p}")
        self.k = int(k)
        self.dc = 2 * self.k - 4
        z0 = regular_polygon(self.k) if z0 is None else np.asarray(z0, complex)
        if z0.shape != (self.k,):
            raise ValueError(f"z0 must have {self.k} landmarks, got shape {z0.shape}")
        z0 = z0 - z0.mean()
        self.z0 = z0 / np.linalg.norm(z0)
        self.u0 = initial_basis(self.z0)
        self.s0, self.theta0 = float(s0), float(theta0)
        self.alpha_s, self.alpha_theta = float(alpha_s), float(alpha_theta)
        self.sigma2_s, self.sigma2_theta = float(sigma2_s), float(sigma2_theta)
        self.a_c = per_entry(a_c, self.dc)
        self.sigma_c = per_entry(sigma_c, self.dc)
        self.sigma2_o, self.p = float(sigma2_o), float(p)
        self.clutter_var = 100.0 * self.sigma2_o if clutter_var is None else float(clutter_var)
        self.newton_iters = int(newton_iters)
        m = self.k * (self.k - 2)
        self._sl = {"s": 0, "theta": 1, "c": slice(2, 2 + self.dc)}
        o = 2 + self.dc
        o2 = o + 2 * self.k
        self._sl.update(zr=slice(o, o + self.k), zi=slice(o + self.k, o2), ur=slice(o2, o2 + m),
                        ui=slice(o2 + m, o2 + 2 * m))
        self.dim = o + 2 * self.k + 2 * m
        self.prior_mean = self.pack(np.array([self.s0]), np.array([self.theta0]), np.zeros((1, self.dc)),
                                    self.z0[None], self.u0[None])[0]

    # ------------------------------------------------------------------ packing
    def unpack(self, states):
        """``(s, θ, c, z, U)`` of packed ``states (N, dim)``."""
        sl, n = self._sl, len(states)
        z = states[:, sl["zr"]] + 1j * states[:, sl["zi"]]
        u = (states[:, sl["ur"]] + 1j * states[:, sl["ui"]]).reshape(n, self.k, self.k - 2)
        return states[:, 0], states[:, 1], states[:, sl["c"]], z, u

    def pack(self, s, theta, c, z, u):
        """Packed states ``(N, dim)`` from the parts (inverse of :meth:`unpack`)."""
        n = len(s)
        u = u.reshape(n, -1)
        return np.concatenate([np.asarray(s, float)[:, None], np.asarray(theta, float)[:, None], c,
                               z.real, z.imag, u.real, u.imag], axis=1)

    def configuration(self, states):
        """``h(s, θ, z) = z e^{s + jθ}`` per particle, complex ``(N, K)``."""
        s, th, _, z, _ = self.unpack(np.atleast_2d(states))
        return z * np.exp(s + 1j * th)[:, None]

    # ------------------------------------------------------------------ dynamics
    def sample_prior(self, n, rng):
        """``n`` copies of the known ``X_0``."""
        return np.tile(self.prior_mean, (n, 1))

    def prior_logpdf(self, states):
        """Zeros ``(N,)``: ``p_0`` is the point mass at the known ``X_0`` (seed 000 §4)."""
        return np.zeros(len(states))

    def sample_motion(self, prev, rng):
        """``(s_t, θ_t)`` from their STP (step 1 of PF-EIS)."""
        n = len(prev)
        s = self.alpha_s * prev[:, 0] + np.sqrt(self.sigma2_s) * rng.standard_normal(n)
        th = self.alpha_theta * prev[:, 1] + np.sqrt(self.sigma2_theta) * rng.standard_normal(n)
        return s, th

    def c_prior_mean(self, prev):
        """The STP mean ``A_c c_{t-1}`` of the shape velocity (seed 000 §3.1), ``(N, 2K - 4)``."""
        return prev[:, self._sl["c"]] * self.a_c

    def advance(self, prev, s, theta, c, u=None):
        """New packed states from ``(s, θ, c)``: ``U_t = g(U_{t-1}, z_{t-1})`` (or the given
        ``u``), ``z_t = f(z_{t-1}, U_t, c_t)``."""
        c = _inside_unit_ball(c)
        _, _, _, z, u_prev = self.unpack(prev)
        u_new = tangent_basis(u_prev, z) if u is None else u
        return self.pack(s, theta, c, shape_step(z, u_new, c), u_new)

    def predict(self, prev, rng):
        """``X_t ~ p(X_t | X_{t-1})`` (eq. 5): the PF-Gordon proposal."""
        s, th = self.sample_motion(prev, rng)
        c = self.c_prior_mean(prev) + np.sqrt(self.sigma_c) * rng.standard_normal((len(prev), self.dc))
        return self.advance(prev, s, th, c)

    def motion_logpdf(self, s, theta, prev):
        """``log N(s; α_s s', σ_s²) + log N(θ; α_θ θ', σ_θ²)``."""
        return (_norm_logpdf(s - self.alpha_s * prev[:, 0], self.sigma2_s)
                + _norm_logpdf(theta - self.alpha_theta * prev[:, 1], self.sigma2_theta))

    def c_logpdf(self, c, prev):
        """``log N(c; A_c c', Σ_c)``."""
        r = c - self.c_prior_mean(prev)
        return -0.5 * np.sum(r * r / self.sigma_c + np.log(2 * np.pi * self.sigma_c), axis=-1)

    def transition_logpdf(self, new, old):
        """``log p(X_t | X_{t-1})`` in ``(s, θ, c)``; ``U``, ``z`` follow deterministically."""
        return self.motion_logpdf(new[:, 0], new[:, 1], old) + self.c_logpdf(new[:, self._sl["c"]], old)

    # ------------------------------------------------------------------ likelihood
    def _obs_terms(self, obs, h):
        """Per landmark: ``ℓ_k = -log p(Y_k | h_k)``, ``dℓ/dq``, ``d²ℓ/dq²`` (``q = |Y_k - h_k|²``), ``e = Y - h``."""
        y = np.asarray(obs, complex)
        missing = np.isnan(y)
        y0 = np.where(missing, 0.0, y)
        e = y0 - h
        q = e.real ** 2 + e.imag ** 2
        s2 = self.sigma2_o
        log_in = np.log1p(-self.p) - _LOG_PI - np.log(s2) - q / s2
        if self.p > 0:
            log_out = np.log(self.p) - _LOG_PI - np.log(self.clutter_var) - np.abs(y0) ** 2 / self.clutter_var
            tot = np.logaddexp(log_in, log_out)
        else:
            tot = log_in
        gam = np.exp(log_in - tot)  # responsibility of the landmark component
        ell = np.where(missing, 0.0, -tot)
        d1 = np.where(missing, 0.0, gam / s2)
        d2 = np.where(missing, 0.0, -gam * (1.0 - gam) / s2 ** 2)
        return ell, d1, d2, e

    def loglik(self, obs, states):
        """``log p(Y_t | X_t)`` of (6), ``(N,)``."""
        ell, _, _, _ = self._obs_terms(obs, self.configuration(states))
        return -ell.sum(axis=-1)

    # ------------------------------------------------------------------ Laplace (eq. 8)
    def _context(self, prev, u=None):
        """What eq. (8) needs of ``X_{t-1}``: ``z_{t-1}``, ``U_t``, ``B = [U_t, jU_t]``, prior means."""
        _, _, _, z_prev, u_prev = self.unpack(prev)
        if u is None:
            u = tangent_basis(u_prev, z_prev)
        return {"prev": prev, "z": z_prev, "u": u, "b": np.concatenate([u, 1j * u], axis=-1),
                "mu_c": self.c_prior_mean(prev), "mu_s": self.alpha_s * prev[:, 0],
                "mu_t": self.alpha_theta * prev[:, 1]}

    @staticmethod
    def _take(ctx, idx):
        return {k: v[idx] for k, v in ctx.items()}

    def objective(self, obs, prev, x, *, free="c", motion=None, u=None, derivs=True, context=None):
        """``L = -log p*`` of eq. (8) up to a constant, with gradient and Hessians (what
        :meth:`laplace`'s Newton steps minimise).

        Parameters
        ----------
        obs : complex (K,)
        prev : (N, dim) previous states ``X_{t-1}``
        x : (N, D) the free variables: ``c`` (``free="c"``, ``D = 2K-4``) or
            ``(s, θ, c)`` (``free="all"``, PF-Doucet)
        motion : ``(s, θ)`` arrays, the sampled motion when ``free="c"``
        u : (N, K, K-2) ``U_t = g(U_{t-1}, z_{t-1})`` (computed if not given)
        context : dict or None
            What eq. (8) needs of ``prev`` (``z_{t-1}``, ``U_t``, the prior means), computed once by
            :meth:`laplace` for its Newton steps (``prev`` and ``u`` are then not read).

        Returns
        -------
        L (N,), and with ``derivs``: grad (N, D), hess (N, D, D) exact, gn (N, D, D)
        a positive definite Gauss–Newton part (the terms with ``dℓ/dq ≥ 0``, prior).
        """
        return self._loss(obs, self._context(prev, u) if context is None else context, x, free, motion, derivs)

    def _loss(self, obs, ctx, x, free, motion, derivs):
        """:meth:`objective` given the context ``ctx`` of ``X_{t-1}``."""
        if free == "c":
            s, th = motion
            c = x
        else:
            s, th, c = x[:, 0], x[:, 1], x[:, 2:]
        rho = np.exp(s + 1j * th)
        z_prev = ctx["z"]
        g = np.sqrt(np.clip(1.0 - np.sum(c * c, axis=-1), 1e-12, None))
        w = g[:, None] * z_prev + np.einsum("nkd,nd->nk", ctx["b"], c)
        h = rho[:, None] * w
        ell, d1, d2, e = self._obs_terms(obs, h)
        rc = c - ctx["mu_c"]
        big_l = ell.sum(axis=1) + 0.5 * np.sum(rc * rc / self.sigma_c, axis=1)
        if free != "c":
            rs, rt = s - ctx["mu_s"], th - ctx["mu_t"]
            big_l = big_l + 0.5 * rs ** 2 / self.sigma2_s + 0.5 * rt ** 2 / self.sigma2_theta
        if not derivs:
            return big_l
        n, dc = c.shape
        # w(c) = g(c) z' + B c: Jacobian and the Hessian of g
        jw = z_prev[:, :, None] * (-c / g[:, None])[:, None, :] + ctx["b"]
        hess_g = -(c[:, :, None] * c[:, None, :]) / g[:, None, None] ** 3
        hess_g[:, np.arange(dc), np.arange(dc)] -= 1.0 / g[:, None]
        jc = rho[:, None, None] * jw  # dh/dc
        if free == "c":
            jh = jc
        else:
            jh = np.concatenate([h[:, :, None], 1j * h[:, :, None], jc], axis=2)
        # q_k = |e_k|^2: grad q_k = -2 Re(conj(e_k) dh_k),
        # hess q_k = 2 Re(conj(dh_k) dh_k^T) - 2 Re(conj(e_k) d2h_k)
        ce = np.conj(e)
        grad_q = -2.0 * np.real(ce[:, :, None] * jh)
        grad = np.einsum("nk,nkd->nd", d1, grad_q)
        sj = np.sqrt(d1)[:, :, None] * jh
        gn = 2.0 * np.einsum("nkd,nke->nde", sj.real, sj.real) + 2.0 * np.einsum("nkd,nke->nde", sj.imag, sj.imag)
        gq = np.sqrt(-d2)[:, :, None] * grad_q
        curv = -np.einsum("nkd,nke->nde", gq, gq)
        a = d1 * ce  # sum_k d1_k conj(e_k) d2h_k, taken as -2 Re(...) below
        o = 0 if free == "c" else 2
        dim = o + dc
        second = np.zeros((n, dim, dim))
        second[:, o:, o:] = -2.0 * np.real(np.sum(a * rho[:, None] * z_prev, axis=1))[:, None, None] * hess_g
        idx = np.arange(o, dim)
        gn[:, idx, idx] += 1.0 / self.sigma_c
        grad[:, o:] += rc / self.sigma_c
        if free != "c":
            ah = np.sum(a * h, axis=1)
            ajc = np.einsum("nk,nkd->nd", a, jc)
            second[:, 0, 0] = -2.0 * ah.real
            second[:, 1, 1] = 2.0 * ah.real
            second[:, 0, 1] = second[:, 1, 0] = 2.0 * ah.imag
            second[:, 0, 2:] = second[:, 2:, 0] = -2.0 * ajc.real
            second[:, 1, 2:] = second[:, 2:, 1] = 2.0 * ajc.imag
            gn[:, 0, 0] += 1.0 / self.sigma2_s
            gn[:, 1, 1] += 1.0 / self.sigma2_theta
            grad[:, 0] += rs / self.sigma2_s
            grad[:, 1] += rt / self.sigma2_theta
        return big_l, grad, gn + curv + second, gn

    def laplace(self, obs, prev, *, free="c", motion=None, x0=None, tol=1e-9):
        """Mode ``m`` and Hessian ``∇²L(m)`` of eq. (3)/(8), batched over particles.

        At most ``newton_iters`` damped Newton steps, all particles at once: the
        step solves with the exact Hessian where it is positive definite and
        with the Gauss–Newton matrix elsewhere (the fallback); a step that does
        not lower ``L`` is halved (up to 2⁻⁸). Particles whose step is below
        ``tol`` stop. Starts from the prior mean. Returns ``(m, H, U_t)``; ``H``
        is the exact Hessian at the mode where positive definite, else the
        Gauss–Newton matrix, so ``H⁻¹`` is always a covariance.
        """
        ctx = self._context(prev)
        if x0 is None:
            x0 = ctx["mu_c"] if free == "c" else np.column_stack([ctx["mu_s"], ctx["mu_t"], ctx["mu_c"]])
        x = x0.copy()
        active = np.arange(len(x))
        halvings = 0.5 ** np.arange(1, 9)
        for _ in range(self.newton_iters):
            sub = self._take(ctx, active)
            mot = None if motion is None else (motion[0][active], motion[1][active])
            xa = x[active]
            big_l, grad, hess, gn = self.objective(obs, None, xa, free=free, motion=mot, context=sub)
            dx = -np.linalg.solve(_pd_or(hess, gn), grad[:, :, None])[:, :, 0]
            trial = xa + dx
            l_new = self.objective(obs, None, trial, free=free, motion=mot, derivs=False, context=sub)
            bad = ~(l_new <= big_l)
            if bad.any():  # backtracking, all halvings of the failed particles at once
                b = np.flatnonzero(bad)
                m = len(halvings)
                tb = (xa[b, None, :] + halvings[None, :, None] * dx[b, None, :]).reshape(-1, xa.shape[1])
                rep = np.repeat(b, m)
                mot_b = None if mot is None else (mot[0][rep], mot[1][rep])
                lt = self.objective(obs, None, tb, free=free, motion=mot_b, derivs=False,
                                    context=self._take(sub, rep)).reshape(len(b), m)
                better = lt < big_l[b, None]
                first = np.argmax(better, axis=1)
                ok = better[np.arange(len(b)), first]
                trial[b] = np.where(ok[:, None], tb.reshape(len(b), m, -1)[np.arange(len(b)), first], xa[b])
                dx[b] = np.where(ok[:, None], dx[b], 0.0)
            x[active] = trial
            active = active[np.max(np.abs(dx), axis=1) > tol]
            if not len(active):
                break
        _, _, hess, gn = self.objective(obs, None, x, free=free, motion=motion, context=ctx)
        return x, _pd_or(hess, gn), ctx["u"]

    # ------------------------------------------------------------------ estimates
    def estimate(self, particles):
        """A state whose configuration is the weighted mean configuration ``Σ w_i h_i``.

        ``s = log‖h̄‖``, ``θ`` the weighted circular mean of ``θ_i`` and
        ``z = h̄ e^{-s - jθ}``; ``c``, ``U`` of the heaviest particle.
        """
        w = particles.weights
        hbar = w @ self.configuration(particles.states)
        nrm = max(np.linalg.norm(hbar), 1e-300)
        th = float(np.angle(w @ np.exp(1j * particles.states[:, 1])))
        best = particles.states[np.argmax(w)].copy()
        z = hbar / nrm * np.exp(-1j * th)
        best[0], best[1] = np.log(nrm), th
        best[self._sl["zr"]], best[self._sl["zi"]] = z.real, z.imag
        return best


def _inside_unit_ball(c):
    """``c`` scaled into ``cᵀc < 1`` where needed so that ``f`` stays real (never met at the paper's Σ_c)."""
    nrm2 = np.sum(c * c, axis=-1, keepdims=True)
    return np.where(nrm2 < 0.99, c, c * np.sqrt(0.99 / np.maximum(nrm2, 1e-300)))


def _norm_logpdf(r, var):
    return -0.5 * (r * r / var + np.log(2 * np.pi * var))


def _pd_or(hess, fallback):
    """``hess`` where positive definite (Cholesky succeeds), ``fallback`` elsewhere."""
    try:
        np.linalg.cholesky(hess)
        return hess
    except np.linalg.LinAlgError:
        pass
    ev = np.linalg.eigvalsh(0.5 * (hess + np.swapaxes(hess, -1, -2)))
    ok = ev[:, 0] > 1e-9 * np.maximum(np.abs(ev[:, -1]), 1e-300)
    return np.where(ok[:, None, None], hess, fallback)
