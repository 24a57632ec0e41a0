"""Bearings-only tracking (the seeds' non-video problem): :mod:`.model` (:class:`Bearings`), the ξ
proposal (:mod:`.xi`) and its compiled kernels (:mod:`.kernels`)."""

from .model import Bearings

__all__ = ["Bearings"]
