"""Basic-SIR (thesis 001, §3.2.1, Fig. 3.2): innovations from the image, histories at random.

Resample ``(X_{t-1}, w_{t-1})`` by the policy; the ``k``-th innovation ``x_1a ~ π(. | Y_t)``
is joined to the ``k``-th resampled history ``X̂^{(k)}``, whatever their agreement (Fig. 3.3);
``x_1b ~ K_1b(. | x_1a, X̂^{(k)})`` where the model has a ``1b`` part (the subspace form, as
plain ``sir`` with the model's proposal); ``w = ŵ_k r(Y_t | x_1) K_1a(x_1a | X̂^{(k)}) / π(x_1a | Y_t)``.
"""

from __future__ import annotations

import numpy as np

from .history import HistorySampling

__all__ = ["BasicSIR"]


class BasicSIR(HistorySampling):
    """Basic-SIR (Fig. 3.2); parameters as :class:`~vistrack.filters.history.HistorySampling`."""

    name = "basic-sir"

    def sample(self, hist, obs, rng, kernel):
        """Draw the new states ``(N, d)`` and their log-weight increments ``(N,)`` (Fig. 3.2)."""
        x1a, log_pi = self._proposed(len(hist.member), obs, rng)
        prev = hist.states[hist.member]
        x1 = x1a if self.k == self.a else np.concatenate([x1a, kernel.sample_rest(x1a, prev, rng)], axis=1)
        new = kernel.join(x1, prev)
        ll = self.model.loglik(obs, new)
        return new, hist.member_log_w + ll + kernel.subspace_logpdf(x1a, prev) - log_pi, ll
