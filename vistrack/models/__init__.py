"""Tracking problems: dynamics + likelihood (+ local proposal), one module each."""

from .bearings import Bearings
from .toy import GaussMixtureToy

__all__ = ["Bearings", "GaussMixtureToy"]
