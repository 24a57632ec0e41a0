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
    return _written() + _two_names() + _interrupted() + _full_disk() + _links_and_inputs()


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
    # the second clip passes the size check (the least a clip takes) and fills the disk while it is written
    clip = [["synth", "contour", "--out", "{T}/c", "--frames", "2", "--size", "96x72", "-q"],
            ["synth", "contour", "--out", "{T}/c", "--frames", "60", "--size", "320x240", "-q"]]
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


def _links_and_inputs():
    """Issue 55's outputs: links written through, descriptors and pipes in place, every output locked, the
    command's inputs (a template, a clip's files, the source of a copy) never written over, SIGHUP."""
    v = "{fx}/v.avi"
    tpl = ["train-search", "--template", "{w}/tpl.txt", "--samples", "100", "--size", "160x120"]
    rep = ["reproduce", "contour", "--algos", "lis:10", "--runs", "1", "--in-process", "--out", "{w}/C", "-q"]
    slow = ["run", v, "--init", INIT, "-n", "3000", "--algo", "bootstrap", "--track", "{w}/t.csv", "--results",
            "{w}/r.txt", "--out", "{w}/a.mp4", "-q"]
    return [
        Scenario("run --track through a link to /proc/self/fd/1 with stdout a file (what /dev/stdout is)",
                 R(v, "--track", "{w}/stdout", init=True), "ok", driver=_stdout_to_file, check=_descriptor_kept),
        Scenario("run --track through a link to a FIFO", R(v, "--track", "{w}/fifo.csv"), "ok",
                 prepare=_fifo_link, driver=_reading_fifo, check=_fifo_kept),
        Scenario("run --results through a link to a file", R(v, "--results", "{w}/r.txt"), "ok",
                 prepare=lambda w: (w / "r.txt").symlink_to(w / "real.txt"), check=_link_kept("r.txt", "real.txt")),
        Scenario("train-search --out its own template", [*tpl, "--out", "{w}/tpl.txt"], mention="overwrite",
                 prepare=_template, check=_unchanged("tpl.txt", TEMPLATE)),
        Scenario("train-search --out on a full disk", [*tpl, "--out", "{w}/full.npz"], mention="network cache",
                 prepare=lambda w: (_template(w), link("full.npz")(w)), check=_no_claim("trained in")),
        Scenario("reproduce contour --json into a clip's ground truth",
                 [*rep, "--clips", "{w}/suite", "--json", "{w}/suite/c1/groundtruth.csv"], mention="overwrite",
                 prepare=copy("suite"), check=_clip_gt_unchanged),
        Scenario("reproduce contour --clips a folder of other files", [*rep, "--clips", "{w}/D", "--make", "2",
                                                                      "--frames", "3", "--size", "96x72"],
                 mention="notes.txt", prepare=_other_files, check=_holds_only("D", ["notes.txt"])),
        Scenario("synth perturb --out its own source clip", ["synth", "perturb", "{w}/c", "--out", "{w}/c", "-q"],
                 mention="reads", prepare=_synth_clip),
        Scenario("two runs, one --out video at once",
                 sub(R("{fx}/otb", "--init-gt", "--out", "{w}/a.mp4", init=False), "--track", "{w}/b.csv"),
                 mention="another vistrack", check=lost_if_flagged,
                 driver=two_runs(["run", "{fx}/long.avi", "--init", INIT, "-n", "20000", "--algo", "bootstrap",
                                  "--track", "{w}/t.csv", "--out", "{w}/a.mp4", "-q"])),
        Scenario("two runs, one --results at once",
                 sub(R("{fx}/otb", "--init-gt", "--results", "{w}/r.txt", init=False), "--track", "{w}/b.csv"),
                 mention="another vistrack", check=lost_if_flagged,
                 driver=two_runs(["run", "{fx}/long.avi", "--init", INIT, "-n", "20000", "--algo", "bootstrap",
                                  "--track", "{w}/t.csv", "--results", "{w}/r.txt", "-q"])),
        Scenario("run SIGHUP: track, video, results", slow, "ok", codes=(143,), check=same_frames,
                 driver=signals([signal.SIGHUP], track_part_rows(4))),
    ]


TEMPLATE = "100 100\n140 100\n140 140\n100 140\n120 90\n"


def _template(w):
    (w / "tpl.txt").write_text(TEMPLATE)


def _unchanged(name, text):
    def check(w, res):
        return None if (w / name).read_text() == text else ("data loss", f"{name} was overwritten")

    return check


def _no_claim(words):
    def check(w, res):
        return ("silent wrong", f"says {words!r} of a file it could not write") if words in res.out else None

    return check


def _clip_gt_unchanged(w, res):
    gt = "suite/c1/groundtruth.csv"
    return None if (w / gt).read_bytes() == (S.FX / gt).read_bytes() else ("data loss", f"{gt} was overwritten")


def _other_files(w):
    (w / "D").mkdir()
    (w / "D" / "notes.txt").write_text("mine")


def _holds_only(folder, names):
    def check(w, res):
        got = sorted(p.name for p in (w / folder).iterdir())
        return None if got == sorted(names) else ("silent wrong", f"{folder} now holds {got}")

    return check


def _synth_clip(w):
    r = vistrack(["synth", "contour", "--out", str(w / "c"), "--frames", "3", "--size", "96x72", "-q"], w, 300)
    assert r.code == 0, r.err


def _link_kept(name, target):
    def check(w, res):
        if not (w / name).is_symlink():
            return "data loss", f"the link {name} was replaced by a file"
        if res.code == 0 and not (w / target).is_file():
            return "silent wrong", f"nothing was written to {target} through the link"
        return None

    return check


def _stdout_to_file(w, argv, timeout):
    """A driver: stdout redirected to ``w/out.txt`` (as a shell's ``>``), ``w/stdout`` a link to
    ``/proc/self/fd/1`` (what the system's ``/dev/stdout`` is)."""
    import subprocess
    import sys
    import time

    (w / "stdout").symlink_to("/proc/self/fd/1")
    t0 = time.time()
    with open(w / "out.txt", "w") as out:
        p = subprocess.run([sys.executable, "-m", "vistrack.cli", *argv], cwd=w, stdout=out, stderr=subprocess.PIPE,
                           text=True, timeout=timeout)
    return S.Result(p.returncode, "", p.stderr, time.time() - t0)


def _descriptor_kept(w, res):
    if not (w / "stdout").is_symlink():
        return "data loss", "the link to /proc/self/fd/1 was replaced by a file"
    text = (w / "out.txt").read_text()
    return None if text.startswith("frame,visible,") else ("silent wrong", f"stdout holds {text[:40]!r}")


def _fifo_link(w):
    os.mkfifo(w / "fifo")
    (w / "fifo.csv").symlink_to(w / "fifo")


def _reading_fifo(w, argv, timeout):
    """A driver: the command runs while a thread reads ``w/fifo`` into ``w/read.txt``."""
    import threading

    def read():
        with open(w / "fifo") as f, open(w / "read.txt", "w") as out:
            out.write(f.read())

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    res = vistrack(argv, w, timeout)
    reader.join(timeout)
    return res


def _fifo_kept(w, res):
    if not (w / "fifo.csv").is_symlink() or (w / "fifo").is_file():
        return "data loss", "the link or the FIFO was replaced by a file"
    text = (w / "read.txt").read_text() if (w / "read.txt").is_file() else ""
    return None if text.startswith("frame,visible,") else ("silent wrong", f"the FIFO's reader got {text[:40]!r}")
