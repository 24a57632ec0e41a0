"""The B-spline contour model (thesis 001, §1.3.1, §4.3.1, §4.4.3).

- :mod:`.model`: :class:`Contour`, the state, dynamics and edge likelihood;
- :mod:`.spline`: the closed cubic B-spline and its shape space;
- :mod:`.moves`: the local moves (LS-N-IPS's search, LLS, LIS); :mod:`.nn`: the learned search;
- :mod:`.colour`: the colour term on colour video;
- :mod:`.builder`: its registry entry; compiled kernels: :mod:`.kernels`, :mod:`.search_kernels`.
"""

from .model import Contour, ellipse_template, pose_from, pose_params

__all__ = ["Contour", "ellipse_template", "pose_from", "pose_params"]
