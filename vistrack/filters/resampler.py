"""When and how a filter resamples (thesis 001, §2.5), and the birth reserve (§4.5.3).

:class:`Resampler` is the policy (resample every step, or when ``ESS < threshold · N``)
with a scheme of :mod:`vistrack.core.resampling`, drawing ancestors ``∝ π = w``.
:class:`BirthReserve` is a resampler whose ``π`` keeps a share ``ε`` of the draws for
the newest births; models with births (:class:`~vistrack.models.protocol.Births`,
:class:`~vistrack.models.protocol.ReservedLineages`) opt into it through their
``birth_reserve``. :func:`make_resampler` picks one for a model.
"""

from __future__ import annotations

import numpy as np

from ..core.particles import logsumexp
from ..core.resampling import get_scheme, needs_resampling
from ..models.protocol import Births, ReservedLineages, offers

__all__ = ["Resampler", "BirthReserve", "make_resampler"]


class Resampler:
    """Resample ``(Z_{t-1}, w_{t-1})`` when the policy says so.

    Parameters
    ----------
    scheme : str or callable
        ``multinomial``, ``residual``, ``stratified`` or ``systematic`` (App. A), or a
        ``scheme(w, n, rng) -> idx``.
    ess_threshold : float or None
        Resample every step when ``None`` (or ``>= 1``), else when ``ESS < ess_threshold · N``.
    """

    def __init__(self, scheme="systematic", ess_threshold=None):
        self.scheme = get_scheme(scheme)
        self.ess_threshold = ess_threshold

    def probs(self, particles):
        """Resampling probabilities ``π (N,)`` and the log-weights ``log(w / π) (N,)`` (up to a
        constant) the offspring carry; here ``π = w`` and the offspring carry equal weights."""
        return particles.weights, np.zeros(particles.n)

    def __call__(self, particles, rng, n=None):
        """Ancestor indices ``(n,)`` into ``particles`` and the log-weights ``(n,)`` the new
        particles start from.

        ``n`` (default ``particles.n``) other than ``particles.n`` always resamples (``n`` of
        more candidates must be chosen); otherwise the policy decides, and a set it keeps
        carries its own weights.
        """
        m = particles.n
        n = m if n is None else n
        if n == m and self.ess_threshold is not None and not needs_resampling(particles.ess, m, self.ess_threshold):
            return np.arange(m), particles.log_weights
        pi, log_w = self.probs(particles)
        idx = self.scheme(pi, n, rng)
        return idx, log_w[idx] - np.log(n)


class BirthReserve(Resampler):
    """Resampling that keeps a share ``ε`` of the draws for births (§4.5.3's entering cars).

    The births ``B`` are ``model.reserved(particles)`` (e.g. lineages a few frames old)
    or else ``model.entering(states)`` (e.g. a car entering the scene). They get ``ε`` of
    the draws on top of their weight: ``π_i = (1 - ε) w_i + ε ρ_i``, with ``ρ`` on ``B``
    ∝ the likelihood ``r`` each had at its frame (``particles.loglik``), or ∝ the weights
    where the filter gave none. Every particle with ``w_i > 0`` keeps ``π_i > 0`` and its
    offspring carry ``w_i / π_i``, so the expected weight of its offspring is ``w_i`` (the
    resampled set stays properly weighted).

    A birth on a new object that the tracked particles outweigh (by the entering
    density's small mass at that pose) then survives resampling with a small weight, and
    takes over when the next frames confirm it. The reserve goes ∝ ``r`` rather than
    ∝ ``w``: a birth's weight is about the likelihood's mass in its search window, so a
    birth in a broad plate-less region (``log r`` −10 over the whole window) would
    outweigh one on the narrow peak of a plate coming into view (``log r`` −0.6) and take
    the reserve's draws.

    Parameters
    ----------
    model : Births or ReservedLineages
    eps : float
        The share ``ε`` in ``[0, 1)`` (``ε = 1`` would leave the tracked particles no draws).
    scheme, ess_threshold
        As :class:`Resampler`.
    """

    def __init__(self, model, eps, scheme="systematic", ess_threshold=None):
        super().__init__(scheme, ess_threshold)
        self.model = model
        self.eps = _checked_reserve(eps)

    def births(self, particles):
        """Boolean mask ``(N,)`` of the births ``B``."""
        if offers(self.model, ReservedLineages):
            return self.model.reserved(particles)
        return self.model.entering(particles.states)

    def probs(self, particles):
        """``π = (1 - ε) w + ε ρ`` (class docstring) and the offspring log-weights ``log(w / π)``,
        both ``(N,)``; plain ``π = w`` when the births hold no weight or all of it.
        """
        w = particles.weights
        born = self.births(particles)
        w_b = float(w[born].sum())
        if not 0.0 < w_b < 1.0:
            return super().probs(particles)
        ll = None if particles.loglik is None else np.where(born, particles.loglik, -np.inf)
        if ll is not None and np.isfinite(ll.max()):
            rho = np.exp(ll - ll.max())
        else:
            rho = np.where(born, w, 0.0)
        pi = (1 - self.eps) * w + self.eps * rho / rho.sum()
        log_w = particles.log_weights - logsumexp(particles.log_weights)
        with np.errstate(divide="ignore", invalid="ignore"):
            return pi, np.where(pi > 0, log_w - np.log(pi), -np.inf)


def _checked_reserve(eps):
    if not 0.0 <= eps < 1.0:
        raise ValueError(f"birth_reserve must be in [0, 1), got {eps}")
    return float(eps)


def make_resampler(model, scheme="systematic", ess_threshold=None, birth_reserve=None):
    """The resampler a filter on ``model`` uses.

    ``birth_reserve`` ``None`` takes ``model.birth_reserve`` where the model has births
    (:class:`~vistrack.models.protocol.Births`), else 0; a positive reserve on a model
    with births gives a :class:`BirthReserve`, anything else a plain :class:`Resampler`.
    """
    has_births = offers(model, ReservedLineages) or offers(model, Births)
    eps = birth_reserve
    if eps is None:
        eps = model.birth_reserve if offers(model, Births) else 0.0
    eps = _checked_reserve(eps)
    if eps > 0 and has_births:
        return BirthReserve(model, eps, scheme, ess_threshold)
    return Resampler(scheme, ess_threshold)
