"""What issue 54's one rule for 1-based ground truth changes on the real clips: the clips whose
``groundtruth_rect.txt`` has no ``img/`` folder beside it were read 0-based before (the folder decided) and
1-based now (the file's name decides). Each is tracked once as a user would (``vistrack run VIDEO --init
<the file's first line> --seed 1``: the box model, LIS, N = 100) and the same track is scored against the
truth read both ways (success AUC, precision at 20 px, mean centre error).

    python benchmarks/one_based.py
"""

import csv
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from real_corpus import find_clips, user_box  # run from benchmarks/

from vistrack.io.video import read_rects
from vistrack.scoring.metrics import box_scores


def main():
    before, after = [], []
    with tempfile.TemporaryDirectory() as d:
        for clip in find_clips():
            if (clip.folder / "img").is_dir():
                continue  # read 1-based before too
            gt = clip.folder / "groundtruth_rect.txt"
            track = Path(d) / f"{clip.name}.csv"
            subprocess.run([sys.executable, "-c", "from vistrack.cli import main; main()", "run", str(clip.video),
                            "--init", ",".join(map(str, user_box(gt))), "--seed", "1", "--track", str(track), "-q"],
                           check=True, cwd=d)
            with open(track, newline="") as f:
                est = np.array([[float(r["cx"]) - float(r["w"]) / 2, float(r["cy"]) - float(r["h"]) / 2,
                                 float(r["w"]), float(r["h"])] for r in csv.DictReader(f)])
            a, b = (box_scores(est, read_rects(gt, origin=o)[:len(est)]) for o in (0, 1))
            before.append(a[0])
            after.append(b[0])
            print(f"{clip.name:34s} AUC {a[0]:.3f} -> {b[0]:.3f}, precision@20px {a[1]:.3f} -> {b[1]:.3f}, "
                  f"centre error {a[2]:.2f} -> {b[2]:.2f} px", flush=True)
    print(f"mean over these {len(before)} clips: AUC {np.mean(before):.3f} -> {np.mean(after):.3f}")


if __name__ == "__main__":
    main()
