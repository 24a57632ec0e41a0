"""``vistrack synth KIND --out DIR``: synthetic clips with exact ground truth."""

from __future__ import annotations

import click
from tqdm import tqdm

from vistrack.data_synth.contour_clip import CLUTTER, SHAPES, make_contour_clip
from vistrack.data_synth.landmark_clip import make_landmark_clip
from vistrack.data_synth.longterm_clip import make_longterm_clip
from vistrack.data_synth.perturb import LIGHTS, Perturbation, perturb_clip, read_clip
from vistrack.data_synth.plate_clip import make_plate_clip
from vistrack.data_synth.plate_composite import composite_plate_clip
from vistrack.data_synth.scene import out_folder
from vistrack.data_synth.suite import SUITES, check_suite, make_suite
from vistrack.registry import LAYOUTS

from .options import SEED, FloatRange, Fraction, Output, Ratio, Size, check_outputs, option, size_text

__all__ = ["synth"]


def _out_dir(out, clip=True):
    """``--out`` ready (:func:`vistrack.data_synth.scene.out_folder`), with a note on stderr where a clip
    there is overwritten."""
    try:
        p, there = out_folder(out, clip)
    except ValueError as e:
        raise click.ClickException(str(e)) from None
    if there:
        click.echo(f"note: overwriting the clip in {p}", err=True)
    return p


def _make(make, out, **kw):
    """``make(out, **kw)`` with its refusals (``ValueError``, an unwritable folder) as one error line."""
    try:
        return make(out, **kw)
    except ValueError as e:
        raise click.ClickException(str(e)) from None
    except OSError as e:
        raise click.ClickException(f"cannot write the clip {out}: {e.strerror or e}") from None


def _clip_options(make):
    """``--out``, ``--frames``, ``--size`` and ``--seed`` of every ``synth`` command that renders a clip, their
    defaults those of the clip's maker ``make``."""
    opts = [click.option("--out", required=True, type=Output(file_okay=False), help="Clip folder to write."),
            option("--frames", source=make, type=click.IntRange(min=1), help="Number of frames to generate."),
            option("--size", source=make, shown=size_text, type=Size(), help="Frame size WIDTHxHEIGHT in pixels."),
            option("--seed", source=make, type=SEED,
                   help="Random seed: the same seed gives the same output, bit for bit.")]

    def decorate(f):
        for opt in reversed(opts):
            f = opt(f)
        return f

    return decorate


@click.group()
def synth():
    """Generate synthetic clips (video.mp4, groundtruth.csv, meta.json)."""


@synth.command()
@_clip_options(make_contour_clip)
@option("--clutter", source=make_contour_clip, type=click.Choice(list(CLUTTER)),
        help="Background edge density and sensor noise.")
@option("--distractor/--no-distractor", source=make_contour_clip,
        help="An identical object lying still in the scene (thesis §3.2.5).")
@option("--shape", source=make_contour_clip, type=click.Choice(list(SHAPES)),
        help="Outline of the object: an open hand or a head-and-shoulders.")
@click.option("--color", "color", is_flag=True,
              help="Give the object (and the distractor) a distinctive saturated colour: the clips of the "
                   "colour-blob proposal (thesis §3.2.5, `vistrack reproduce hs-sir`).")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar; print only errors.")
def contour(out, frames, size, seed, clutter, distractor, shape, color, quiet):
    """A textured object with a B-spline outline moving (AR(2) with sudden jumps, scale,
    rotation) over edge clutter, with lighting change, blur and noise."""
    out = _out_dir(out)
    with tqdm(total=frames, unit="frame", disable=quiet, desc="synth contour") as bar:
        _make(make_contour_clip, out, frames=frames, size=size, seed=seed, clutter=clutter, distractor=distractor,
                          shape=shape, color=color, progress=bar.update)
    if not quiet:
        click.echo(f"wrote {out}/video.mp4, groundtruth.csv, meta.json ({frames} frames, {size[0]}x{size[1]})")


@synth.command()
@_clip_options(make_plate_clip)
@option("--cars", source=make_plate_clip, type=click.IntRange(min=1), help="Cars driving through.")
@option("--layout", source=make_plate_clip, type=click.Choice(list(LAYOUTS)),
        help="Plate layout: Japanese (Fig. 1.5) or single-row (European/Indian style).")
@click.option("--overlap", is_flag=True,
              help="Cars close together in three lanes: up to three plates in view at once (track them with "
                   "run --targets K).")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar; print only errors.")
def plate(out, frames, size, seed, cars, layout, overlap, quiet):
    """A road scene in which cars carrying plates drive through (thesis §1.3.2, §4.5.3).

    groundtruth.csv has a row per frame (the largest plate in view), objects.csv a row per
    frame and plate in view with the plate's id (the car's number)."""
    if size[0] < 160 or size[1] < 120:
        raise click.ClickException(f"frame size {size[0]}x{size[1]} is too small for plates (at least 160x120)")
    out = _out_dir(out)
    with tqdm(total=frames, unit="frame", disable=quiet, desc="synth plate") as bar:
        _make(make_plate_clip, out, frames=frames, size=size, seed=seed, cars=cars, layout=layout, overlap=overlap,
                        progress=bar.update)
    if not quiet:
        click.echo(f"wrote {out}/video.mp4, groundtruth.csv, objects.csv, meta.json ({frames} frames, "
                   f"{size[0]}x{size[1]})")


@synth.command()
@_clip_options(make_landmark_clip)
@option("--k", "k", source=make_landmark_clip, type=click.IntRange(min=3), help="Number of landmarks K.")
@option("--clutter-blobs", source=make_landmark_clip, type=click.IntRange(min=0),
        help="Drifting blobs identical to the landmarks.")
@option("--occlusion", source=make_landmark_clip, type=Fraction(),
        help="Per-frame probability that a landmark disappears for 3-10 frames.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar; print only errors.")
def landmarks(out, k, frames, size, seed, clutter_blobs, occlusion, quiet):
    """K landmark blobs moving and deforming by the shape model of seed 000 (§3.1): scale and
    rotation about the image centre, shape change in the tangent space; clutter blobs, occlusions,
    lighting change and noise. Ground truth: every landmark's position per frame (lx0.., ly0..)."""
    if size[0] < 128 or size[1] < 96:
        raise click.ClickException(f"frame size {size[0]}x{size[1]} is too small for landmarks (at least 128x96)")
    out = _out_dir(out)
    with tqdm(total=frames, unit="frame", disable=quiet, desc="synth landmarks") as bar:
        _make(make_landmark_clip, out, k=k, frames=frames, size=size, seed=seed, clutter_blobs=clutter_blobs,
                           occlusion=occlusion, progress=bar.update)
    if not quiet:
        click.echo(f"wrote {out}/video.mp4, groundtruth.csv, meta.json ({frames} frames, {size[0]}x{size[1]}, K={k})")


@synth.command()
@click.option("--out", required=True, type=Output(file_okay=False), help="Clip folder to write.")
@option("--size", source=make_longterm_clip, shown=size_text, type=Size(), help="Frame size WIDTHxHEIGHT in pixels.")
@option("--seed", source=make_longterm_clip, type=SEED,
        help="Random seed: the same seed gives the same output, bit for bit.")
@option("--gap", source=make_longterm_clip, type=FloatRange(0.2, 60),
        help="Seconds of each absence (out of the frame, then behind the pillar).")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar; print only errors.")
def longterm(out, size, seed, gap, quiet):
    """A long-term clip: an object that leaves the frame, comes back through another edge, hides behind a
    pillar and comes out on its other side (GAP seconds away each time), for a tracker that must say when
    the object is gone. groundtruth.csv marks the frames without any of it in view visible=0 (0,0,0,0);
    meta.json lists them. Its length follows from the script (about 12 s at 30 frames/s).

    \b
    Example:
      vistrack synth longterm --out lt --seed 1 && vistrack run lt --init-gt --track t.csv
    """
    out = _out_dir(out)
    with tqdm(unit="frame", disable=quiet, desc="synth longterm") as bar:
        meta = _make(make_longterm_clip, out, size=size, seed=seed, gap=gap, progress=bar.update,
                     on_length=lambda n: bar.reset(total=n))
    if not quiet:
        click.echo(f"wrote {out}/video.mp4, groundtruth.csv, meta.json ({meta['frames']} frames, {size[0]}x{size[1]}, "
                   f"absent in frames " + ", ".join(f"{a}-{b}" for a, b in meta["absent"]) + ")")


@synth.command()
@click.argument("clip", type=click.Path(exists=True))
@click.option("--out", required=True, type=Output(file_okay=False), help="Folder of the stressed copy.")
@click.option("--light", type=click.Choice(LIGHTS), default=None,
              help="ramp: the gain goes linearly from the first --gain factor to the second (dark into light); "
                   "flicker: a random gain per frame between them.")
@click.option("--gain", default=None, type=Ratio(), help="Gain range of --light [default: 0.3:1.6].")
@option("--blur", source=Perturbation, type=click.IntRange(0, 200),
        help="Motion blur: a line kernel K px long along a random direction per frame.")
@option("--shake", source=Perturbation, type=FloatRange(0, 1000),
        help="Camera shake: each frame moved by up to PX px in x and y (uniform).")
@click.option("--zoom", default=None, type=Ratio(),
              help="Zoom about the object over the clip: its size goes from A to B times its own (1:0.6 shrinks it).")
@option("--drop", source=Perturbation, type=click.IntRange(min=0),
        help="Drop every K-th frame (and its ground-truth row); 0: none.")
@option("--seed", source=Perturbation, type=SEED, help="Seed of the shake, blur directions, flicker.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar; print only errors.")
def perturb(clip, out, light, gain, blur, shake, zoom, drop, seed, quiet):
    """A harder copy of a real CLIP (a folder or video with box ground truth beside it) with its
    ground truth transformed exactly: OUT/<name>.mp4, groundtruth_rect.txt (0-based x,y,w,h) and
    perturb.json. Stresses combine; geometry (zoom, shake) is applied first, then blur, then light.

    \b
    Examples:
      vistrack synth perturb ../shared/data/real/girl_otb --out girl-ramp --light ramp
      vistrack synth perturb CLIP --out C2 --blur 9 --shake 6 --zoom 1:0.6 --drop 2 --seed 1
    """
    check_outputs({"--out": out}, clip)
    try:
        p = Perturbation(light=light, gain=gain, blur=blur, shake=shake, zoom=zoom, drop=drop, seed=seed)
        video, gt = read_clip(clip)
    except ValueError as e:
        raise click.ClickException(str(e)) from None
    out = _out_dir(out)
    with tqdm(total=p.kept(len(gt)), unit="frame", disable=quiet, desc=f"synth perturb {p.name}") as bar:
        n = _make(perturb_clip, out, clip=clip, p=p, progress=bar.update)
    if not quiet:
        click.echo(f"wrote {out} ({p.name}: {n} of {len(gt)} frames, ground truth transformed)")


@synth.command("plate-on-car")
@click.argument("clip", type=click.Path(exists=True))
@click.option("--out", required=True, type=Output(file_okay=False), help="Folder of the new clip.")
@option("--layout", source=composite_plate_clip, type=click.Choice(list(LAYOUTS)),
        help="Layout of the rendered plate.")
@option("--width", source=composite_plate_clip, type=FloatRange(0.05, 1.0),
        help="Plate width as a share of the car box's width.")
@option("--upscale", source=composite_plate_clip, type=FloatRange(1.0, 8.0),
        help="Enlarge the frames by this factor first (bicubic): a small car's plate is a few px high.")
@option("--blur", source=composite_plate_clip, type=FloatRange(0, 20),
        help="Gaussian blur (px) of the plate, to match the clip's sharpness.")
@option("--noise", source=composite_plate_clip, type=FloatRange(0, 50),
        help="Sensor noise (grey levels) on the plate.")
@option("--seed", source=composite_plate_clip, type=SEED, help="Seed of the plate's characters and noise.")
@click.option("--quiet", "-q", is_flag=True, help="Print only errors.")
def plate_on_car(clip, out, layout, width, upscale, blur, noise, seed, quiet):
    """A rendered plate composited onto the car of a real CLIP (a folder or video whose box ground
    truth is the car, e.g. car4), in the clip's light, blur and noise: OUT/<name>_plate.mp4,
    groundtruth_rect.txt (the plate's exact boxes, 0-based x,y,w,h) and composite.json.

    \b
    Examples:
      vistrack synth plate-on-car ../shared/data/real/car4_otb_first100 --out car4-jp --layout jp
      vistrack synth plate-on-car ../shared/data/real/car4_otb_first100 --out car4-eu --upscale 2
    """
    check_outputs({"--out": out}, clip)
    try:
        read_clip(clip)
    except ValueError as e:
        raise click.ClickException(str(e)) from None
    out = _out_dir(out)
    n = _make(composite_plate_clip, out, clip=clip, layout=layout, seed=seed, width=width, blur=blur, noise=noise,
              upscale=upscale)
    if not quiet:
        click.echo(f"wrote {out} ({layout} plate on the car, {n} frames, exact ground truth)")


@click.command("synth-suite")
@click.option("--kind", required=True, type=click.Choice(list(SUITES)),
              help="Which synthetic clips to make: contour, plate or landmarks (as vistrack synth KIND).")
@option("--clips", "n_clips", source=make_suite, key="clips", type=click.IntRange(min=1),
        help="Number of clips in the suite.")
@option("--seed", source=make_suite, type=SEED, help="Seed of the first clip (then +1, +2, ...).")
@click.option("--frames", default=None, type=click.IntRange(min=1),
              help="Frames per clip [default: 300; 200 for landmarks].")
@click.option("--size", default=None, type=Size(),
              help="Frame size [default: 320x240 contour, 640x480 plate/landmarks].")
@click.option("--out", required=True, type=Output(file_okay=False), help="Folder to hold the clip folders.")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar; print only errors.")
def synth_suite(kind, n_clips, seed, frames, size, out, quiet):
    """A suite of clips for `vistrack eval` (OUT/<kind>-<seed>/ each), with each kind's defaults
    (contour: high clutter and a distractor; plate: 3 cars, JP layout; landmarks: K = 5)."""
    frames = frames or SUITES[kind][1]
    check_suite(out, kind, n_clips, frames, size)  # before the folder is made
    out = _out_dir(out, clip=False)
    with tqdm(total=n_clips * frames, unit="frame", disable=quiet, desc=f"synth-suite {kind}") as bar:
        _make(make_suite, out, kind=kind, clips=n_clips, seed=seed, frames=frames, size=size, progress=bar.update)
    if not quiet:
        click.echo(f"wrote {n_clips} {kind} clips into {out}")
