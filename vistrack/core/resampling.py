"""Resampling schemes (thesis 001, §2.5 and Appendix A).

Each scheme is ``scheme(w, n, rng) -> idx``: ``w`` normalised weights of shape
``(N,)``, ``n`` the number of indices to draw, ``idx`` an int array of shape
``(n,)``. Expected duplication counts are ``n * w`` for every scheme; residual,
stratified and systematic have lower variance than multinomial.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "multinomial",
    "residual",
    "stratified",
    "systematic",
    "SCHEMES",
    "get_scheme",
    "needs_resampling",
    "grouped",
    "Groups",
]


def _inverse_cdf(u, w):
    """Indices ``argmin_k u_i <= C_k`` for uniforms ``u`` in (0, 1] (App. A.3)."""
    cdf = np.cumsum(w)
    cdf[-1] = 1.0  # guard against round-off: every u <= 1 finds an index
    return np.searchsorted(cdf, u, side="left")


def multinomial(w, n, rng):
    """Multinomial resampling (Fig. 2.1): ``U_i ~ U(0, 1]`` i.i.d."""
    return _inverse_cdf(1.0 - rng.random(n), w)


def stratified(w, n, rng):
    """Stratified resampling (App. A.3): ``U_i ~ U((i-1)/n, i/n]``."""
    u = (np.arange(n) + 1.0 - rng.random(n)) / n
    return _inverse_cdf(u, w)


def systematic(w, n, rng):
    """Systematic resampling (App. A.4): ``U_i = (i-1)/n + U``, ``U ~ U(0, 1/n]``."""
    u = (np.arange(n) + 1.0 - rng.random()) / n
    return _inverse_cdf(u, w)


def residual(w, n, rng):
    """Residual resampling (App. A.2): ``floor(n w_i)`` copies plus a multinomial remainder."""
    nw = n * np.asarray(w)
    counts = np.floor(nw).astype(np.int64)
    r = n - counts.sum()
    if r > 0:
        rest = nw - counts
        rest_sum = rest.sum()
        if rest_sum > 0:
            counts += np.bincount(
                multinomial(rest / rest_sum, r, rng), minlength=len(w)
            )
        else:  # round-off: put the remainder on the heaviest particles
            counts[np.argsort(-nw)[:r]] += 1
    return np.repeat(np.arange(len(w)), counts)


SCHEMES = {
    "multinomial": multinomial,
    "residual": residual,
    "stratified": stratified,
    "systematic": systematic,
}


class Groups:
    """Consecutive groups of particles (for :func:`grouped`): group ``s`` is the next
    ``sizes[s]`` particles.

    Attributes
    ----------
    sizes, starts : int arrays (S,)
        Each group's size (positive) and first particle.
    of, start_of, within : int arrays (N,)
        Each particle's group, its group's first particle and its place in the group.
    """

    def __init__(self, sizes):
        self.sizes = np.asarray(sizes, dtype=np.intp)
        self.starts = np.cumsum(self.sizes) - self.sizes
        self.of = np.repeat(np.arange(len(self.sizes)), self.sizes)
        self.start_of = self.starts[self.of]
        self.within = np.arange(len(self.of)) - self.start_of
        self._size_of = self.sizes[self.of].astype(float)

    def uniforms(self, scheme, rng):
        """The uniforms of ``scheme`` in every group at once, ``(N,)`` in (0, 1]; ``None`` where
        the scheme has no grouped form."""
        if scheme is multinomial:
            return 1.0 - rng.random(len(self.of))
        if scheme is stratified:
            return (self.within + 1.0 - rng.random(len(self.of))) / self._size_of
        if scheme is systematic:
            return (self.within + 1.0 - rng.random(len(self.sizes))[self.of]) / self._size_of
        return None


def grouped(scheme, w, groups, rng):
    """``scheme`` run within each group of consecutive particles, all groups in one call.

    Parameters
    ----------
    scheme : callable
        :func:`multinomial`, :func:`stratified` or :func:`systematic` (the others have no
        grouped form).
    w : ndarray (N,)
        Weights normalised within each group (every group's sum is 1).
    groups : Groups or int array (S,)
        The groups (or their sizes, positive and summing to ``N``).
    rng : numpy.random.Generator

    Returns
    -------
    ndarray (N,) or None
        Every group draws as many indices as it has particles, into itself, with the
        scheme's uniforms (the systematic scheme one uniform per group); ``None`` for a
        scheme without a grouped form.
    """
    groups = groups if isinstance(groups, Groups) else Groups(groups)
    u = groups.uniforms(scheme, rng)
    if u is None:
        return None
    cdf = np.cumsum(w)
    cdf -= np.repeat(cdf[groups.starts] - w[groups.starts], groups.sizes)  # within each group
    cdf[groups.starts + groups.sizes - 1] = 1.0  # round-off: every u <= 1 finds an index in its group
    # shifting group s by s keeps the order; u + s <= s + 1 exactly, u + s > s but for round-off
    return np.maximum(np.searchsorted(cdf + groups.of, u + groups.of, side="left"), groups.start_of)


def get_scheme(name):
    """The scheme registered as ``name`` (a callable passes through)."""
    if callable(name):
        return name
    try:
        return SCHEMES[name]
    except KeyError:
        raise ValueError(
            f"unknown resampling scheme {name!r}; choose from {', '.join(SCHEMES)}"
        ) from None


def needs_resampling(ess, n, threshold):
    """Resampling policy: every step when ``threshold is None`` or ``>= 1``,
    else when ``ESS < threshold * N``."""
    if threshold is None or threshold >= 1.0:
        return True
    return ess < threshold * n
