"""Write ``vistrack/system/kernel_manifest.json``: the compiled kernels each registered model and algorithm
call, with their argument types, so that a run compiles exactly those before it tracks and counts them
(:mod:`vistrack.system.compiling`). Run from the repository root after changing a kernel or what calls it::

    python tools/kernel_manifest.py            # write it (a few minutes: every model and algorithm)
    python tools/kernel_manifest.py --models siam   # rebuild one model's runs, keep the others'
    python tools/kernel_manifest.py --check    # exit 1 if it differs from what the code calls

Each model and algorithm tracks a few frames of clips of its kind (a small and a large frame, so that
the paths taken by frame size are seen) in a fresh process with an empty kernel cache, as ``vistrack
run`` does (the plan, the warm-up on a blank frame, the frames); a kernel counts when Python calls it
(numba compiles it at the top level), not when another kernel does. Every run compiles from scratch:
about 15 minutes on two busy cores.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

#: in a child process: track CLIP with MODEL and ALGO (TARGETS plates) for a few frames; print the kernels called
CHILD = r"""
import json, sys
from numba.core import event
from vistrack.session.plan import execute, prepare
from vistrack.system.compiling import signature_text

clip, model, algo, targets, from_gt = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5] == "1"
top, depth = [], [0]


class Listener(event.Listener):
    def on_start(self, ev):
        if depth[0] == 0:  # compiled because Python called it (the cache is empty: everything compiles)
            top.append((ev.data["dispatcher"], tuple(ev.data["args"])))
        depth[0] += 1

    def on_end(self, ev):
        depth[0] -= 1


event.register("numba:compile", Listener())
targets = int(targets) or None
plan = prepare(clip, model=model, algo=algo, particles=60, init_gt="" if from_gt else None, targets=targets,
               max_frames=6)
execute(plan, 60, 0)
out = []
for d, args in top:
    item = [d.py_func.__module__, d.py_func.__name__, signature_text(args)]
    if d.py_func.__module__.startswith("vistrack.") and item not in out:
        out.append(item)
print("KERNELS " + json.dumps(out))
"""


def clips(folder):
    """Small and large clips of each kind: ``{kind: [paths]}``."""
    from vistrack.data_synth.contour_clip import make_contour_clip
    from vistrack.data_synth.landmark_clip import make_landmark_clip
    from vistrack.data_synth.plate_clip import make_plate_clip

    folder = Path(folder)
    out = {"contour": [], "plate": [], "landmarks": []}
    for size in ((160, 120), (640, 480)):
        p = folder / f"contour-{size[0]}"
        make_contour_clip(p, frames=6, size=size, seed=1, model="box")
        out["contour"].append(p)
    p = folder / "plate"
    make_plate_clip(p, frames=40, seed=1, cars=2)
    out["plate"].append(p)
    p = folder / "landmarks"
    make_landmark_clip(p, frames=6, seed=1)
    out["landmarks"].append(p)
    return out


#: the clip kind each model tracks here
KIND = {"box": "contour", "siam": "contour", "contour": "contour", "plate": "plate", "landmarks": "landmarks"}


def called(clip, model, algo, targets=0, from_gt=True):
    """The kernels a run of ``model`` and ``algo`` on ``clip`` (from its first ground-truth box, or without
    one: the plate search) calls: ``[[module, name, argument types]]``."""
    with tempfile.TemporaryDirectory() as cache:  # empty: every kernel Python calls compiles, and is seen
        res = subprocess.run([sys.executable, "-c", CHILD, str(clip), model, algo, str(targets), str(int(from_gt))],
                             capture_output=True, text=True, cwd=ROOT, env={**os.environ, "NUMBA_CACHE_DIR": cache})
    if res.returncode:
        raise SystemExit(f"{model}/{algo} on {clip}: {res.stderr[-2000:]}")
    line = next(ln for ln in res.stdout.splitlines() if ln.startswith("KERNELS "))
    return json.loads(line[len("KERNELS "):])


def build(workers=2, models=None):
    """The manifest: ``{"kernels": {id: [module, name, argument types]}, "runs": {model/algo: [ids]}}`` (of
    ``models`` only, where given)."""
    from vistrack.registry import MODELS, SEARCH_MODEL

    jobs = []
    with tempfile.TemporaryDirectory() as d:
        by_kind = clips(d)
        for name, spec in MODELS.items():
            kind = KIND.get(name)
            if kind is None or (models and name not in models):
                continue
            starts = (True, False) if name == SEARCH_MODEL else (True,)  # from a box, and the plate search
            jobs += [(f"{name}/{a}", clip, name, a, 0, g) for a in spec.algos for clip in by_kind[kind] for g in starts]
            jobs += [(f"{name}/{a}/targets", clip, name, a, 2, False) for a in spec.multi_algos
                     for clip in by_kind[kind]]
        with ThreadPoolExecutor(workers) as pool:
            results = list(pool.map(lambda j: (j[0], called(*j[1:])), jobs))
    kernels, runs = {}, {}
    for key, found in results:
        ids = runs.setdefault(key, [])
        for item in found:
            kid = ".".join(item[:2]).removeprefix("vistrack.") + (f"({item[2]})")
            kernels.setdefault(kid, item)
            if kid not in ids:
                ids.append(kid)
    return {"kernels": dict(sorted(kernels.items())), "runs": {k: v for k, v in runs.items() if v}}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="compare with the file instead of writing it")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--models", default="", help="rebuild these models' runs only (comma-separated), keep the rest")
    args = ap.parse_args()
    from vistrack.system.compiling import MANIFEST

    models = [m for m in args.models.split(",") if m]
    built = build(args.workers, models)
    if models:  # the other models' runs as the file has them
        old = json.loads(MANIFEST.read_text())
        runs = {k: v for k, v in old["runs"].items() if k.split("/")[0] not in models} | built["runs"]
        kernels = {k: v for k, v in (old["kernels"] | built["kernels"]).items()
                   if any(k in ids for ids in runs.values())}
        built = {"kernels": dict(sorted(kernels.items())), "runs": dict(sorted(runs.items()))}
    text = json.dumps(built, indent=1) + "\n"
    if args.check:
        if MANIFEST.read_text() != text:
            raise SystemExit(f"{MANIFEST} differs from what the code calls: python tools/kernel_manifest.py")
        print(f"{MANIFEST}: up to date")
        return
    MANIFEST.write_text(text)
    print(f"wrote {MANIFEST}")


if __name__ == "__main__":
    main()
