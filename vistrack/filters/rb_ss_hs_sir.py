"""Rao-Blackwellised subspace SIR with history sampling, RB-SS-HS-SIR (thesis 001, §3.2.4, Fig. 3.7).

The image-only proposal acts on ``X_{t,1a}`` (translation) only. Resample by the policy into
``C`` distinct histories ``X̂^{(l)}`` with weights ``ŵ_l``; draw ``x_1a^{(k)} ~ π(. | Y_t)``;
draw its history with law ``p(I_k = l) ∝ ŵ_l K_1a(x_1a^{(k)} | X̂^{(l)})``; draw the rest of the
innovation ``x_1b ~ K_1b(. | x_1a, X̂^{(I_k)})``; weigh
``w_k = r(Y_t | x_1^{(k)}) Σ_l ŵ_l K_1a(x_1a^{(k)} | X̂^{(l)}) / π(x_1a^{(k)} | Y_t)`` (divided by
``N``; Fig. 3.7's sum is over all histories ``l``).
"""

from __future__ import annotations

import numpy as np

from .history import HistorySampling, associate

__all__ = ["RBSSHSSIR"]


class RBSSHSSIR(HistorySampling):
    """RB-SS-HS-SIR (Fig. 3.7); parameters as :class:`~vistrack.filters.history.HistorySampling`."""

    name = "rb-ss-hs-sir"

    def sample(self, hist, obs, rng, kernel):
        """Draw the new states ``(N, d)`` (the proposal on ``X_{t,1a}``, ``K_1b`` for the rest) and their
        log-weight increments ``(N,)`` (Fig. 3.7)."""
        n = len(hist.member)
        x1a, log_pi = self._proposed(n, obs, rng)
        idx, log_mix = associate(lambda rows: hist.log_w[None] + self.pair_logpdf(x1a[rows], hist, kernel), n,
                                 len(hist.log_w), rng, self.resampler.scheme)
        prev = hist.states[idx]
        x1 = x1a if self.k == self.a else np.concatenate([x1a, kernel.sample_rest(x1a, prev, rng)], axis=1)
        new = kernel.join(x1, prev)
        ll = self.model.loglik(obs, new)
        return new, ll + log_mix - log_pi - np.log(n), ll
