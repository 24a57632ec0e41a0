"""Fixed-seed tracks of ``vistrack run`` for every model family, digested: behaviour unchanged?

A refactor (issue 36: model families as packages, one registry, ...) must leave every track bit for
bit as it was. This script runs ``vistrack run`` with a fixed ``--seed`` on each model family and the
bearings reproduction, drops the timing columns (``ms``, ``ms_per_run``), and prints one SHA-256
per case; ``--save FILE`` keeps them, ``--check FILE`` compares and exits 1 on any difference::

    git stash; python benchmarks/fixed_tracks.py --save /tmp/before.json; git stash pop
    python benchmarks/fixed_tracks.py --check /tmp/before.json

Cases: the box and the siam model on a rendered contour clip and (when ``../shared/data/real/girl_otb`` is
there) on a real clip; the contour model with LIS, LS-N-IPS and SIR with history sampling (colour clip);
the plate model with LIS (one plate) and partitioned LIS (``--targets 2``); the landmark model with
PF-EIS-MT; ``vistrack reproduce bearings`` (a small grid). The rendered clips are made once by
``vistrack synth`` under ``--cache``. About a minute on two cores.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import io
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT.parent / "shared" / "data" / "real"

CLIPS = {
    "contour": ["contour", "--frames", "25", "--seed", "3"],
    "contour-colour": ["contour", "--frames", "25", "--seed", "4", "--color"],
    "plate": ["plate", "--frames", "30", "--seed", "2"],
    "landmarks": ["landmarks", "--frames", "20", "--seed", "1"],
}

#: case -> (clip, run arguments)
CASES = {
    "box-lis": ("contour", ["--model", "box", "--init-gt"]),
    "box-real": (str(REAL / "girl_otb"), ["--model", "box", "--init-gt", "--max-frames", "60"]),
    "siam-lis": ("contour", ["--model", "siam", "--init-gt"]),
    "siam-real": (str(REAL / "girl_otb"), ["--model", "siam", "--init-gt", "--max-frames", "60"]),
    "contour-lis": ("contour", ["--model", "contour", "--init-gt", "--algo", "lis"]),
    "contour-ls-n-ips": ("contour", ["--model", "contour", "--init-gt", "--algo", "ls-n-ips"]),
    "contour-hs-sir": ("contour-colour", ["--model", "contour", "--init-gt", "--algo", "hs-sir"]),
    "plate-lis": ("plate", ["--model", "plate", "--algo", "lis"]),
    "plates-partitioned-lis": ("plate", ["--model", "plate", "--targets", "2", "--algo", "partitioned-lis"]),
    "landmarks-pf-eis-mt": ("landmarks", ["--model", "landmarks", "--init-gt", "--algo", "pf-eis-mt"]),
}

TIMING = {"ms", "ms_per_run", "seconds", "elapsed_s"}


def _vistrack(*args):
    return subprocess.run([sys.executable, "-m", "vistrack.cli", *args], capture_output=True, text=True)


def _digest_csv(path):
    rows = list(csv.DictReader(open(path)))
    out = io.StringIO()
    for r in rows:
        out.write(",".join(f"{k}={v}" for k, v in r.items() if k not in TIMING) + "\n")
    return hashlib.sha256(out.getvalue().encode()).hexdigest()


def _strip(obj):
    if isinstance(obj, dict):
        return {k: _strip(v) for k, v in obj.items() if k not in TIMING}
    if isinstance(obj, list):
        return [_strip(v) for v in obj]
    return obj


def digests(cache, seed=1):
    """``{case: sha256 of its track without timing columns}`` (``"skipped"`` without the clip;
    ``"failed: ..."`` when the run fails)."""
    cache.mkdir(parents=True, exist_ok=True)
    for name, args in CLIPS.items():
        if not (cache / name / "meta.json").exists():
            r = _vistrack("synth", args[0], "--out", str(cache / name), *args[1:])
            if r.returncode:
                raise SystemExit(f"vistrack synth {name} failed:\n{r.stderr}")
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for case, (clip, args) in CASES.items():
            folder = Path(clip) if "/" in clip else cache / clip
            if not folder.exists():
                out[case] = "skipped"
                continue
            track = Path(tmp) / f"{case}.csv"
            r = _vistrack("run", str(folder), *args, "--seed", str(seed), "--track", str(track))
            out[case] = _digest_csv(track) if track.exists() else f"failed: {(r.stderr or r.stdout)[-300:]}"
            print(f"{case:26s} {out[case][:16]}", flush=True)
        js = Path(tmp) / "bearings.json"
        r = _vistrack("reproduce", "bearings", "--sequences", "2", "--runs", "3", "--steps", "8", "--particles", "50",
                      "--algos", "bootstrap,lis", "--workers", "1", "--in-process", "--json", str(js))
        out["bearings"] = (hashlib.sha256(json.dumps(_strip(json.load(open(js))), sort_keys=True).encode()).hexdigest()
                           if js.exists() else f"failed: {r.stderr[-300:]}")
        print(f"{'bearings':26s} {out['bearings'][:16]}", flush=True)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--save", type=Path, help="write the digests here (JSON)")
    ap.add_argument("--check", type=Path, help="compare with the digests in this file; exit 1 on a difference")
    ap.add_argument("--cache", type=Path, default=Path.home() / ".cache" / "vistrack" / "fixed_tracks")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args(argv)
    got = digests(a.cache, a.seed)
    if a.save:
        a.save.write_text(json.dumps(got, indent=1) + "\n")
    if a.check:
        want = json.loads(a.check.read_text())
        diff = [k for k in sorted(set(want) | set(got)) if want.get(k) != got.get(k)]
        for k in diff:
            print(f"DIFFERENT {k}: {want.get(k, '-')[:16]} -> {got.get(k, '-')[:16]}")
        print("identical" if not diff else f"{len(diff)} case(s) differ")
        return 1 if diff else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
