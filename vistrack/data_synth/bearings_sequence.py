"""State/observation sequences of the bearings-only problem (thesis 001, §4.5.5).

The true initial state ``x_1`` is fixed at the prior mean ("keeping the
initial position fixed") and observed, as in Gordon et al. (1993); the
filters start from the prior ``p_0`` and update it with ``y_1``. The simulation is the
model's own (:func:`vistrack.models.bearings.model.simulate`), re-exported here.
"""

from __future__ import annotations

from vistrack.models.bearings.model import simulate

__all__ = ["simulate"]
