"""The soak's size scenarios (:mod:`soak`): a size a user gives (runs, clips, frames, targets, steps, cars,
landmarks, blobs, workers) too large for the machine. What they may break: memory or disk, a process
killed with no word, a refusal after the work instead of before it."""

from __future__ import annotations

import soak_harness as S


def scenarios():
    """The size scenarios."""
    return _sizes() + _synth_sizes()


def _sizes():
    def made_nothing(*names):
        def check(w, res):
            made = [n for n in names if (w / n).exists()]
            return ("silent wrong", f"{made[0]} was made before the refusal") if made else None

        return check

    fast = S.fast(30)
    return [
        S.Scenario("eval --runs 100000000", S.sub(S.EV("{fx}/suite"), "--runs", "100000000"), mention="runs",
                   check=S.all_of(fast, made_nothing("R"))),
        S.Scenario("eval --particles 10,20,30,40 --runs 1000000 (the grid, not one size)",
                   S.sub(S.sub(S.EV("{fx}/suite"), "--runs", "1000000"), "--particles", "10,20,30,40"), mention="grid",
                   check=fast),
        S.Scenario("synth-suite --clips 1000000000000", ["synth-suite", "--kind", "contour", "--clips",
                                                               "1000000000000", "--frames", "1", "--size", "64x48",
                                                               "--out", "{w}/s"],
                   mention="clips", check=S.all_of(fast, made_nothing("s"))),
        S.Scenario("synth-suite --clips 3 (lazy names, a suite as before)",
                   ["synth-suite", "--kind", "contour", "--clips", "3", "--frames", "2", "--size", "96x72", "--seed",
                    "99", "--out", "{w}/s", "-q"], "ok", check=S.suite_holds(["contour-99", "contour-100",
                                                                             "contour-101"])),
        S.Scenario("run --targets 100000", S.R("{fx}/plate", "--targets", "100000", init=False),
                   mention="targets", check=fast),
        S.Scenario("run --targets 1000 on 160x120 frames", S.R("{fx}/plate", "--targets", "1000", init=False),
                   mention="plates", check=fast),
        S.Scenario("reproduce bearings --steps 1000000000", S.sub(S.BE, "--steps", "1000000000"),
                   mention="steps", check=fast),
        S.Scenario("reproduce bearings --runs 1000000000", S.sub(S.BE, "--runs", "1000000000"),
                   mention="runs", check=fast),
        S.Scenario("reproduce landmarks --steps 1000000000",
                   ["reproduce", "landmarks", "--steps", "1000000000", "--runs", "2", "--in-process", "--out",
                    "{w}/L", "-q"], mention="steps", check=fast),
        S.Scenario("reproduce contour --runs 100000000 (before making clips)",
                   ["reproduce", "contour", "--runs", "100000000", "--clips", "{w}/made", "--make", "2", "--frames",
                    "3", "--size", "96x72", "--in-process", "--out", "{w}/C", "-q"], mention="grid",
                   check=S.all_of(fast, made_nothing("made", "C"))),
    ]


def _synth_sizes():
    """Issue 55's sizes: synth's frames, cars, clutter blobs and landmarks, synth-suite's frames, demo's runs,
    reproduce's ships, eval's workers and run's targets, each checked before anything is made."""
    fast = S.fast(30)
    out = "{w}/c"

    def made_nothing(w, res):
        made = sorted(p.name for p in w.iterdir())
        return ("silent wrong", f"{made} made before the refusal") if made else None

    def capped(w, res):
        return None if "capped at" in res.err else ("silent wrong", "no line saying the workers were capped")

    big = "1000000000000"
    return [
        *[S.Scenario(f"synth {k} --frames 10^12", ["synth", k, "--frames", big, *size, "--out", out], mention="frames",
                     check=S.all_of(fast, made_nothing))
          for k, size in (("contour", ["--size", "64x48"]), ("plate", []), ("landmarks", []))],
        S.Scenario("synth plate --cars 10^9", ["synth", "plate", "--cars", "1000000000", "--frames", "3", "--out", out],
                   mention="cars", check=S.all_of(fast, made_nothing)),
        S.Scenario("synth landmarks --clutter-blobs 10^9", ["synth", "landmarks", "--clutter-blobs", "1000000000",
                                                           "--frames", "3", "--out", out],
                   mention="clutter-blobs", check=S.all_of(fast, made_nothing)),
        S.Scenario("synth landmarks --k 100000", ["synth", "landmarks", "--k", "100000", "--frames", "3", "--out", out],
                   mention="--k", check=S.all_of(fast, made_nothing)),
        S.Scenario("synth-suite --frames 10^12 (advice is not 'at most 0 clips')",
                   ["synth-suite", "--kind", "contour", "--clips", "2", "--frames", big, "--out", "{w}/s"],
                   mention="--frames", check=S.all_of(fast, made_nothing)),
        S.Scenario("demo --runs 10^9 (checked before the clip is made)", ["demo", "--runs", "1000000000", "--out",
                                                                         "{w}/d"],
                   mention="runs", check=S.all_of(fast, made_nothing)),
        S.Scenario("reproduce bearings --ships 10^6", S.sub(S.BE, "--ships", "1000000"), mention="ships",
                   check=fast),
        S.Scenario("eval --workers 1000 (capped, with a line)", S.sub(S.EV("{fx}/suite"), "--workers", "1000"), "ok",
                   check=capped),
        S.Scenario("run --targets 100000 (what a frame holds, before memory)",
                   S.R("{fx}/plate", "--targets", "100000", init=False), mention="holds at most", check=fast),
    ]
