"""Fault-injection soak: ~280 scenarios of bad input, broken files and interruptions, each run as a
user would (``python -m vistrack.cli ...`` in a fresh folder), its outcome classified automatically.

Not part of CI (about 30 minutes on 2 cores). The fast cases that guard each fix live in
``tests/*/test_faults_*.py``; this sweep looks for new ones. The scenarios are filed by what a fault
breaks: ``soak_outputs`` (outputs that are inputs, links or devices, two writers, a full disk on a small
tmpfs where one can be mounted, else ``skipped``, interrupts), ``soak_sizes``, ``soak_trax`` (and Ctrl-C
at start-up), ``soak_api``, ``soak_data`` (videos, ground truth, URLs and their cache), ``soak_options``
and ``soak_tasks`` (eval's grid and task files); ``soak_harness`` runs and judges them. A case whose fix
is another issue's is counted apart (``..., awaits issue 46``), not as a failure.

    python benchmarks/soak.py [--only SUBSTRING] [--keep DIR] [--timeout 180]

Outcomes, in this order of precedence:

* ``hang``: no exit within the timeout;
* ``traceback``: a Python traceback on stdout/stderr, or the process died by a signal;
* ``data loss``: a scenario check found a file lost or damaged that should have survived
  (the old clip of an interrupted synth, the partial track of an interrupted run, task files);
* ``silent wrong``: exit 0 on input that must be refused, or an output that does not parse,
  holds NaN/inf (no output column is documented to hold them), or fails the scenario's check
  (a resume that mixes seeds, ground truth of another length without a warning, ...);
* ``misleading error``: a non-zero exit without exactly one ``Error:`` line, an error that does
  not name what is wrong (the scenario's keyword), or valid input refused;
* ``clear error``: a non-zero exit with one ``Error:`` line and no traceback;
* ``correct``: exit 0 (or 130 / 143 where the scenario interrupts) and outputs that parse;
* ``skipped``: the scenario cannot run here (no tmpfs can be mounted, no vot-trax), with the reason.

Prints a markdown table (scenario, command, exit code, outcome, note) and the totals.
"""

from __future__ import annotations

import argparse
import re
import shutil
import tempfile
import time
from pathlib import Path

import soak_api
import soak_data
import soak_harness
import soak_options
import soak_outputs
import soak_sizes
import soak_tasks
import soak_trax
from soak_harness import BAD, OUTCOMES, Result, build_fixtures, run_scenario

#: the scenario modules, each filed by what its faults break
MODULES = (soak_data, soak_options, soak_outputs, soak_tasks, soak_sizes, soak_api, soak_trax)


def scenarios():
    """Every scenario of :data:`MODULES`."""
    return [sc for m in MODULES for sc in m.scenarios()]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", default="", help="Run the scenarios whose name contains this.")
    ap.add_argument("--keep", help="Work in this folder and keep it (default: a temporary folder, removed).")
    ap.add_argument("--timeout", type=float, default=180, help="Seconds before a scenario counts as a hang.")
    args = ap.parse_args()
    base = Path(args.keep or tempfile.mkdtemp(prefix="vistrack-soak-")).resolve()
    base.mkdir(parents=True, exist_ok=True)
    FX = soak_harness.FX = base / "fixtures"
    if not FX.is_dir():
        build_fixtures(FX)
    chosen = [s for s in scenarios() if args.only.lower() in s.name.lower()]
    totals = dict.fromkeys(OUTCOMES, 0)
    print("| # | scenario | command | exit | outcome | note |\n|---|---|---|---|---|---|", flush=True)
    t0 = time.time()
    try:
        for k, sc in enumerate(chosen, 1):
            work = base / "work"
            shutil.rmtree(work / re.sub(r"[^A-Za-z0-9_.-]", "_", sc.name), ignore_errors=True)
            work.mkdir(exist_ok=True)
            try:
                argv, res, outcome, note = run_scenario(sc, work, FX, args.timeout)
            except Exception as e:  # noqa: BLE001  (a bug of this script: say so, go on)
                argv, res, outcome, note = sc.argv, Result(None, "", "", 0.0), "harness error", repr(e)[:100]
            if sc.awaits and outcome in BAD + ("misleading error",):
                outcome = f"{outcome}, awaits {sc.awaits}"
            totals[outcome] = totals.get(outcome, 0) + 1
            wdir = str(work / re.sub(r"[^A-Za-z0-9_.-]", "_", sc.name))
            cmd = " ".join(a.replace(wdir, "W").replace(str(FX), "FX") for a in argv)
            cell = (note or "").replace("|", "/").replace("\n", " ")
            print(f"| {k} | {sc.name} | `{cmd}` | {res.code} | {outcome} | {cell} |", flush=True)
    finally:
        if not args.keep:
            shutil.rmtree(base, ignore_errors=True)
    print(f"\n{len(chosen)} scenarios in {time.time() - t0:.0f} s: "
          + ", ".join(f"{n} {o}" for o, n in totals.items() if n or o in OUTCOMES))
    bad = BAD
    print("failures: " + ", ".join(f"{totals.get(o, 0)} {o}" for o in bad)
          + f" ({sum(totals.get(o, 0) for o in bad)} of {len(chosen)} scenarios)")


if __name__ == "__main__":
    main()
