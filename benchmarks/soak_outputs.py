"""The soak's output scenarios (:mod:`soak`): an output that is an input or another name of one, a link,
a device or a pipe, two writers of one output, a full disk (a link to ``/dev/full``; a small tmpfs), an
interrupt or a kill mid-run. What they may break: an input overwritten, an earlier output lost, a
partial output left where a whole one should be."""

from __future__ import annotations

import os
import shutil
import signal

import soak_harness as S
from soak_harness import (
    BE,
    EV,
    INIT,
    SY,
    R,
    Scenario,
    clip_intact,
    copy,
    equals_fresh,
    has_task,
    input_intact,
    interrupt,
    kill_worker,
    killed_track,
    link,
    lost_if_flagged,
    old_clip,
    partial_track,
    same_frames,
    signals,
    sub,
    suite_holds,
    track_part_rows,
    two_runs,
    vistrack,
)


def scenarios():
    """The output scenarios."""
    return _written() + _two_names() + _interrupted() + _full_disk()


def _written():
    v, suite = "{fx}/v.avi", "{fx}/suite"
    return [
        Scenario("run --out annotated.txt", R(v, "--out", "{w}/annotated.txt"), "either"),
        Scenario("run --out annotated (no extension)", R(v, "--out", "{w}/annotated"), "either"),
        Scenario("run --out on a full disk", R(v, "--out", "{w}/full.mp4"), prepare=link("full.mp4")),
        Scenario("run --track on a full disk", R(v, "--track", "{w}/full.csv"), prepare=link("full.csv")),
        Scenario("run --results on a full disk", R(v, "--results", "{w}/full.txt"), prepare=link("full.txt")),
        Scenario("run --track to /dev/null", R(v, "--track", "/dev/null"), "ok"),
        Scenario("run --track to /dev/stdout", R(v, "--track", "/dev/stdout"), "ok",
                 check=lambda w, res: (None if res.out.startswith("frame,visible,")
                                       else ("silent wrong", "no CSV on stdout"))),
        Scenario("run --track into a missing folder", R(v, "--track", "{w}/no/t.csv"), mention="no"),
        Scenario("run --track is a folder", R(v, "--track", "{w}"), mention="director"),
        Scenario("run --out under a file", R(v, "--out", "{fx}/notes.txt/a.mp4"), mention="notes.txt"),
        Scenario("run --out is the input video", R("{w}/v.avi", "--out", "{w}/v.avi"), "either", prepare=copy("v.avi"),
                 check=input_intact("v.avi")),
        Scenario("run --track is the input video", R("{w}/v.avi", "--track", "{w}/v.avi"), "either",
                 prepare=copy("v.avi"), check=input_intact("v.avi")),
        Scenario("eval --out is a file", sub(EV(suite), "--out", "{fx}/notes.txt"), mention="notes.txt"),
        Scenario("eval --out under a file", sub(EV(suite), "--out", "{fx}/notes.txt/R"), mention="notes.txt"),
        Scenario("eval --out on a full disk", EV(suite), prepare=lambda w: [(w / "R").mkdir(),
                                                                          (w / "R" / "results.json").symlink_to(
                                                                              "/dev/full")]),
        Scenario("reproduce bearings --json on a full disk", BE + ["--json", "{w}/full.json"],
                 prepare=link("full.json")),
        Scenario("reproduce bearings --json into a missing folder", BE + ["--json", "{w}/no/b.json"], mention="no"),
        Scenario("reproduce bearings --plots is a file", BE + ["--plots", "{fx}/notes.txt"], mention="notes.txt"),
        Scenario("synth contour over an existing clip", SY, "ok",
                 prepare=lambda w: shutil.copytree(S.FX / "clip", w / "c")),
        Scenario("synth --out is a file", sub(SY, "--out", "{fx}/notes.txt"), mention="notes.txt"),
        Scenario("synth --out under a file", sub(SY, "--out", "{fx}/notes.txt/c"), mention="notes.txt"),
        Scenario("synth --out under a device", sub(SY, "--out", "/dev/full/c"), mention="/dev/full"),
        Scenario("synth --out the current folder", sub(SY, "--out", "."), "either"),
    ]


def _two_names():
    P = ["synth", "perturb", "{fx}/otb", "--out", "{w}/o", "-q"]

    def hard(name, target):
        return lambda w: (shutil.copy(S.FX / "v.avi", w / "in.avi"), os.link(w / "in.avi", w / name))

    def old_suite(w):
        r = vistrack(["synth-suite", "--kind", "contour", "--clips", "3", "--frames", "2", "--size", "96x72",
                      "--out", str(w / "s"), "-q"], w, 300)
        assert r.code == 0, r.err

    def intact(name):
        def check(w, res):
            return None if (w / name).read_bytes() == (S.FX / "v.avi").read_bytes() else \
                ("data loss", f"the input {name} was overwritten")

        return check

    return [
        *[Scenario(f"run {o} a hard link of the input", ["run", "{w}/in.avi", "--init", INIT, "-n", "50", o,
                                                            "{w}/h" + ext, "-q"], prepare=hard("h" + ext, "in.avi"),
                   mention="overwrite", check=intact("in.avi")) for o, ext in
          (("--out", ".avi"), ("--track", ".avi"), ("--results", ".avi"))],
        Scenario("run --out a symbolic link of the input", ["run", "{w}/in.avi", "--init", INIT, "--out",
                                                               "{w}/s.avi", "-q"], mention="overwrite",
                 prepare=lambda w: (shutil.copy(S.FX / "v.avi", w / "in.avi"), (w / "s.avi").symlink_to(w / "in.avi")),
                 check=intact("in.avi")),
        Scenario("two runs, one --track at once", R("{fx}/otb", "--init-gt", init=False), mention="another vistrack",
                 check=lost_if_flagged, driver=two_runs(["run", "{fx}/long.avi", "--init", INIT, "-n", "20000",
                                                         "--algo", "bootstrap", "--track", "{w}/t.csv", "-q"])),
        Scenario("synth-suite over an earlier, larger suite", ["synth-suite", "--kind", "contour", "--clips", "2",
                                                                   "--frames", "2", "--size", "96x72", "--seed", "5",
                                                                   "--out", "{w}/s", "-q"], "ok", prepare=old_suite,
                 check=suite_holds(["contour-05", "contour-06"])),
        Scenario("synth --out a folder holding an OTB clip", sub(SY, "--out", "{w}/otb"), mention="not a clip",
                 prepare=copy("otb")),
        Scenario("synth perturb into its own earlier output", [*P, "--blur", "5"], "ok",
                 prepare=_perturbed_once),
    ]


def _interrupted():
    slow = R("{fx}/v.avi", "--out", "{w}/a.mp4", init=False) + ["--init", INIT, "-n", "3000"]
    grid = sub(sub(EV("{w}/suite"), "--particles", "400"), "--runs", "3")
    grid.remove("--in-process")  # worker processes, which get the Ctrl-C too
    synth_over = ["synth", "contour", "--out", "c1", "--frames", "100000", "--size", "96x72", "-q", "--seed", "2"]

    def resumed(w, res, timeout):
        r = vistrack([a.format(w=w) for a in grid + ["--resume"]], w, timeout)
        if r.code != 0:
            res.note, res.lost = f"--resume after Ctrl-C failed: {r.err[-80:]}", True
        return res

    slow_all = ["run", "{fx}/v.avi", "--init", INIT, "-n", "3000", "--algo", "bootstrap", "--track", "{w}/t.csv",
                "--results", "{w}/r.txt", "--out", "{w}/a.mp4", "-q"]
    ready = track_part_rows(4)
    return [

        Scenario("run SIGINT mid-run", slow, "ok", codes=(130,), check=partial_track,
                 driver=interrupt(signal.SIGINT, track_part_rows(4))),
        Scenario("run SIGTERM mid-run", slow, "ok", codes=(143,), check=partial_track,
                 driver=interrupt(signal.SIGTERM, track_part_rows(4))),
        Scenario("run Ctrl-C on the process group", slow, "ok", codes=(130,), check=partial_track,
                 driver=interrupt(signal.SIGINT, track_part_rows(4), group=True)),
        Scenario("run kill -9 mid-run", slow, "ok", codes=(-9,), check=killed_track,
                 driver=interrupt(signal.SIGKILL, track_part_rows(4))),
        Scenario("eval Ctrl-C on the process group, then --resume", grid, "ok", codes=(130,), prepare=copy("suite"),
                 check=lost_if_flagged, driver=interrupt(signal.SIGINT, has_task, group=True, then=resumed)),
        Scenario("eval SIGTERM mid-grid", grid, "either", codes=(143, 0), prepare=copy("suite"),
                 driver=interrupt(signal.SIGTERM, has_task)),
        Scenario("eval kill -9 of a worker mid-grid", grid, "ok", prepare=copy("suite"), driver=kill_worker,
                 check=equals_fresh(sub(sub(sub(EV("{w}/suite"), "--particles", "400"), "--runs", "3"),
                                        "--out", "{w}/F"))),
        Scenario("synth SIGINT while overwriting a clip", synth_over, "ok", codes=(130,), prepare=old_clip,
                 check=clip_intact, driver=interrupt(signal.SIGINT, lambda w: any(w.glob(".c1.partial-*/video.mp4")))),
        Scenario("synth kill -9 while overwriting a clip", synth_over, "ok", codes=(-9,), prepare=old_clip,
                 check=clip_intact, driver=interrupt(signal.SIGKILL, lambda w: any(w.glob(".c1.partial-*/video.mp4")))),
        Scenario("reproduce bearings Ctrl-C on the process group", sub(sub(BE, "--runs", "200"), "--particles", "3000"),
                 "ok", codes=(130,),
                 driver=interrupt(signal.SIGINT, lambda w: (w / "B" / "tasks").is_dir(), group=True)),
        Scenario("run SIGINT once: track, video, results", slow_all, "ok", codes=(130,), check=same_frames,
                 driver=signals([signal.SIGINT], ready)),
        Scenario("run SIGINT twice: track, video, results", slow_all, "ok", codes=(130,), check=same_frames,
                 driver=signals([signal.SIGINT, signal.SIGINT], ready)),
        Scenario("run Ctrl-C twice on the process group", slow_all, "ok", codes=(130,), check=same_frames,
                 driver=signals([signal.SIGINT, signal.SIGINT], ready, group=True)),
        Scenario("run SIGTERM: track, video, results", slow_all, "ok", codes=(143,), check=same_frames,
                 driver=signals([signal.SIGTERM], ready)),
        Scenario("run SIGTERM early: track, video, results", slow_all, "ok", codes=(143,), check=same_frames,
                 driver=signals([signal.SIGTERM], track_part_rows(2))),
        Scenario("run SIGTERM then SIGINT", slow_all, "ok", codes=(143,), check=same_frames,
                 driver=signals([signal.SIGTERM, signal.SIGINT], ready)),
    ]


def _full_disk():
    long, short = "{fx}/long.avi", "{fx}/v.avi"
    run = ["run", "--init", INIT, "-n", "20", "-q"]
    out = []
    for name, size in (("old.mp4", "48k"), ("old.avi", "256k"), ("old.mkv", "48k")):  # Motion JPEG is larger
        steps = [[*run[:1], video, *run[1:], "--out", "{T}/" + name] for video in (short, long)]
        out.append(Scenario(f"run --out over an earlier {name} on a full tmpfs", S.shown(steps),
                              mention="No space left", driver=S.tmpfs(steps, size), check=S.earlier_kept(name)))
    for name in ("a.mp4", "a.avi"):
        steps = [[*run[:1], long, *run[1:], "--out", "{T}/" + name]]
        out.append(Scenario(f"run --out {name} on a full tmpfs, no earlier file", S.shown(steps),
                              mention=f"{{T}}/{name}", driver=S.tmpfs(steps), check=S.nothing_left([])))
    track = ["--track", "{T}/t.csv", "--results", "{T}/r.txt"]
    steps = [[*run[:1], short, *run[1:], *track], [*run[:1], long, *run[1:], *track, "--out", "/dev/null"]]
    alone = [[*run[:1], long, *run[1:], "--track", "{T}/t.csv"]]
    clip = [["synth", "contour", "--out", "{T}/c", "--frames", "2", "--size", "96x72", "-q"],
            ["synth", "contour", "--out", "{T}/c", "--frames", "400", "--size", "320x240", "-q"]]
    out += [
        Scenario("run --track over an earlier track on a full tmpfs", S.shown(steps), mention="is kept",
                   driver=S.tmpfs(steps, "24k"), check=S.earlier_kept("t.csv")),
        Scenario("run --track on a full tmpfs, no earlier file (whole rows kept)", S.shown(alone),
                   mention="{T}/t.csv", driver=S.tmpfs(alone, "12k"), check=S.nothing_left(["t.csv"])),
        Scenario("synth over an earlier clip on a full tmpfs", S.shown(clip), mention="No space left",
                   driver=S.tmpfs(clip, "96k"), check=S.clip_kept),
    ]
    return out


def _perturbed_once(w):
    """``w/o``: a stressed copy of the OTB fixture, written once before the scenario writes it again."""
    r = vistrack(["synth", "perturb", str(S.FX / "otb"), "--out", str(w / "o"), "--blur", "3", "-q"], w, 300)
    assert r.code == 0, r.err
