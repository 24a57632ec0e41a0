"""Local proposals shared by models (models never import filters)."""

from .grid import MapProposal, categorical_rows

__all__ = ["MapProposal", "categorical_rows"]
