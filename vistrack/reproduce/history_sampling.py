"""The history-sampling experiment (thesis 001, §3.2.5, Figs. 3.9-3.10, Table 3.1) on synthetic
colour contour clips.

A contour with the thesis's edge likelihood is tracked on clips whose object has a distinctive
colour and an identical distractor lies in the scene (``make_contour_clip(color=True,
distractor=True)``), so the colour-blob proposal keeps drawing fake positions that must be
filtered out. Every (clip, algorithm, N, run) is a task of the evaluation engine
(:mod:`vistrack.evaluation.experiment`), as the contour experiment's; lost is the centre error above 50 px
at 240-px width, scaled (Fig. 3.10), and the mean error is over runs not lost (Fig. 3.9).
Table 3.1 ran Basic-SIR with 3000 particles against RB-SS-HS-SIR with 400, at equal time;
:func:`equal_time_entries` finds such particle counts on this machine. ``HSConfig.likelihood``
sets the edge likelihood's parameters for every algorithm alike (:func:`likelihood_params`;
empty: the contour model's defaults).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..io.clips import load_clip
from ..loop.stepper import filter_ms
from ..registry import build_model
from ..registry.comparisons import HISTORY_SAMPLING
from ..scoring.metrics import equal_time
from .contour import ContourConfig

__all__ = ["HSConfig", "DEFAULT_ENTRIES", "LIKELIHOOD_KEYS", "hs_tasks", "equal_time_entries", "likelihood_params"]

#: Table 3.1's algorithms and particle counts
DEFAULT_ENTRIES = list(HISTORY_SAMPLING)


@dataclass
class HSConfig(ContourConfig):
    """The §3.2.5 experiment: colour contour clips, ``(algo, N)`` entries, runs per clip and the
    root seed (the contour experiment's tasks and summaries)."""

    entries: list = field(default_factory=lambda: list(DEFAULT_ENTRIES))
    #: the contour model's likelihood parameters for every task (:data:`LIKELIHOOD_KEYS`)
    likelihood: dict = field(default_factory=dict)

    table = "hs-sir"
    #: the folder of its task files when ``--out`` is not given
    results_dir = "hs-sir-results"

    def tasks(self):
        """:func:`hs_tasks`."""
        return hs_tasks(self)

    def equal_time(self, frames=20):
        """:func:`equal_time_entries` on the first clip: ``(entries, {"algo:N": ms per frame})``."""
        return equal_time_entries(self.clips[0], self.entries, frames, self.likelihood)


#: the edge likelihood's parameters that ``likelihood`` may set, with their types
#: (:class:`~vistrack.models.contour.model.Contour`)
LIKELIHOOD_KEYS = {"sigma_edge": float, "q_miss": float, "clutter_density": float, "measure_per_segment": int,
                   "edge_threshold": float}


def likelihood_params(text):
    """``{key: value}`` from ``"KEY=VALUE,..."`` (keys of :data:`LIKELIHOOD_KEYS`, positive values);
    a ``ValueError`` with a one-line message otherwise. ``""`` gives ``{}``."""
    out = {}
    for item in filter(None, (i.strip() for i in str(text).split(","))):
        key, _, value = item.partition("=")
        if key not in LIKELIHOOD_KEYS:
            raise ValueError(f"unknown likelihood parameter {key!r}; choose from {', '.join(LIKELIHOOD_KEYS)}")
        try:
            out[key] = LIKELIHOOD_KEYS[key](value)
        except ValueError:
            kind = "an integer" if LIKELIHOOD_KEYS[key] is int else "a number"
            raise ValueError(f"{key} needs {kind}, got {value!r}") from None
        if not out[key] > 0:
            raise ValueError(f"{key} must be positive, got {value}")
    return out


def hs_tasks(cfg):
    """The contour experiment's tasks of ``cfg`` (an :class:`HSConfig`), each building its model with
    ``cfg.likelihood``."""
    tasks = ContourConfig.tasks(cfg)
    if cfg.likelihood:  # absent by default, so the default tasks (and their --resume files) stay as they are
        for t in tasks:
            t["model_params"] = dict(cfg.likelihood)
    return tasks


def equal_time_entries(clip_path, entries, frames=20, likelihood=None):
    """``entries`` with every N after the first set so that its time per frame matches the first
    entry's (:func:`~vistrack.scoring.metrics.equal_time`: a line through N and 2N), timed on the first
    ``frames`` frames of ``clip_path`` with the model built with ``likelihood``, as Table 3.1's counts
    were chosen. Returns ``(entries, {"algo:N": ms per frame})`` at the given N."""
    clip = load_clip(clip_path)
    fr = []
    for i, f in clip.source:
        if i >= frames:
            break
        fr.append((i, f))
    model = build_model(HSConfig.model, clip, init_gt="", **(likelihood or {}))
    return equal_time(lambda algo, n: filter_ms(fr, model, algo, n), entries)
