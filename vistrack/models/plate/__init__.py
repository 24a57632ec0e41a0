"""The license-plate model (thesis 001, §1.3.2): one plate or several, found without a box.

- :mod:`.model`: :class:`Plate`, the quadrilateral state and its dynamics;
- :mod:`.layout`: the plate layouts (jp two-row, single-row); :mod:`.likelihood`, :mod:`.observation`:
  the template likelihood; :mod:`.fit`: fitting its weights;
- :mod:`.appearance`: the learned appearance and correlation filter on real footage;
- :mod:`.proposal`: the LIS line-scan proposal; :mod:`.plates`, :mod:`.plates_proposal`: several plates;
- :mod:`.detect`, :mod:`.classifier`: finding plates over the whole frame;
- :mod:`.builder`: its registry entry; compiled kernels: :mod:`.kernels`, :mod:`.scan_kernels`.
"""

from .model import Plate
from .plates import Plates

__all__ = ["Plate", "Plates"]
