"""The kernel a filter step predicts with: :mod:`vistrack.transition` (a core module, so that
proposals and filters need not import :mod:`vistrack.models`), re-exported for the models."""

from ..transition import PriorKernel, Transition, is_prior

__all__ = ["Transition", "PriorKernel", "is_prior"]
