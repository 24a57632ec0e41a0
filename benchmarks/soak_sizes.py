"""The soak's size scenarios (:mod:`soak`): a size a user gives (runs, clips, frames, targets, steps, cars,
landmarks, blobs, workers) too large for the machine. What they may break: memory or disk, a process
killed with no word, a refusal after the work instead of before it."""

from __future__ import annotations

import soak_harness as S


def scenarios():
    """The size scenarios."""
    return _sizes()


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
