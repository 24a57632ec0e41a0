"""``vistrack run VIDEO``: track one video, write a track CSV and an annotated video."""

from __future__ import annotations

import itertools
import os
import sys
import warnings

import click
import numpy as np
from tqdm import tqdm

from vistrack.registry import (DEFAULT_MODEL, DEFAULT_PARTICLES, MODELS, OptionError, all_algos, check_algo,
                               get_model_spec, model_params, build_model, read_support_points)
from vistrack.registry.builders import start_frame
from vistrack.io.clips import load_clip
from vistrack.filters import make_filter
from vistrack.models.contour.nn import network_for
from vistrack.models.plate.detect import PlateSearch
from vistrack.engine.evaluation import sequence_name
from vistrack.io.results_format import FORMATS, result_paths
from vistrack.core.runtime import check_particle_memory
from vistrack.track.run import stop_on_signals, summary_lines, track_video
from vistrack.io.outputs import OutputBusy
from vistrack.io.video import is_stream, VideoDecodeWarning, VideoError, prefetch

from .options import SEED, Box, Fraction, check_outputs, check_writable

__all__ = ["run"]


class _Video(click.Path):
    """A video file, image folder or clip folder that exists, a camera's index (``0``) or a stream URL."""

    def __init__(self):
        super().__init__(exists=True)

    def convert(self, value, param, ctx):
        """The path checked as ``click.Path(exists=True)`` does, unless it names a camera or a stream."""
        if is_stream(value) and not os.path.exists(value):
            return value
        return super().convert(value, param, ctx)

#: every algorithm a registered model runs (the registry is the one list: ``eval --algos`` takes the same)
RUN_ALGOS = all_algos()


def lost_notice(most=5):
    """``notify(index, reason, detail)`` for :func:`~vistrack.track.run.track_video`: a line on stderr
    (above the progress bar) for each of the first ``most`` frames where the object is lost."""
    said = []

    def notify(index, reason, detail):
        said.append(index)
        if len(said) <= most:
            tqdm.write(f"frame {index}: lost the object ({reason}: {detail})"
                       + ("; further losses in the summary" if len(said) == most else ""), file=sys.stderr)

    return notify


@click.command()
@click.argument("video", type=_Video())
@click.option("--model", "model_name", default=None, metavar="[" + "|".join(MODELS) + "]",
              help="Tracking model, any registered one [default: the clip's meta.json model; else box when --init or --init-gt "
                   "is given (any object: colour and template learned from the first frame); else plate, "
                   "which finds plates by itself].")
@click.option("--layout", type=click.Choice(["auto", "jp", "single-row"]), default="auto", show_default=True,
              help="Plate layout: auto decides between the two-row Japanese (jp) and the single-row layout from "
                   "the clip, the --init box's aspect ratio or the plate found.")
@click.option("--algo", default=None, type=click.Choice(RUN_ALGOS),
              help="Particle filter [default: lis; pf-eis-mt for landmarks]. Contour and box also run sir and "
                   "the history-sampling family of thesis §3.2 (basic-sir, hs-sir, rb-hs-sir, rb-ss-hs-sir), "
                   "whose innovations come from the image only: the colour-blob proposal (the target's "
                   "Gaussian colour learned from the first frame, drawn over a grid of cells).")
@click.option("--search", type=click.Choice(["lms", "nn"]), default=None,
              help="LS-N-IPS on contour: the local search, LMS or the neural network trained on simulated "
                   "measurements (thesis §4.3.1; trained on first use, cached; see train-search) [default: lms].")
@click.option("-n", "--particles", default=DEFAULT_PARTICLES, show_default=True, type=click.IntRange(min=1),
              help="Number of particles N.")
@click.option("--seed", default=0, show_default=True, type=SEED, help="Random seed (same seed, same track).")
@click.option("--init", type=Box(), help="Start from this box (x,y,w,h) in the first frame; the contour is the "
                                        "ellipse in it.")
@click.option("--init-gt", "init_gt", is_flag=False, flag_value="", default=None, metavar="[FILE]",
              help="Start from the first ground-truth frame: the clip's own (groundtruth.csv with meta.json "
                   "template, or OTB groundtruth_rect.txt), or FILE.")
@click.option("--template", "template_path", type=click.Path(dir_okay=False),
              help="Contour support points (x y per line, or JSON): used where they lie in the first "
                   "frame, or fitted to --init / --init-gt boxes. Default: an ellipse, or the clip's template. "
                   "Landmarks: the first frame's landmark positions.")
@click.option("--track", "track_path", type=click.Path(dir_okay=False), help="Write the track CSV here.")
@click.option("--out", "out_path", type=click.Path(dir_okay=False),
              help="Write the annotated video here: .mp4 (H.264, index first: plays in browsers while loading), .mkv, .mov, or .avi (Motion JPEG).")
@click.option("--results", "results_path", type=click.Path(),
              help="Write the track as the tracking toolkits' result file: x,y,w,h per frame (0,0,0,0 where the "
                   "object is not reported). otb: this file, 1-based pixels as the OTB toolkit and pytracking "
                   "write them; got10k: the submission layout in this folder (SEQ/SEQ_001.txt, 0-based, and "
                   "SEQ/SEQ_time.txt); vot: this folder's SEQ/SEQ_001.txt (0-based, '1' on the first frame).")
@click.option("--results-format", "results_format", type=click.Choice(FORMATS), default="otb", show_default=True,
              help="Format of --results (OTB is 1-based; GOT-10k and VOT 0-based).")
@click.option("--show-particles", default=10, show_default=True, type=click.IntRange(min=0),
              help="Draw the K highest-weight particles in the annotated video.")
@click.option("--resample", default="systematic", show_default=True,
              type=click.Choice(["multinomial", "residual", "stratified", "systematic"]),
              help="Resampling scheme of the particle filter.")
@click.option("--ess-threshold", default=None, type=Fraction(),
              help="Resample when ESS < threshold·N [default: every frame].")
@click.option("--targets", type=click.IntRange(min=1), default=None,
              help="Plate: track up to K plates at once, one slot each (found by themselves, no --init); the track "
                   "CSV has a row per frame and plate with its id. Default algorithm: partitioned-lis.")
@click.option("--max-frames", type=click.IntRange(min=1), help="Stop after this many frames.")
@click.option("--no-colour", "no_colour", is_flag=True,
              help="Contour: edges only (no colour term, which is on for colour video). Plate: the plate "
                   "likelihood only (no appearance learned from the --init box).")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar and no summary.")
def run(video, model_name, layout, algo, search, particles, seed, init, init_gt, template_path, track_path, out_path,
        results_path, results_format, show_particles, resample, ess_threshold, targets, max_frames, no_colour, quiet):
    """Track the object in VIDEO (a video file, an image folder or a clip folder).

    \b
    Examples:
      vistrack run video.mp4 --init 120,80,60,60 --out annotated.mp4 --track track.csv   # box model, LIS
      vistrack run video.mp4 --init 120,80,60,60 --algo bootstrap -n 500 --results r.txt
      vistrack run ../shared/data/real/girl_otb --init-gt --out girl.mp4   # started from the ground truth
      vistrack synth contour --out clip && vistrack run clip --algo ls-n-ips -n 30 --init-gt --out a.mp4
      vistrack run video.mp4 --model contour --init 120,80,60,60 --track track.csv
      vistrack run video.mp4 --model contour --template hand.txt --out a.mp4

    The track CSV has one row per frame: frame, visible, cx, cy, w, h,
    angle_deg, scale, the model's points (contour: support points qx0..,
    qy0..; plate: vertices x0..y3; landmarks: lx0.., ly0..), then ess, ms
    (time spent on the frame) and lost_reason (empty where visible=1; else
    scale, outside, likelihood or "not found"; "decode" for a frame that
    failed to decode and "not started" before the first ground-truth box of
    --init-gt: every frame of the input has a row). run says on which frames
    it loses the object and why. Ctrl-C or SIGTERM stops it after the frame
    in hand: the track, --results and --out then hold the same frames. With ground truth beside the video, the
    summary reports the centre error (landmarks: the mean landmark error).

    \b
    Several plates (--targets K): one row per frame and reported plate,
    frame, visible, id, cx, ..., y3, ess, ms, lost_reason (a frame without
    any: one row with visible=0, id=-1); each id has its colour in --out;
    the summary gives MOTA and IDF1 against the clip's objects.csv.
      vistrack synth plate --overlap --cars 6 --out road && vistrack run road --targets 3 --out a.mp4

    \b
    Landmarks (seed 000): vistrack synth landmarks --out lm && vistrack run lm --algo pf-eis-mt --out lm.mp4
    """
    _check_output_paths(video, track_path, out_path, results_path, results_format, (template_path, init_gt or None))
    if init is not None and init_gt is not None:
        raise click.UsageError("give either --init or --init-gt, not both")
    if targets is not None and results_path:
        raise click.UsageError("--results writes one box per frame: not with --targets (use --track)")
    clip, name, algo, model = _setup(video, model_name, algo, search, particles, init, init_gt, quiet,
                                     layout=layout, no_colour=no_colour, template_path=template_path, targets=targets)
    frames, lead = _frames(clip.source, max_frames), ()
    if isinstance(model, PlateSearch):  # real footage without a box: find the plate first
        model, frames, lead = _find_plate(model, frames, video, quiet)
    try:
        filt = make_filter(algo, model, resample=resample, ess_threshold=ess_threshold)
    except ValueError as e:
        raise click.ClickException(str(e)) from None
    outputs = {"track_path": track_path, "out_path": out_path, "results_path": results_path,
               "results_format": results_format, "sequence": sequence_name(video)}
    start = _start(clip, init, init_gt, max_frames)
    done = _track(clip, frames, model, filt, particles, seed, max_frames, show_particles, quiet,
                  f"{algo} N={particles}", outputs, lead, start=start)
    _report(video, clip, done, name, model, particles, quiet, outputs)


def _check_output_paths(video, track_path, out_path, results_path, results_format, inputs):
    """One error line for an output ``run`` cannot write, or one that is an input or another output."""
    check_writable(track_path, "track file")
    check_writable(out_path, "annotated video")
    if results_format == "otb":
        check_writable(results_path, "results file")
    elif results_path is not None and os.path.exists(results_path) and not os.path.isdir(results_path):
        raise click.ClickException(f"--results {results_path}: the {results_format} layout is a folder "
                                   "(SEQ/SEQ_001.txt inside it), not a file")
    check_outputs({"--track": track_path, "--out": out_path, "--results": results_path}, video, inputs=inputs)


def _find_plate(search, frames, video, quiet):
    """``(model, frames, lead)``: the plate model built where :class:`PlateSearch` finds a plate in the
    first frames, the frames from that one on, and the frames searched before it; one error line with
    the ``--init`` hint where it finds none."""
    if not quiet:  # which model and why, on one line (the error below is the one line with -q)
        click.echo("no --init and no model in meta.json: looking for a license plate (the plate model) in the "
                   "first 30 frames; to track any other object give --init x,y,w,h", err=True)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", VideoDecodeWarning)
            model, found, lead = search.start(frames)
    except VideoError as e:
        raise click.ClickException(str(e)) from None
    if model is None:
        raise click.ClickException(f"no license plate found in the first {len(lead)} frames of {video}; give its "
                                   f"box: vistrack run {video} --init x,y,w,h")
    if not quiet:
        b = found[2].box
        click.echo(f"plate found in frame {found[0]} at {b[0]:.0f},{b[1]:.0f},{b[2]:.0f},{b[3]:.0f} "
                   f"({found[2].layout} layout)", err=True)
    return model, itertools.chain([found[:2]], frames), lead


def _setup(video, model_name, algo, search, particles, init, init_gt, quiet, *, layout, no_colour, template_path,
           targets=None):
    """``(clip, model name, algorithm, model)`` of a run, checked; one error line for bad input."""
    try:
        clip = load_clip(video)
        if init is not None:
            x, y, w, h = init
            fw, fh = clip.source.size
            if x >= fw or y >= fh or x + w <= 0 or y + h <= 0:
                raise click.UsageError(f"--init box {x:g},{y:g},{w:g},{h:g} lies outside the {fw}x{fh} frame")
        name = model_name or clip.model_name or (DEFAULT_MODEL if init is not None or init_gt is not None else "plate")
        if model_name is None and name not in MODELS:
            raise click.ClickException(f"{video}: meta.json names model {name!r}, which this version cannot track")
        spec = get_model_spec(name)
        algo = algo or ((spec.multi_algos or spec.algos)[0] if targets is not None else spec.default_algo)
        flags = {"--targets": targets, "--template": template_path and read_support_points(template_path),
                 "--layout": None if layout == "auto" else layout, "--no-colour": no_colour or None, "--search": search}
        try:
            extra = model_params(name, flags, algo)
            check_algo(name, algo, targets is not None, who=f"--algo {algo}")
        except OptionError as e:
            raise click.UsageError(str(e)) from None
        check_particle_memory(particles, spec.bytes_per_particle, algo)
        model = build_model(name, clip, init=init, init_gt=init_gt, **extra)
        if search == "nn":  # train (once per template) or load before the progress bar starts
            network_for(model, notify=None if quiet else lambda m: click.echo(m, err=True))
    except (VideoError, ValueError) as e:
        raise click.ClickException(str(e)) from None
    return clip, name, algo, model


def _frames(src, max_frames):
    """The ``(index, frame)`` pairs of ``src`` (decoded ahead), up to ``max_frames``."""
    for i, f in prefetch(src):
        if max_frames is not None and i >= max_frames:
            return
        yield i, f


def _start(clip, init, init_gt, max_frames):
    """The start frame (:func:`~vistrack.models.builders.start_frame`), said on stderr when it is not 0."""
    try:
        start = start_frame(clip, init, init_gt)
    except (VideoError, ValueError) as e:
        raise click.ClickException(str(e)) from None
    if start and max_frames is not None and start >= max_frames:
        raise click.ClickException(f"--init-gt: the ground truth's first box is at frame {start}, past --max-frames "
                                   f"{max_frames}")
    if start:
        click.echo(f"note: the ground truth has no box before frame {start}: tracking starts there (frames 0-"
                   f"{start - 1} get rows with visible=0, lost_reason \"not started\"; scores count from frame "
                   f"{start})", err=True)
    return start


def _track(clip, frames, model, filt, particles, seed, max_frames, show_particles, quiet, label, outputs, lead=(),
           start=0):
    """:func:`~vistrack.track.run.track_video` over ``frames`` from ``start`` with a progress bar (``lead``:
    the frames searched before them); stops cleanly on SIGINT/SIGTERM after the frame in hand (the
    outputs so far kept, holding the same frames)."""
    src = clip.source
    total = src.frame_count if max_frames is None else min(max_frames, src.frame_count or max_frames)
    # an image folder's frame count is exact: frames after the last decodable one get rows too
    exact = total if src.exact_count else None
    frames = ((i, f) for i, f in frames if i >= start)
    bar = tqdm(total=total, unit="frame", disable=quiet, dynamic_ncols=True, desc=label, initial=len(lead))

    def progress(ess):
        bar.update(1)
        bar.set_postfix(ess=f"{ess:.1f}", refresh=False)

    try:  # skipped frames: one line below, not the decoder's warning too
        with stop_on_signals(), warnings.catch_warnings():
            warnings.simplefilter("ignore", VideoDecodeWarning)
            return track_video(frames, model, filt, particles, np.random.default_rng(seed),
                               video_info=(src.fps, src.size), show_particles=show_particles, label=label,
                               progress=progress, notify=None if quiet else lost_notice(), frame_count=exact,
                               start=start, lead=lead, **outputs)
    except (VideoError, OSError, OutputBusy) as e:
        raise click.ClickException(str(e)) from None
    finally:
        bar.close()


def _report(video, clip, done, name, model, particles, quiet, outputs):
    """Print what happened (interrupts, skipped frames, the summary, the files written); exit 130/143
    after an interrupt."""
    track_path, out_path, results_path = outputs["track_path"], outputs["out_path"], outputs["results_path"]
    if results_path and outputs["results_format"] != "otb":
        results_path = result_paths(results_path, outputs["results_format"], outputs["sequence"])[0]
    src = clip.source
    if not done.rows:
        if done.stopped:
            raise click.exceptions.Exit(done.exit_code)
        raise click.ClickException(f"{video}: no frame could be decoded")
    if done.stopped:
        click.echo(f"{'Interrupted' if done.stopped == 'interrupt' else 'Terminated'} after {len(done.rows)} frames"
                   + (f"; track so far: {track_path}" if track_path else "")
                   + (f"; annotated video so far: {out_path}" if out_path else ""), err=True)
    if src.skipped:
        click.echo(f"{len(src.skipped)} frame(s) failed to decode: "
                   + ", ".join(map(str, src.skipped[:10])) + (", ..." if len(src.skipped) > 10 else "")
                   + " (their rows have visible=0, lost_reason \"decode\"; results 0,0,0,0)", err=True)
    if src.ended_at is not None and not done.stopped:
        click.echo(f"warning: {video} ended early: decoding stopped at frame {src.ended_at} of the "
                   f"{src.frame_count} its header announces (frames {src.ended_at}-{src.frame_count - 1} have no row)",
                   err=True)
    if not quiet:
        for line in summary_lines(done, particles, model_name=name, model=model, truth=clip.truth,
                                  frame_width=src.size[0], objects=clip.objects):
            click.echo(line)
        if track_path:
            click.echo(f"track: {track_path}")
        if out_path:
            click.echo(f"annotated video: {out_path}" + (f" ({done.video_note})" if done.video_note else " (H.264)"))
        if results_path:
            click.echo(f"results (x,y,w,h): {results_path}")
        if not (track_path or out_path or results_path):
            click.echo("nothing written (give --track, --results or --out to keep the track)")
    if done.stopped:
        raise click.exceptions.Exit(done.exit_code)
