"""License-plate tracking model (thesis 001, §1.3.2, §4.5.2): AR(2) and entering-car dynamics,
the birth reserve, the learned appearance for ``--init``; the likelihood is
:mod:`~vistrack.models.plate.likelihood`, the LIS proposal :mod:`~vistrack.models.plate.proposal`."""

from __future__ import annotations

import numpy as np

from ...core.gaussian import diag_logpdf
from ...proposals import Window
from ..protocol import VideoModelBase
from .appearance import PlateAppearance
from .likelihood import LEARNT_WEIGHTS, PlateLikelihood, PlateObservation, scale_band, thesis_weights
from .proposal import PlateLISProposal

__all__ = ["Plate", "PlateLikelihood", "PlateObservation", "PlateLISProposal", "thesis_weights", "scale_band",
           "LEARNT_WEIGHTS"]


class Plate(PlateAppearance, VideoModelBase):
    """License-plate tracking model (thesis 001, §1.3.2, §4.5.2).

    State ``(u, w, θ, s, u', w', θ', s', a)``: centre, angle of the non-vertical
    sides, width (px), their previous values, and the lineage's age ``a`` — frames
    since its entering draw (0 for a draw of the entering component, +1 per AR(2)
    step; it changes neither ``K`` nor ``r``, only what the resampling reserve keeps). Dynamics: with probability
    0.9 a factored AR(2), ``z_t = z_{t-1} + d (z_{t-1} - z_{t-2}) + σ ε``; with
    probability 0.1 a new car entering, ``z_t ~ N(m_e, diag(σ_e²))`` with zero
    velocity (previous = current). Likelihood: :class:`PlateLikelihood`.
    Local moves act on translation ``(u, w)`` (§4.5.2), and for an entering particle also on
    the scale; an entering particle moves its previous pose along (it stays a zero-velocity start).

    Parameters
    ----------
    frame_size : tuple of int
    layout : str
    enter_weight : float
        Weight of the entering-car component (0.1).
    sharpness : float
        Multiplies ``log r`` (:class:`PlateLikelihood`); :meth:`visible` still thresholds the
        log-odds.
    enter_mean, enter_std : array_like of 4 floats
        The entering-car Gaussian over ``(u, w, θ, s)``. Default: ``u`` over the frame (0.5 W,
        sd 0.35 W); ``w``, ``θ``, ``s`` from the plates of the 16 training clips
        (:mod:`~vistrack.models.plate.fitting`'s seeds): their mean ``w`` 0.69 H and ``s`` 0.125 W,
        with twice their spread (sd 0.025 H and 0.010 W there: 0.05 H and 0.02 W) and ``θ`` sd
        0.1 rad (0.06 there). With these, births at the suite's entering frames end within a third
        of the plate height 16 % of the time, against 9.4 % with 0.1 H and 0.03 W, which leave most
        births 20–50 % off the entering plate's scale, where the entering search does not reach it;
        on 10 clips × 10 runs LIS-100's P(lost) is 0.038 against 0.055 and its mean acquisition
        delay 1.4 frames against 2.1 (docs/experiments.md). A scene where plates appear elsewhere or
        at other sizes needs its own values.
    enter_sides : float
        Share of the entering component placed where cars come in — Gaussians at the
        left and right borders (``u`` at 0.1 W and 0.9 W, sd 0.07 W), the rest the broad
        Gaussian over the road (§1.3.2: "cars appear on one side of the image and
        disappear at the other end").
    birth_reserve : float
        Share ``ε`` of the resampled particles that goes to the young lineages
        (:meth:`reserved`), ∝ their likelihood, with the offspring weights corrected (unbiased).
        A plate that enters while the track sits on a sign or a lane mark is found by the
        births, but the entering density's small mass at the plate's pose (about e^-12 of
        the tracked pose's) lets plain resampling drop them; kept with a small weight, they
        take over in the next frames. On 10 clips × 10 runs, ε = 0.05 for the fresh births
        gave LIS-100 P(lost) 0.085 instead of 0.105 (bootstrap-750: 0.178 instead of 0.226);
        0.15 gave no further gain.
    reserve_age : int
        Lineages younger than this many frames are reserved. Reserving only the fresh
        births kept a birth through one resampling, and its offspring — still at a small
        weight, with a rough pose — were dropped at the next. On 10 clips × 10 runs (with the
        refined entering search), ages < 1 / 3 / 5 frames: acquired within 10 frames 99 / 99
        / 100 % of 300 appearances.
    lambda_dcf : float
        ``λ_dcf``: with a learned appearance (:meth:`learn_appearance`, real footage), the weight of the
        box model's correlation filter's response (:class:`~vistrack.appearance.correlation.CorrelationFilter`
        on the plate's box, about 1 at the plate) in ``log r``, read at the state's centre and width
        (:meth:`dcf_states`; the angle is the plate likelihood's and the template's). 0: no filter.
        20: on the 10 plate clips of ``benchmarks/bench_plate_real.py`` from the first box (with the
        first view kept, :attr:`adapt_rate`) the mean AUC is 0.916 against 0.911 without the filter,
        the 6-px shaken dashcam's 0.903 against 0.846; 60 lowers the shaken clips (docs/experiments.md).
    dcf_options : dict or None
        Passed to :class:`~vistrack.appearance.correlation.CorrelationFilter` (the box model's defaults).
    """

    dim = 9

    def __init__(self, frame_size, layout="jp", *, enter_weight=0.1, damping=(0.8, 0.8, 0.5, 0.5), sigma=None,
                 enter_mean=None, enter_std=None, enter_sides=0.5, kappa=2.0, weights="learnt", sharpness=1.0,
                 birth_reserve=0.05, reserve_age=5, lambda_dcf=20.0, dcf_options=None):
        w, h = frame_size
        self.lambda_dcf, self.dcf_options = float(lambda_dcf), dict(dcf_options or {})
        self.frame_size = (int(w), int(h))
        self.lik = PlateLikelihood(layout, kappa=kappa, weights=weights, sharpness=sharpness)
        #: the estimate is reported visible when ``log r`` at it exceeds this: with the learnt
        #: coefficients log-odds 2.5, the lowest with no false report on the 16 training clips
        #: (LIS-100 × 5 runs: 1 / 1.5 / 2 / 2.5 / 3 gave 37 / 30 / 13 / 0 / 0 false reports in 80
        #: runs, all on one sign, at P(lost) 0.053 / 0.055 / 0.058 / 0.062 / 0.068);
        #: 10 for the thesis's coefficients (not calibrated)
        self.visible_loglik = 2.5 if self.lik.learnt else 10.0
        self.visible_margin = 4.0
        #: with a level here, the estimate is reported only when each half of the plate, scored
        #: alone (:meth:`PlateLikelihood.half_loglik`), also exceeds it: a plate a car in front
        #: covers from one side fails in that half (None: no half test; :class:`Plates` sets 2)
        self.visible_half = None
        self.layout = self.lik.layout
        self.enter_weight = float(enter_weight)
        self.damping = np.asarray(damping, float)
        self.sigma = np.asarray(sigma if sigma is not None else (0.012 * w, 0.008 * h, 0.01, 0.004 * w), float)
        self.enter_mean = np.asarray(enter_mean if enter_mean is not None else (0.5 * w, 0.69 * h, 0.0, 0.125 * w),
                                     float)
        self.enter_std = np.asarray(enter_std if enter_std is not None else (0.35 * w, 0.05 * h, 0.1, 0.02 * w),
                                    float)
        self.enter_sides = float(enter_sides)
        #: share of the resampled particles kept for the entering-car births (see
        #: :class:`~vistrack.filters.resampler.BirthReserve`)
        self.birth_reserve = float(birth_reserve)
        #: lineages younger than this many frames since their entering draw are in the reserve
        self.reserve_age = int(reserve_age)
        #: entering components: (weight, mean, std) — the broad one and one per side
        side_std = np.array([0.07 * w, self.enter_std[1], self.enter_std[2], self.enter_std[3]])
        self._enter_parts = [(1.0 - self.enter_sides, self.enter_mean, self.enter_std)] + [
            (self.enter_sides / 2, np.array([fx * w, *self.enter_mean[1:]]), side_std) for fx in (0.1, 0.9)]
        self.prior_mean = np.concatenate([self.enter_mean, self.enter_mean, [0.0]])
        #: plate widths (px) the model allows; the dynamics clip to it
        self.scale_range = (0.05 * w, 0.4 * w)

    # -- dynamics ----------------------------------------------------------------
    def sample_entering(self, n, rng):
        weights = np.array([p[0] for p in self._enter_parts])
        comp = rng.choice(len(weights), size=n, p=weights / weights.sum())
        means = np.array([p[1] for p in self._enter_parts])[comp]
        stds = np.array([p[2] for p in self._enter_parts])[comp]
        z = means + stds * rng.standard_normal((n, 4))
        z[:, 3] = np.clip(z[:, 3], *self.scale_range)
        return np.concatenate([z, z, np.zeros((n, 1))], axis=1)

    def enter_logpdf(self, z):
        """Log density of the entering-car mixture at poses ``z (N, 4)``."""
        parts = [np.log(wt) + diag_logpdf(z, m, sd) for wt, m, sd in self._enter_parts if wt > 0]
        return np.logaddexp.reduce(np.stack(parts), axis=0)

    #: optional ``(mean, std)`` of the first pose (``--init``); else the entering density
    start = None

    def sample_prior(self, n, rng):
        """``n`` states ``(n, 9)`` from ``p_0``: the entering-car mixture, or the ``--init`` Gaussian
        (:attr:`start`); zero velocity and age."""
        if self.start is None:
            return self.sample_entering(n, rng)
        mean, std = self.start
        z = mean + std * rng.standard_normal((n, 4))
        return np.concatenate([z, z, np.zeros((n, 1))], axis=1)

    def prior_logpdf(self, states):
        """``log p_0`` of the current pose of ``states (N, 9)`` -> ``(N,)``."""
        if self.start is None:
            return self.enter_logpdf(states[:, :4])
        mean, std = self.start
        return diag_logpdf(states[:, :4], mean, std)

    def predict_mean(self, states):
        """The mean of the AR(2) branch (thesis 001 §1.3.2): ``z + d (z - z')``, previous pose ``z``, age + 1;
        ``(N, 9)`` -> ``(N, 9)``."""
        z1, z2 = states[:, :4], states[:, 4:8]
        return np.concatenate([z1 + self.damping * (z1 - z2), z1, states[:, 8:] + 1], axis=1)

    def predict(self, states, rng):
        """A draw from ``K`` (§1.3.2): the factored AR(2), or with probability :attr:`enter_weight` (0.1) an entering
        car; ``(N, 9)`` -> ``(N, 9)``."""
        n = len(states)
        out = self.predict_mean(states)
        out[:, :4] += self.sigma * rng.standard_normal((n, 4))
        out[:, 3] = np.clip(out[:, 3], *self.scale_range)
        enter = rng.random(n) < self.enter_weight
        if enter.any():
            out[enter] = self.sample_entering(int(enter.sum()), rng)
        return out

    @staticmethod
    def entering(states):
        """Particles that are a fresh entering-car draw (previous pose = current pose)."""
        return np.all(states[:, 4:8] == states[:, :4], axis=1)

    def reserved(self, particles):
        """The particles the resampling reserve keeps (:attr:`birth_reserve`): the lineages
        younger than :attr:`reserve_age` frames since their entering draw (the fresh births
        when the states carry no age)."""
        x = particles.states
        return x[:, 8] < self.reserve_age if x.shape[1] > 8 else self.entering(x)

    def transition_logpdf(self, new, old):
        """``log K(new|old)`` for the branch ``new`` came from (AR(2) or entering car)."""
        ar = np.log1p(-self.enter_weight) + diag_logpdf(new[:, :4], self.predict_mean(old)[:, :4], self.sigma)
        with np.errstate(divide="ignore"):  # enter_weight 0 (a plate found on real footage): no births
            ent = np.log(self.enter_weight) + self.enter_logpdf(new[:, :4])
        return np.where(self.entering(new), ent, ar)

    def estimate(self, particles):
        """The weighted mean of the particles about the posterior's main mode: those within half
        a plate (centre) and 25 % (scale) of the highest-weight particle. With one plate in the
        model a posterior split between the plate and a plate-like sign would otherwise put the
        mean between them."""
        x, w = particles.states, particles.weights
        best = x[np.argmax(w)]
        near = (np.hypot(x[:, 0] - best[0], x[:, 1] - best[1]) <= 0.5 * best[3]) & \
            (np.abs(x[:, 3] - best[3]) <= 0.25 * best[3])
        return (w[near] @ x[near]) / w[near].sum()

    def loglik(self, obs, states):
        """``log r`` of ``states (N, 9)`` -> ``(N,)``: :class:`PlateLikelihood`, plus the learned appearance term
        when there is one."""
        ll = self.lik.loglik(obs, states)
        if self.app is not None:
            log_rc, log_rt, _ = self._app_terms(obs, states)
            ll = ll + (log_rc + log_rt)
        resp = obs.dcf if isinstance(obs, PlateObservation) else None
        if resp is not None and self.lambda_dcf:
            ll = ll + self.lambda_dcf * resp.read(self.dcf_states(states))
        return ll

    def check_lost(self, obs, state):
        """``(reason, detail)`` (:meth:`visible`), remembered for the correlation filter's adaptation."""
        out = super().check_lost(obs, state)
        self._reported = not out[0]
        return out

    def vertices(self, states):
        """The parallelogram's four vertices ``(N, 4, 2)`` of ``states (N, 9)`` or ``(9,)``."""
        from .layout import plate_vertices

        return plate_vertices(np.atleast_2d(states)[:, :4], self.layout.aspect)

    def outline(self, states):
        """The vertices ``(N, 4, 2)`` (:meth:`vertices`), to draw."""
        return self.vertices(states)

    def box(self, states):
        """Bounding boxes ``(N, 4)`` ``(x, y, w, h)`` of the parallelograms."""
        v = self.vertices(states)
        lo, hi = v.min(axis=1), v.max(axis=1)
        return np.concatenate([lo, hi - lo], axis=1)

    def visible(self, obs, state):
        """Whether a plate is reported at ``state``: ``log r`` above :attr:`visible_loglik` (and, with
        :attr:`visible_half` set, each half's ``log r`` above that level) and the whole
        parallelogram at least :attr:`visible_margin` px inside the frame (the ground truth
        counts a plate as in view when it is wholly inside; an estimate at the border is as
        likely a plate half gone). With a learned appearance (:meth:`learn_appearance`), also
        when the estimate matches the first frame's plate: the template's ``ncc`` at least the
        appearance's adaptation bar (0.6)."""
        s = np.asarray(state, float).reshape(1, -1)
        v = self.vertices(s)[0]
        w, h = self.frame_size
        d = self.visible_margin
        inside = bool(np.all((v[:, 0] >= d) & (v[:, 0] <= w - 1 - d) & (v[:, 1] >= d) & (v[:, 1] <= h - 1 - d)))
        if not inside:
            return False
        if bool(self.lik.loglik(obs, s)[0] / self.lik.sharpness > self.visible_loglik) and (
                self.visible_half is None or bool(np.all(self.lik.half_loglik(obs, s)[0] / self.lik.sharpness
                                                         > self.visible_half))):
            return True
        if self.app is None:
            return False
        return bool(self._app_terms(obs, s)[2, 0] >= self.app.adapt_min_ncc)

    def describe(self, state):
        """Track-file fields of one state: ``cx, cy, w, h, angle_deg, scale`` and the vertices ``x0..x3, y0..y3``."""
        s = np.asarray(state, float).reshape(1, -1)
        v = self.vertices(s)[0]
        lo, hi = v.min(axis=0), v.max(axis=0)
        row = {"cx": s[0, 0], "cy": s[0, 1], "w": hi[0] - lo[0], "h": hi[1] - lo[1],
               "angle_deg": float(np.rad2deg(s[0, 2])), "scale": s[0, 3]}
        for i in range(4):
            row[f"x{i}"], row[f"y{i}"] = v[i]
        return row

    # -- local moves on translation (§4.5.2) -------------------------------------
    def local_coords(self, states):
        """The translation ``(u, w)``, ``(N, 9)`` -> ``(N, 2)`` (§4.5.2)."""
        return states[:, :2]

    def with_local(self, states, u):
        """``states (N, 9)`` moved to the translations ``u (N, 2)``; an entering particle moves its previous pose
        along (a zero-velocity start)."""
        out = states.copy()
        ent = self.entering(states)
        out[:, :2] = u
        out[ent, 4:6] = u[ent]
        return out

    with_local_prior = with_local

    def plate_size(self, states):
        """Plate width and height ``(N, 2)`` (px)."""
        s = states[:, 3]
        return np.stack([s, s / self.layout.aspect], axis=1)

    def lis_proposal(self, kernel=None):
        """LIS's proposal for a step with ``kernel`` (:class:`PlateLISProposal`)."""
        return PlateLISProposal(self, kernel=kernel)

    def loglik_local_grid(self, obs, states, offsets):
        """LLS's grid (:class:`~vistrack.filters.lls.LLS`): ``log r`` at every pose shifted by the
        translation ``offsets (G, 2)``, from the sparse point sets of the LIS scans — ``(N, G)``.
        Only LLS's proposal uses it; its weight takes the full ``r`` at the drawn pose."""
        off = np.broadcast_to(np.asarray(offsets, float)[None], (len(states),) + np.shape(offsets))
        return self.lik.loglik_sparse(obs, states, off)

    def lls_window(self, kernel=None):
        """LLS's box window: a 9×9 grid over the entering plate's width and height."""
        size = self.enter_mean[3]
        return Window("box", (size, size / self.layout.aspect), grid=9)
