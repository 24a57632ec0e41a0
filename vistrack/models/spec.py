"""What a video model offers ``run``, ``eval`` and ``vistrack.Tracker``: its registry entry's form.

Each model package's ``builder`` module defines one :class:`ModelSpec` (``SPEC``); the registry
(:mod:`vistrack.registry`) holds them and derives from :attr:`ModelSpec.model_class` which algorithms
run on each.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

__all__ = ["ModelSpec", "ModelOption"]


@dataclass(frozen=True)
class ModelOption:
    """A keyword option of a model's builder.

    Attributes
    ----------
    name : str
        The builder's keyword (``colour``, ``layout``, ...).
    default : object
    help : str
    flag : str or None
        The ``vistrack run`` option that sets it (``--no-colour``, ...).
    value : object
        What the flag passes (``None``: the option's own value; ``False`` for ``--no-colour``).
    needs : Protocol or None
        It is for the algorithms that need this protocol of the model (``--search``: those of
        :class:`~vistrack.models.protocol.LocalSearch`); ``None``: for all.
    """

    name: str
    default: object
    help: str
    flag: str | None = None
    value: object = None
    needs: type | None = None


@dataclass(frozen=True)
class ModelSpec:
    """One registered video model.

    Attributes
    ----------
    name : str
    algos : tuple of str or None
        Algorithms that run on it, the default first; ``None``: every algorithm whose protocols
        :attr:`model_class` offers, in the filter registry's order
        (:func:`vistrack.registry.algos_for`). A tuple given here is the model's choice among them.
    description : str
    box_init : bool
        Whether it can start from an ``(x, y, w, h)`` box.
    from_box : callable or None
        ``from_box(frame, box, **params) -> model``: started from ``box`` ``(x, y, w, h)`` in the
        first ``frame`` (BGR or grey array); what ``vistrack.Tracker`` and ``run --init`` call.
    from_clip : callable or None
        ``from_clip(clip, *, init, init_gt, template, **params) -> model`` for ``run`` and
        ``eval`` on a clip; ``None``: ``from_box`` at the start box (``init`` or the first
        ground-truth row) in the clip's first frame.
    lost_rule : {"centre", "plate"}
        How ``eval`` decides a frame is lost (:func:`vistrack.scoring.metrics.lost_frames`).
    bytes_per_particle : int
        Peak working memory of one step per particle (bytes; measured, rounded up), for
        :func:`vistrack.registry.catalog.check_particle_memory`.
    multi_algos : tuple of str or None
        Algorithms that track several targets at once (``run``/``eval --targets K``), the default
        first; ``None``: derived from :attr:`targets_class` (none without one).
    model_class : type or None
        The class of the models it builds: the protocols it offers decide which filters run on it.
    targets_class : type or None
        The class of its several-target form (the plate model's :class:`~vistrack.models.plate.plates.Plates`).
    seed : str
        The seed it comes from (``"001"``: the thesis, ``"000"``: the PF-EIS paper): the names its
        algorithms are listed under (``condensation`` on the thesis's models, ``pf-gordon`` on the paper's).
    options : tuple of ModelOption
        Its builder's options that ``run`` sets (with their flags).
    summary : callable or None
        ``summary(rows, truth, model) -> str or None``: ``run``'s line against ground truth of the model's
        own kind (the plate's vertices, the landmarks), from the track rows and the ground truth's
        columns; ``None`` (or ``None`` returned, where the truth has no such columns): the box scores of
        :mod:`vistrack.session.run_summary`, as ``eval`` scores a task.
    passes_on : tuple of type
        Classes its model passes keyword options on to (the box model's ``**appearance`` to
        :class:`~vistrack.appearance.cues.Appearance`): their documented parameters are options of the model
        too, each checked against its declared type and range (:mod:`vistrack.registry.option_types`).
    """

    name: str
    algos: tuple | None = None
    description: str = ""
    box_init: bool = True
    from_box: Callable | None = None
    from_clip: Callable | None = None
    lost_rule: str = "centre"
    bytes_per_particle: int = 64_000
    multi_algos: tuple | None = None
    model_class: type | None = None
    targets_class: type | None = None
    seed: str = "001"
    options: tuple = ()
    summary: Callable | None = None
    passes_on: tuple = ()

    @property
    def default_algo(self):
        """The default algorithm: the first of :attr:`algos`."""
        return self.algos[0]

    def option(self, flag):
        """Its option that ``run``'s ``flag`` sets, or ``None``."""
        return next((o for o in self.options if o.flag == flag), None)
