"""A ``vistrack run`` set up from what the user gave: :func:`prepare` loads the clip, chooses the model
(the one named, the clip's ``meta.json``'s, the default from a box, or the plate model that finds
plates by itself) and its algorithm (the registry's default), checks every option against the model
(:mod:`vistrack.registry`), builds the model and its filter, searches for a plate first where the model
starts from no box, and finds the start frame; :func:`execute` tracks it
(:func:`~vistrack.session.recording.record_video`), stopping cleanly on Ctrl-C or SIGTERM after the frame in hand.
"""

from __future__ import annotations

import itertools
import warnings
from dataclasses import dataclass

import numpy as np

from .. import kernels
from ..core.seeds import run_seed
from ..io.clips import load_clip
from ..io.starts import one_based_init_note, start_box_problem, start_frame
from ..io.video import VideoDecodeWarning, prefetch
from ..models.contour.nn import network_for
from ..models.plate.detect import PlateSearch
from ..registry import (
    DEFAULT_PARTICLES,
    OptionError,
    build_model,
    check_algo,
    check_particle_memory,
    get_model_spec,
    make_filter,
    model_params,
    read_support_points,
)
from ..registry.choice import choose
from ..system.compiling import compiling
from ..system.signals import stop_on_signals
from .recording import record_video
from .run_summary import run_report

__all__ = ["Plan", "prepare", "execute", "track_video"]


@dataclass
class Plan:
    """A run ready to track (:func:`prepare`).

    Attributes
    ----------
    clip : Clip
        The input (:func:`~vistrack.io.clips.load_clip`).
    model_name, algo : str
        The model and the algorithm chosen.
    model, filt : object
        The model built and its filter.
    frames : iterator of (int, ndarray)
        The frames to track, decoded ahead, up to ``max_frames``.
    start : int
        The first frame tracked (:func:`~vistrack.io.starts.start_frame`): earlier ones get rows too.
    lead : tuple of (int, ndarray)
        Frames searched without finding a plate before the first tracked one.
    found : tuple or None
        ``(index, frame, Detection)`` of the plate the search found.
    total : int or None
        The frames to expect (the input's count, up to ``max_frames``): a progress bar's length.
    """

    clip: object
    model_name: str
    algo: str
    model: object
    filt: object = None
    frames: object = None
    start: int = 0
    lead: tuple = ()
    found: tuple | None = None
    total: int | None = None


def prepare(video, *, model=None, algo=None, particles=DEFAULT_PARTICLES, init=None, init_gt=None, template=None,
             layout=None, no_colour=False, targets=None, search=None, resample="systematic", ess_threshold=None,
             max_frames=None, notify=None, compiler=None):
    """Set up ``vistrack run VIDEO`` (module docstring): returns a :class:`Plan`.

    ``template`` is a file of support points (:func:`~vistrack.registry.builders.read_support_points`);
    ``layout``, ``no_colour``, ``targets`` and ``search`` are ``run``'s model options (``None``/``False``:
    not given; :func:`~vistrack.registry.catalog.model_params`). ``notify(line)`` hears what the user should
    know on the way (how a URL was read, the model and algorithm and why: :mod:`vistrack.registry.choice`, a
    1-based box given as ``--init``, the plate search and what it found, training the network search; a
    download's progress bar when given). ``compiler`` (:class:`~vistrack.system.compiling.Compiler`) compiles the
    kernels of the model and algorithm chosen before anything calls them. Raises
    :class:`~vistrack.registry.OptionError` for options that do not go together or do not apply to the
    model, ``ValueError`` (``VideoError``) for bad input; each one line.
    """
    if init is not None and init_gt is not None:
        raise OptionError("give either --init or --init-gt, not both")
    clip = load_clip(video, progress=notify is not None)
    if clip.remote is not None and notify:  # read from the server, downloaded or a cached copy
        notify(clip.remote.describe())
    _check_init(init, clip.source.size)
    choice = choose(clip, model=model, algo=algo, init=init, init_gt=init_gt, targets=targets)
    name, algo, spec = choice.model, choice.algo, get_model_spec(choice.model)
    if notify:  # which model and algorithm, and why: one line
        notify(choice.line(particles))
    flags = {"--targets": targets, "--template": template and read_support_points(template),
             "--layout": layout, "--no-colour": no_colour or None, "--search": search}
    params = model_params(name, flags, algo)
    check_algo(name, algo, targets is not None, who=f"--algo {algo}")
    if compiler is not None:  # the options go together: compile before anything calls the kernels (building does)
        compiler.compile(name, [algo], targets is not None)
    # built first: what the model refuses by sense (more plates than a frame holds) before what memory allows
    built = build_model(name, clip, init=init, init_gt=init_gt, **params)
    check_particle_memory(particles, spec.bytes_per_particle, algo, targets=targets or 1)
    if search == "nn":  # train (once per template) or load before the first frame
        network_for(built, notify=notify)
    plan = Plan(clip, name, algo, built, frames=_frames(clip.source, max_frames))
    src = clip.source
    plan.total = src.frame_count if max_frames is None else min(max_frames, src.frame_count or max_frames)
    if isinstance(built, PlateSearch):  # real footage without a box: find the plate first
        _find_plate(plan, video, notify)
    plan.filt = make_filter(algo, plan.model, resample=resample, ess_threshold=ess_threshold)
    plan.start = start_frame(clip, init, init_gt)
    note = one_based_init_note(clip, init)
    if note and notify:
        notify(note)
    if plan.start and notify:
        notify(f"note: the ground truth has no box before frame {plan.start}: tracking starts there (frames 0-"
               f"{plan.start - 1} get rows with visible=0, lost_reason \"not started\"; scores count from frame "
               f"{plan.start})")
    if plan.start and max_frames is not None and plan.start >= max_frames:
        raise ValueError(f"--init-gt: the ground truth's first box is at frame {plan.start}, past --max-frames "
                         f"{max_frames}")
    return plan


def _check_init(init, size):
    """An ``--init`` box outside the frame (its centre not in it: :func:`~vistrack.io.starts.start_box_problem`)
    is an :class:`~vistrack.registry.OptionError`, found before anything is built."""
    problem = None if init is None else start_box_problem(init, size)
    if problem and problem[0] == "outside":
        raise OptionError(problem[1])


def _frames(src, max_frames):
    """The ``(index, frame)`` pairs of ``src`` (decoded ahead), up to ``max_frames``."""
    for i, f in prefetch(src):
        if max_frames is not None and i >= max_frames:
            return
        yield i, f


def _find_plate(plan, video, notify):
    """The plate model built where the plan's :class:`~vistrack.models.plate.detect.PlateSearch` finds a
    plate in the first frames, the frames from that one on, and the frames searched before it; a
    ``ValueError`` with the ``--init`` hint where it finds none."""
    search = plan.model
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", VideoDecodeWarning)
        model, found, lead = search.start(plan.frames)
    if model is None:
        raise ValueError(f"no license plate found in the first {len(lead)} frames of {video}; give its box: "
                         f"vistrack run {video} --init x,y,w,h")
    if notify:
        b = found[2].box
        notify(f"plate found in frame {found[0]} at {b[0]:.0f},{b[1]:.0f},{b[2]:.0f},{b[3]:.0f} "
               f"({found[2].layout} layout)")
    plan.model, plan.found, plan.lead = model, found, tuple(lead)
    plan.frames = itertools.chain([found[:2]], plan.frames)


def execute(plan, particles, seed=0, *, label="", show_particles=10, progress=None, notify=None, ready=None, **outputs):
    """Track ``plan`` with ``particles`` particles from ``seed`` (an integer or a ``SeedSequence``:
    :func:`~vistrack.core.seeds.run_seed`): :func:`~vistrack.session.recording.record_video` over its frames from its
    start (``outputs``: ``track_path``, ``out_path``, ``results_path``, ``results_format``, ``sequence``;
    ``ready()`` once the kernels are loaded), the decoder's warnings for skipped frames left to the summary, and
    Ctrl-C or SIGTERM honoured after the frame in hand (the outputs so far kept, holding the same frames).
    Returns the :class:`~vistrack.session.recording.SessionLog`."""
    src = plan.clip.source
    frames = ((i, f) for i, f in plan.frames if i >= plan.start)
    # an image folder's frame count is exact: frames after the last decodable one get rows too
    exact = plan.total if src.exact_count else None
    with stop_on_signals(), warnings.catch_warnings():
        warnings.simplefilter("ignore", VideoDecodeWarning)
        return record_video(frames, plan.model, plan.filt, particles, np.random.default_rng(seed),
                           video_info=(src.fps, src.size), show_particles=show_particles, label=label,
                           progress=progress, notify=notify, frame_count=exact, start=plan.start, lead=plan.lead,
                           ready=ready, **outputs)


def track_video(video, *, particles=DEFAULT_PARTICLES, seed=0, run=0, show_particles=10, outputs=None, note=None,
                lost=None, compiling_progress=None, frames=None, **options):
    """``vistrack run VIDEO``: :func:`prepare` with ``options`` (its keywords), the kernels of the model and
    algorithm chosen compiled first, then :func:`execute` from ``seed``'s stream of run ``run``
    (:func:`~vistrack.core.seeds.run_seed`) into ``outputs`` (``track_path``, ``out_path``, ``results_path``,
    ``results_format``, ``sequence``). Returns ``(plan, log, report)``: the :class:`Plan`, the
    :class:`~vistrack.session.recording.SessionLog` and the :class:`~vistrack.session.run_summary.RunReport`.

    What the user hears on the way, each optional: ``note(line)`` (:func:`prepare`'s notes),
    ``lost(index, reason, detail)`` where the object is lost, ``compiling_progress(done, total)`` while the
    kernels compile (:func:`~vistrack.system.compiling.compiling`: the first run after an install, until
    tracking starts), and ``frames(label, total, initial)``, called when tracking starts, returning the
    ``progress(ess)`` told after every frame (a progress bar)."""
    outputs = dict(outputs or {})
    with compiling(compiling_progress, kernels.use()) as compiler:
        plan = prepare(video, particles=particles, notify=note, compiler=compiler, **options)
        label, tick = f"{plan.algo} N={particles}", []

        def ready():  # the kernels are loaded: tracking starts
            compiler.progress = None
            tick.append(frames(label, plan.total, len(plan.lead)) if frames else None)

        def progress(ess):
            if tick[-1]:
                tick[-1](ess)

        done = execute(plan, particles, run_seed(seed, run), label=label, show_particles=show_particles,
                       progress=progress, notify=lost, ready=ready, **outputs)
    return plan, done, run_report(video, plan, done, particles, outputs)
