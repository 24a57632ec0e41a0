"""``vistrack run VIDEO``: track one video, write a track CSV and an annotated video."""

from __future__ import annotations

import os
from contextlib import contextmanager

import click

from vistrack import registry
from vistrack.core.resampling import SCHEMES
from vistrack.filters import SIR, ParticleFilter
from vistrack.filters.history import HistorySampling
from vistrack.io.clips import sequence_name
from vistrack.io.remote import is_url
from vistrack.io.results_format import FORMATS
from vistrack.io.track_files import columns_help
from vistrack.io.video import is_stream
from vistrack.registry import (
    DEFAULT_MODEL,
    FILTERS,
    LAYOUTS,
    MODELS,
    SEARCH_MODEL,
    all_algos,
    get_model_spec,
    run_option,
    targets_model,
)
from vistrack.session.plan import track_video
from vistrack.session.recording import record_video

from .errors import one_line
from .options import SEED, Box, Fraction, Output, check_outputs, check_writable, option
from .progress import Bars

__all__ = ["run"]


class _Video(click.Path):
    """A video file, image folder or clip folder that exists, a camera's index (``0``: a file or folder
    of that name wins), a live stream or a URL."""

    def __init__(self):
        super().__init__(exists=True)

    def convert(self, value, param, ctx):
        """The path checked as ``click.Path(exists=True)`` does, unless it names a camera, a stream or a URL."""
        if is_stream(value) or is_url(value):
            return value
        return super().convert(value, param, ctx)


#: ``--layout``'s default: the layout decided from the clip, the box or the plate found (the plate model's option)
AUTO_LAYOUT = run_option("--layout").default
#: every algorithm a registered model runs (the registry is the one list: ``eval --algos`` takes the same)
RUN_ALGOS = all_algos()


def _defaults():
    """``lis; pf-eis-mt for landmarks``: the models' default algorithms, the default model's first."""
    by_algo = {get_model_spec(DEFAULT_MODEL).default_algo: []}
    for spec in MODELS.values():
        by_algo.setdefault(spec.default_algo, []).append(spec.name)
    first, *others = by_algo
    return first + "".join(f"; {a} for {' and '.join(by_algo[a])}" for a in others)


def _history():
    """``Box and contour also run sir and the history-sampling family of thesis §3.2 (basic-sir, ...)``."""
    family = [n for n, f in FILTERS.items() if issubclass(f.cls, HistorySampling) and f.alias_of is None]
    sir = next(n for n, f in FILTERS.items() if f.cls is SIR)
    models = [s.name for s in MODELS.values() if sir in s.algos]
    return (" and ".join(models).capitalize() + f" also run {sir} and the history-sampling family of thesis §3.2 ("
            + ", ".join(family) + ")")


def lost_notice(say, most=5):
    """``lost(index, reason, detail)`` for :func:`~vistrack.session.plan.track_video`: a line to ``say`` (above
    the progress bar) for each of the first ``most`` frames where the object is lost."""
    said = []

    def notify(index, reason, detail):
        said.append(index)
        if len(said) <= most:
            say(f"frame {index}: lost the object ({reason}: {detail})"
                + ("; further losses in the summary" if len(said) == most else ""))

    return notify


#: ``run --help`` (the track CSV's columns and lost_reason values from their one list, :mod:`vistrack.io.track_files`)
RUN_HELP = """Track the object in VIDEO: a video file, an image folder or a clip folder, a camera's index (0,
1, ...; a file or folder of that name wins), a live stream (rtsp://...) or the URL of a video or
clip folder (http(s)://, s3://, ...: read with seeking where the server allows it, else downloaded
into a cache checked against the server on every use).

\b
Examples:
  vistrack run video.mp4 --init 120,80,60,60 --out annotated.mp4 --track track.csv   # box model, LIS
  vistrack run video.mp4 --init 120,80,60,60 --algo bootstrap -n 500 --results r.txt
  vistrack run ../shared/data/real/girl_otb --init-gt --out girl.mp4   # started from the ground truth
  vistrack synth contour --out clip && vistrack run clip --algo ls-n-ips -n 30 --init-gt --out a.mp4
  vistrack run video.mp4 --model contour --init 120,80,60,60 --track track.csv
  vistrack run video.mp4 --model contour --template hand.txt --out a.mp4

The track CSV has one row per frame of the input (every frame: one that failed to decode, or before
the first ground-truth box of --init-gt, too); a model writes the columns of its kind.

""" + columns_help() + """

run says on which frames it loses the object and why, and the annotated video draws the last box
reported, dashed and labelled "lost" with the reason, on those frames (and marks a re-detected one).
Ctrl-C or SIGTERM stops it after the frame in hand: the track, --results and --out then hold the
same frames. With ground truth beside the video, the summary reports the centre error (landmarks:
the mean landmark error).

\b
Several plates (--targets K): one row per frame and reported plate,
frame, visible, id, cx, ..., y3, ess, ms, lost_reason (a frame without
any: one row with visible=0, id=-1); each id has its colour in --out;
the summary gives MOTA and IDF1 against the clip's objects.csv.
  vistrack synth plate --overlap --cars 6 --out road && vistrack run road --targets 3 --out a.mp4

\b
Landmarks (seed 000): vistrack synth landmarks --out lm && vistrack run lm --algo pf-eis-mt --out lm.mp4
"""


@click.command(help=RUN_HELP)
@click.argument("video", type=_Video())
@click.option("--model", "model_name", default=None, metavar="[" + "|".join(MODELS) + "]",
              help="Tracking model, any registered one [default: the clip's meta.json model; else " + DEFAULT_MODEL
                   + " when --init or --init-gt is given (any object: colour and template learned from the first "
                   "frame); else " + SEARCH_MODEL + ", which finds plates by itself].")
@option("--layout", source=run_option("--layout"), key="default", type=click.Choice([AUTO_LAYOUT, *LAYOUTS]),
        help="Plate layout: auto decides between the two-row Japanese (jp) and the single-row layout from the clip, "
             "the --init box's aspect ratio or the plate found.")
@click.option("--algo", default=None, type=click.Choice(RUN_ALGOS),
              help="Particle filter [default: " + _defaults() + "]. " + _history() + ", whose innovations come "
                   "from the image only: the colour-blob proposal (the target's Gaussian colour learned from the "
                   "first frame, drawn over a grid of cells).")
@click.option("--search", type=click.Choice(["lms", "nn"]), default=None,
              help="LS-N-IPS on contour: the local search, LMS or the neural network trained on simulated "
                   "measurements (thesis §4.3.1; trained on first use, cached; see train-search) [default: lms].")
@option("-n", "--particles", source=registry, key="DEFAULT_PARTICLES", type=click.IntRange(min=1),
        help="Number of particles N.")
@option("--seed", source=track_video, type=SEED,
        help="Random seed: the same seed gives the same track, bit for bit. eval --seed S tracks a clip in its run 0 "
             "as run --seed S does (eval --runs 1 --seed S: this track), in its run r as --seed S --run r.")
@option("--run", "run_no", source=track_video, key="run", type=SEED,
        help="Track as eval's run R does under the same --seed (run 0 is --seed alone).")
@click.option("--init", type=Box(), help="Start from this box in the first frame: x,y,w,h in 0-based pixels (the "
                                        "top-left pixel is 0,0; OTB's and LaSOT's ground-truth files count from 1: "
                                        "use --init-gt to start from them). The contour is the "
                                        "ellipse in it.")
@click.option("--init-gt", "init_gt", is_flag=False, flag_value="", default=None, metavar="[FILE]",
              help="Start from the first ground-truth box, read in its dataset's own convention (OTB and LaSOT "
                   "1-based, VOT, GOT-10k and vistrack's groundtruth.csv 0-based): the clip's own, or FILE.")
@click.option("--template", "template_path", type=click.Path(dir_okay=False),
              help="Contour support points (x y per line, or JSON): used where they lie in the first "
                   "frame, or fitted to --init / --init-gt boxes. Default: an ellipse, or the clip's template. "
                   "Landmarks: the first frame's landmark positions.")
@click.option("--track", "track_path", type=Output(dir_okay=False), help="Write the track CSV here.")
@click.option("--out", "out_path", type=Output(dir_okay=False),
              help="Write the annotated video here: .mp4 (H.264, index first: plays in browsers while loading), .mkv, "
                   ".mov, or .avi (Motion JPEG).")
@click.option("--results", "results_path", type=Output(),
              help="Write the track as the tracking toolkits' result file: x,y,w,h per frame (0,0,0,0 where the "
                   "object is not reported). otb: this file, 1-based pixels as the OTB toolkit and pytracking "
                   "write them; got10k: the submission layout in this folder (SEQ/SEQ_001.txt, 0-based, and "
                   "SEQ/SEQ_time.txt); vot: this folder's SEQ/SEQ_001.txt (0-based, '1' on the first frame).")
@option("--results-format", "results_format", source=record_video, type=click.Choice(FORMATS),
        help="Format of --results (OTB is 1-based; GOT-10k and VOT 0-based).")
@option("--show-particles", source=track_video, type=click.IntRange(min=0),
        help="Draw the K highest-weight particles in the annotated video.")
@option("--resample", source=ParticleFilter, type=click.Choice(list(SCHEMES)),
        help="Resampling scheme of the particle filter.")
@click.option("--ess-threshold", default=None, type=Fraction(),
              help="Resample when ESS < threshold·N [default: every frame].")
@click.option("--targets", type=click.IntRange(min=1), default=None,
              help="Plate: track up to K plates at once, one slot each (found by themselves, no --init); the track "
                   "CSV has a row per frame and plate with its id. Default algorithm: "
                   + get_model_spec(targets_model()).multi_algos[0] + ".")
@click.option("--max-frames", type=click.IntRange(min=1), help="Stop after this many frames.")
@click.option("--no-colour", "no_colour", is_flag=True,
              help="Contour: edges only (no colour term, which is on for colour video). Plate: the plate "
                   "likelihood only (no appearance learned from the --init box).")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar and no summary.")
def run(video, model_name, layout, algo, search, particles, seed, init, init_gt, template_path, track_path, out_path,
        results_path, results_format, show_particles, resample, ess_threshold, targets, max_frames, no_colour, quiet,
        run_no=0):
    """``vistrack run``: :data:`RUN_HELP`."""
    _check_output_paths(video, track_path, out_path, results_path, results_format, (template_path, init_gt or None))
    if targets is not None and results_path:
        raise click.UsageError("--results writes one box per frame: not with --targets (use --track)")
    outputs = {"track_path": track_path, "out_path": out_path, "results_path": results_path,
               "results_format": results_format, "sequence": sequence_name(video)}
    bars = Bars(quiet)
    say = None if quiet else bars.note
    try:
        with one_line(), _output_errors():
            _, _, report = track_video(
                video, particles=particles, seed=seed, run=run_no, show_particles=show_particles, outputs=outputs,
                note=say, lost=say and lost_notice(say), compiling_progress=None if quiet else bars.compiling,
                frames=bars.frames, model=model_name, algo=algo, init=init, init_gt=init_gt, template=template_path,
                layout=None if layout == AUTO_LAYOUT else layout, no_colour=no_colour, targets=targets, search=search,
                resample=resample, ess_threshold=ess_threshold, max_frames=max_frames)
    finally:
        bars.close()
    _print(report, quiet)


def _check_output_paths(video, track_path, out_path, results_path, results_format, inputs):
    """One error line for an output ``run`` cannot write, or one that is an input or another output."""
    check_writable(track_path, "--track")
    check_writable(out_path, "--out")
    if results_format == "otb":  # its folder is made as the GOT-10k and VOT layouts' are
        check_writable(results_path, "--results", create=True)
    elif results_path is not None and os.path.exists(results_path) and not os.path.isdir(results_path):
        raise click.ClickException(f"--results {results_path}: the {results_format} layout is a folder "
                                   "(SEQ/SEQ_001.txt inside it), not a file")
    check_outputs({"--track": track_path, "--out": out_path, "--results": results_path}, video, inputs)


@contextmanager
def _output_errors():
    """An output that cannot be written (a full disk, one that cannot be opened) as one error line naming it."""
    try:
        yield
    except OSError as e:
        raise click.ClickException(str(e)) from None


def _print(report, quiet):
    """The :class:`~vistrack.session.run_summary.RunReport`: its notes on stderr, its lines (unless ``quiet``);
    its error line, or its exit code after an interrupt."""
    if report.error:
        raise click.ClickException(report.error)
    for line in report.notes:
        click.echo(line, err=True)
    for line in [] if quiet else report.lines:
        click.echo(line)
    if report.exit_code:
        raise click.exceptions.Exit(report.exit_code)
