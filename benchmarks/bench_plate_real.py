"""Every plate clip on real footage (issue 35), with and without a box, beside the box model.

Clips: the dashcam clip, its stressed copies (``vistrack synth perturb``: light ramp and flicker,
motion blur, shake, zoom, dropped frames, all at once) and rendered plates composited onto car4's
car (``vistrack synth plate-on-car``: jp at the clip's size, single-row at twice it), made once into
``--work``. Entries, LIS-100, seeds ``--seeds``:

- plate, no box: ``vistrack run CLIP --seed S`` (the detector's search, then the plate model);
- plate from the first ground-truth box: ``vistrack run CLIP --model plate --init-gt``;
- box from the same box: ``vistrack run CLIP --init-gt``.

Success AUC of the ``--results`` file against ``groundtruth_rect.txt`` (a frame not reported, or
searched before the plate was found, counts IoU 0).

    python benchmarks/bench_plate_real.py [--seeds 1 2 3] [--work /tmp/vistrack_plate_clips]
                                          [--entries "plate, no box" "plate from box"] [--clips dashcam ...]
"""

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np

from vistrack.io.results_format import read_result_file
from vistrack.scoring.metrics import iou, success_auc

REAL = Path(__file__).resolve().parents[2] / "shared" / "data" / "real"
DASHCAM = REAL / "plate_in_polo_dashcam"
CAR4 = REAL / "car4_otb_first100"
VISTRACK = [sys.executable, "-m", "vistrack.cli"]
PERTURB = {"ramp": ["--light", "ramp"], "flicker": ["--light", "flicker"], "blur7": ["--blur", "7"],
           "shake6": ["--shake", "6"], "zoom1-0.6": ["--zoom", "1:0.6"], "drop2": ["--drop", "2"],
           "all": ["--light", "flicker", "--blur", "5", "--shake", "4", "--zoom", "1:0.8", "--drop", "3"]}
COMPOSITE = {"car4-jp": ["--layout", "jp"], "car4-single-row-x2": ["--layout", "single-row", "--upscale", "2"]}


def make_clips(work):
    clips = {"dashcam": DASHCAM}
    for name, args in PERTURB.items():
        out = work / f"dashcam-{name}"
        if not out.is_dir():
            subprocess.run(VISTRACK + ["synth", "perturb", str(DASHCAM), "--out", str(out), "--seed", "1", "-q"]
                           + args, check=True)
        clips[f"dashcam-{name}"] = out
    for name, args in COMPOSITE.items():
        out = work / name
        if not out.is_dir():
            subprocess.run(VISTRACK + ["synth", "plate-on-car", str(CAR4), "--out", str(out), "--seed", "1", "-q"]
                           + args, check=True)
        clips[name] = out
    return clips


def auc(clip, results):
    gt = np.loadtxt(clip / "groundtruth_rect.txt", delimiter=",")
    if not results.is_file():  # nothing found: no frame reported
        return 0.0
    r = np.nan_to_num(read_result_file(results, "otb"))  # run --results: OTB's 1-based format
    return float(success_auc(iou(r[:len(gt)], gt[:len(r)])))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--work", default="/tmp/vistrack_plate_clips")
    ap.add_argument("--entries", nargs="+", default=None, help="only these columns (default: all three)")
    ap.add_argument("--clips", nargs="+", default=None, help="only these rows (default: every clip)")
    args = ap.parse_args()
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    entries = {"plate, no box": [], "plate from box": ["--model", "plate", "--init-gt"],
               "box from box": ["--init-gt"]}
    entries = {k: v for k, v in entries.items() if args.entries is None or k in args.entries}
    print("| clip | " + " | ".join(entries) + " |")
    print("|---|" + "---|" * len(entries))
    for name, clip in make_clips(work).items():
        if args.clips is not None and name not in args.clips:
            continue
        cells = []
        for entry, extra in entries.items():
            aucs = []
            for s in args.seeds:
                res = work / f"{name}.{entry.replace(' ', '_').replace(',', '')}.{s}.txt"
                res.unlink(missing_ok=True)
                subprocess.run(VISTRACK + ["run", str(clip), "--seed", str(s), "--results", str(res), "-q"] + extra,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                aucs.append(auc(clip, res))
            cells.append(" / ".join(f"{a:.3f}" for a in aucs) + f" (mean {np.mean(aucs):.3f})")
        print(f"| {name} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
