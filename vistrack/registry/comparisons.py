"""What the seeds compare, and the demo: the algorithms of their tables and figures, with the particle
counts where they fix them (``(algorithm, N)`` entries). The reproductions and ``vistrack demo`` take
their default algorithms (and the demo its comparison tracker) from here, so that no list of algorithm or
tracker names sits outside the registry.
"""

from __future__ import annotations

__all__ = ["CONTOUR", "HISTORY_SAMPLING", "PLATE", "PLATES", "BEARINGS", "LANDMARKS", "SEED_000_ORDER", "DEMO",
           "DEMO_REAL"]

#: thesis 001 Table 4.1 (a contour in clutter with a distractor): LS-N-IPS with 30 particles against the
#: bootstrap filter with 2000
CONTOUR = (("ls-n-ips", 30), ("bootstrap", 2000))
#: Table 3.1 (history sampling, colour clips): Basic-SIR with 3000 against RB-SS-HS-SIR with 400, at equal time
HISTORY_SAMPLING = (("basic-sir", 3000), ("rb-ss-hs-sir", 400))
#: §4.5.3, Figs. 4.15-4.16 (plates acquired without a box): LIS with 100 against bootstrap with 750
PLATE = (("lis", 100), ("bootstrap", 750))
#: App. C with §4.5.3 (several plates at once): partitioned LIS with 100 against bootstrap with 2000
PLATES = (("partitioned-lis", 100), ("bootstrap", 2000))
#: §4.5.5, Tables 4.3 and 4.4 (bearings-only ships): bootstrap, AVPF and LIS, each at every N
BEARINGS = ("bootstrap", "avpf", "lis")
#: seed 000 §4: Fig. 2a (K = 5) PF-EIS, PF-Doucet and PF-Gordon; Fig. 2b (K = 8) PF-EIS-MT, PF-EIS and PF-Gordon
LANDMARKS = {5: ("pf-eis", "pf-doucet", "pf-gordon"), 8: ("pf-eis-mt", "pf-eis", "pf-gordon")}
#: seed 000's filters in the order the paper introduces them (a landmark run's random streams follow it)
SEED_000_ORDER = ("pf-gordon", "pf-doucet", "pf-eis", "pf-eis-mt")
#: ``vistrack demo``: the box model's LS-N-IPS, LIS and bootstrap at about equal time per frame on a clip of
#: sudden jumps in heavy clutter (docs/experiments.md)
DEMO = (("ls-n-ips", 30), ("lis", 30), ("bootstrap", 150))
#: ``vistrack demo``'s real clip: the comparison trackers beside vistrack's default tracker (the default model's
#: default algorithm at the default N): OpenCV's MIL, which every OpenCV build has
DEMO_REAL = (("opencv-mil", 1),)
