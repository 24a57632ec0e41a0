"""Local-search N-IPS, LS-N-IPS (thesis 001, §4.3, Fig. 4.2).

Predict ``X_t ~ K(.|Z_{t-1})``, refine ``Z_t = LS_λ(X_t, Y_t)`` with a local
search that should satisfy ``r(Y_t|LS_λ(x, Y_t)) >= r(Y_t|x)``, weight
``w_t = r(Y_t|Z_t)``. The move is not compensated in the weight: the filter
is biased relative to the bootstrap filter, with ``λ`` bounding the bias
(``λ = 0`` is the bootstrap filter).

The local search is model-supplied: ``model.local_search(obs, states)``
(e.g. the LMS fit of edges along the contour normals, §4.3.1).
"""

from __future__ import annotations

from ..models.protocol import LearnedSearch, LocalSearch, StateSpaceModel, require
from .base import ParticleFilter

__all__ = ["LSNIPS", "LSNIPSNN"]


class LSNIPS(ParticleFilter):
    """LS-N-IPS filter.

    Parameters
    ----------
    local_search : callable or None
        ``local_search(obs, states) -> states`` or ``-> (states, loglik)``; ``None`` takes ``model.local_search``.
    """

    name = "ls-n-ips"
    needs = (StateSpaceModel,)
    part_needs = (LocalSearch,)

    def __init__(self, model, local_search=None, **kwargs):
        super().__init__(model, **kwargs)
        if local_search is None:
            require(model, (LocalSearch,), self.name)
        self.local_search = local_search

    def propose(self, prev, obs, rng, kernel):
        """§4.3, Fig. 4.2: ``X_t ~ K``, ``Z_t = LS_λ(X_t)``, log increment ``log r(Y_t|Z_t)``
        (uncompensated: the search's density is not in the weight).

        Parameters and returns as :meth:`ParticleFilter.propose`: ``prev (N, d)`` ->
        ``(new (N, d), log_incr (N,), predicted (N, d), loglik (N,))``.
        """
        x = kernel.predict(prev, rng)
        search = self.local_search or self.model.local_search
        z = search(obs, x)
        if isinstance(z, tuple):  # the search may return the log-likelihoods it computed
            z, ll = z
        else:
            ll = self.model.loglik(obs, z)
        return z, ll, x, ll


class LSNIPSNN(LSNIPS):
    """LS-N-IPS with the model's learned local search (``model.searcher("nn")``: the contour
    model's neural network, §4.3.1 Fig. 4.5), whatever the model's default search."""

    name = "ls-n-ips-nn"
    part_needs = (LearnedSearch,)

    def __init__(self, model, **kwargs):
        require(model, (LearnedSearch,), f"{self.name} (a learned local search)")
        super().__init__(model, local_search=model.searcher("nn"), **kwargs)
