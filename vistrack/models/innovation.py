"""The innovation/history split of AR(2) pose models (thesis 001, §3.2, Assumption 3.2.1).

For a state ``(z_t, z_{t-1})`` with Gaussian dynamics of diagonal covariance,
``z_t ~ N(m(X_{t-1}), diag(s(X_{t-1})²))``, the innovation ``X_{t,1} = z_t`` is the current
pose and the history ``X_{t,2} = f(X_{t-1})`` the previous state's current pose. The pose
starts with the translation, ``X_{t,1a}`` (where the colour-blob proposal acts,
:class:`~vistrack.proposals.BlobProposal`); the rest ``X_{t,1b}`` (scale, rotation) is
independent of it given ``X_{t-1}``, so ``K_1b(. | x_1a, X_{t-1})`` is the Gaussian of those
coordinates (§3.2.4's easy case). ``p_0`` draws ``z`` from ``N(init_pose, diag(prior_std²))``
and starts at rest, ``X_1 = (z, z)``.
"""

from __future__ import annotations

import numpy as np

from ..core.gaussian import diag_logpdf
from ..core.transition import Transition
from ..proposals.blob import BlobProposal, GaussianColour, SubspaceProposal

__all__ = ["ARPrior", "ARInnovation"]


class ARPrior:
    """Mixin: ``p_0`` of an AR(2) pose state ``(z, z')``: ``z ~ N(init_pose, diag(prior_std²))`` at rest (``z' = z``).

    The model supplies ``init_pose`` and ``prior_std`` (each ``(d,)``, or ``prior_std`` a scalar)."""

    def sample_prior(self, n, rng):
        """``n`` states ``(n, 2 d)`` from ``p_0``: a Gaussian about the first pose, zero velocity."""
        z = self.init_pose + self.prior_std * rng.standard_normal((n, np.size(self.init_pose)))
        return np.concatenate([z, z], axis=1)

    def prior_logpdf(self, states):
        """``log p_0`` of the current pose of ``states (N, 2 d)`` -> ``(N,)``."""
        return diag_logpdf(states[:, :np.size(self.init_pose)], self.init_pose, self.prior_std)


class ARInnovation(ARPrior):
    """Mixin: :class:`~vistrack.models.protocol.InnovationSplit` for states ``(z_t, z_{t-1})``.

    The model supplies ``dim``, ``predict_mean(states)``, ``innovation_std(states) -> (N, k)``,
    ``init_pose``, ``prior_std``, ``outline(states)`` (the target's polygon, for
    :meth:`learn_blob`), ``blob_cell`` (the proposal's cell side, frame px) and
    ``blob_image(obs) -> (image, x0, y0, f)`` (what the proposal looks at).
    """

    #: ``X_{t,1a}``: the translation
    subspace_dim = 2
    #: the target's colour (:meth:`learn_blob`); ``None``: not learned
    blob_colour = None

    @property
    def innovation_dim(self):
        """Components of the innovation ``X_{t,1}``: the current pose (half the state)."""
        return self.dim // 2

    def history(self, prev):
        """``f(X_{t-1})``: its current pose."""
        return prev[..., :self.dim // 2]

    def _moments(self, prev):
        """Mean and std ``(..., k)`` of ``K_1(. | prev)`` for ``prev (..., d)``."""
        prev = np.asarray(prev, float)
        flat = prev.reshape(-1, self.dim)
        shape = prev.shape[:-1] + (self.dim // 2,)
        return self.predict_mean(flat)[:, :self.dim // 2].reshape(shape), self.innovation_std(flat).reshape(shape)

    def subspace_logpdf(self, x1a, prev):
        """``log K_1a(x1a | prev)``, broadcast over leading axes (``(N, C)`` pairs)."""
        m, s = self._moments(prev)
        a = self.subspace_dim
        return diag_logpdf(x1a, m[..., :a], s[..., :a])

    def rest_logpdf(self, x1b, x1a, prev):
        """``log K_1b(x1b | x1a, prev)``, broadcast over leading axes."""
        m, s = self._moments(prev)
        a = self.subspace_dim
        return diag_logpdf(x1b, m[..., a:], s[..., a:])

    def sample_rest(self, x1a, prev, rng):
        """A draw of ``X_{t,1b} ~ K_1b(. | x1a, prev)`` (Gaussian), shape ``(..., k - a)``."""
        m, s = self._moments(prev)
        a = self.subspace_dim
        return m[..., a:] + s[..., a:] * rng.standard_normal(m[..., a:].shape)

    def prior_subspace_logpdf(self, x1a):
        """``log p_0`` of the subspace part ``x1a (..., a)``."""
        a = self.subspace_dim
        return diag_logpdf(x1a, self.init_pose[:a], self.prior_std[:a])

    def prior_rest_logpdf(self, x1b, x1a):
        """``log p_0`` of the rest ``x1b`` (independent of ``x1a`` here)."""
        a = self.subspace_dim
        return diag_logpdf(x1b, self.init_pose[a:], self.prior_std[a:])

    def sample_prior_rest(self, x1a, rng):
        """A draw of the rest ``X_{1,1b}`` from ``p_0``, shape ``(..., k - a)``."""
        a = self.subspace_dim
        rest = self.init_pose[a:]
        return rest + self.prior_std[a:] * rng.standard_normal(np.shape(x1a)[:-1] + rest.shape)

    def join_prior(self, x1):
        """``X_1 = (z, z)``: at rest."""
        return np.concatenate([x1, x1], axis=-1)

    # -- the colour-blob proposal (§3.2.5) ---------------------------------------------------
    def learn_blob(self, frame, mask=None):
        """Learn the target's :class:`~vistrack.proposals.GaussianColour` from ``frame``'s pixels
        in ``mask`` (default: inside the outline at the initial pose); returns it."""
        import cv2

        if mask is None:
            poly = np.round(self.outline(self.prior_mean[None])[0]).astype(np.int32)
            mask = np.zeros(frame.shape[:2], np.uint8)
            cv2.fillPoly(mask, [poly], 1)
        self.blob_colour = GaussianColour.fit(frame, mask)
        return self.blob_colour

    def innovation_proposal(self, kernel=None):
        """``π(X_{t,1a} | Y_t)``: the colour-blob proposal (needs :meth:`learn_blob`)."""
        if self.blob_colour is None:
            raise ValueError(f"the colour-blob proposal needs the target's colour: "
                             f"{type(self).__name__}.learn_blob(first_frame) first")
        return BlobProposal(self.blob_colour, self.blob_image, self.blob_cell)

    def sir_proposal(self, kernel=None):
        """Plain SIR's proposal: the colour blob on translation, ``K_1b`` for the rest."""
        return SubspaceProposal(self.innovation_proposal(kernel), kernel or Transition(self), self.subspace_dim,
                                self.innovation_dim)
