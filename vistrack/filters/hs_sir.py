"""SIR with history sampling, HS-SIR (thesis 001, §3.2.2, Fig. 3.4).

All ``N`` innovations ``x_1^{(k)} ~ π(. | Y_t)`` are drawn first; the pairs ``(l, k)`` of a
history ``X_{t-1}^{(l)}`` and an innovation weigh
``w^{(l,k)} = w_{t-1}^{(l)} r(Y_t | x_1^{(k)}) K_1(x_1^{(k)} | X_{t-1}^{(l)}) / π(x_1^{(k)} | Y_t)``
(eq. 3.4), and ``N`` pairs are resampled ∝ ``w^{(l,k)}`` with the filter's scheme over the
flattened ``(N, C)`` array: the law of ``J`` (the innovation) then ``I | J`` (the history) of
Fig. 3.4, with the low-variance schemes applied to the pairs directly. HS-SIR resamples every
step by construction (no ESS policy): its new particles are equally weighted, each carrying
``(1/N) Σ w^{(l,k)} / N`` so that the weights' sum stays the unbiased estimate. The image-only
proposal gives ``x_1a``; a ``1b`` part comes from the predictive mixture of the previous set
(:meth:`~vistrack.filters.history.HistorySampling.innovations`).
"""

from __future__ import annotations

import numpy as np

from ..core.particles import logsumexp
from .history import HistorySampling

__all__ = ["HSSIR"]


class HSSIR(HistorySampling):
    """HS-SIR (Fig. 3.4); parameters as :class:`~vistrack.filters.history.HistorySampling`
    (``ess_threshold`` does not apply: every step resamples the pairs)."""

    name = "hs-sir"
    resamples_first = False

    def sample(self, hist, obs, rng, kernel):
        """Draw the new states ``(N, d)`` with sampled history indices and their log-weight increments ``(N,)``
        (Fig. 3.4)."""
        n = len(hist.member)
        x1, log_pi = self.innovations(hist, obs, rng, kernel)
        ll = self._loglik(obs, x1, hist, kernel)
        log_pair = (ll - log_pi - np.log(n))[:, None] + hist.log_w[None] + self.pair_logpdf(x1, hist, kernel)
        total = logsumexp(log_pair)
        c = log_pair.shape[1]
        if not np.isfinite(total):
            return kernel.join(x1, hist.states[np.zeros(n, int)]), np.full(n, -np.inf), ll
        pick = self.resampler.scheme(np.exp(log_pair.ravel() - total), n, rng)
        k, l = np.divmod(pick, c)
        return kernel.join(x1[k], hist.states[l]), np.full(n, total - np.log(n)), ll[k]
