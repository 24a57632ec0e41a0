"""Local proposals and windows shared by models and filters (models never import filters)."""

from .blob import BlobProposal, GaussianColour, SubspaceProposal
from .map_proposal import MapProposal, categorical_rows
from .mixture import GaussMixtureProposal
from .window import Window

__all__ = ["BlobProposal", "GaussianColour", "SubspaceProposal", "MapProposal", "GaussMixtureProposal", "Window",
           "categorical_rows"]
