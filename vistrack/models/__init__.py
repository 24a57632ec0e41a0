"""Tracking problems: dynamics + likelihood (+ local proposal), one module each."""

from .bearings.model import Bearings
from .toy import AR2Toy, GaussMixtureToy

__all__ = ["AR2Toy", "Bearings", "GaussMixtureToy"]
