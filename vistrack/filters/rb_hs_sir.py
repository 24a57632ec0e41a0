"""Rao-Blackwellised SIR with history sampling, RB-HS-SIR (thesis 001, §3.2.3, Fig. 3.5).

Resample ``(X_{t-1}, w_{t-1})`` by the policy into ``C`` distinct histories ``X̂^{(l)}`` with
weights ``ŵ_l``; draw ``x_1^{(k)} ~ π(. | Y_t)``; draw each innovation's history index with
law ``p(I_k = l) ∝ ŵ_l K_1(x_1^{(k)} | X̂^{(l)})``; weigh
``w_k = r(Y_t | x_1^{(k)}) Σ_l ŵ_l K_1(x_1^{(k)} | X̂^{(l)}) / π(x_1^{(k)} | Y_t)`` (divided by
``N``: the weights' sum is the unbiased estimate). The innovation index ``J`` of HS-SIR is
integrated out. A ``1b`` part of the innovation comes from the predictive mixture
(:meth:`~vistrack.filters.history.HistorySampling.innovations`).
"""

from __future__ import annotations

import numpy as np

from .history import HistorySampling, associate

__all__ = ["RBHSSIR"]


class RBHSSIR(HistorySampling):
    """RB-HS-SIR (Fig. 3.5); parameters as :class:`~vistrack.filters.history.HistorySampling`."""

    name = "rb-hs-sir"

    def sample(self, hist, obs, rng, kernel):
        """Draw the new states ``(N, d)`` with the history Rao-Blackwellised out of the weight, and their
        log-weight increments ``(N,)`` (Fig. 3.5)."""
        n = len(hist.member)
        x1, log_pi = self.innovations(hist, obs, rng, kernel)
        idx, log_mix = associate(lambda rows: hist.log_w[None] + self.pair_logpdf(x1[rows], hist, kernel), n,
                                 len(hist.log_w), rng, self.resampler.scheme)
        new = kernel.join(x1, hist.states[idx])
        ll = self.model.loglik(obs, new)
        return new, ll + log_mix - log_pi - np.log(n), ll
