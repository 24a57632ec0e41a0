"""README's demo block from `vistrack demo` itself: run it ``--times`` times (default 3) and write the
tables it prints into README.md between ``<!-- BEGIN demo`` and ``<!-- END demo -->``, a cell that
differs between the runs (frames/s; OpenCV's MIL, which is randomised inside OpenCV) as the range
seen.

    python benchmarks/readme_demo.py [--times 3] [--readme README.md]
"""

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def tables(text):
    """The markdown tables the demo printed: a list of lists of rows (cells)."""
    out, cur = [], None
    for line in text.splitlines():
        if line.startswith("|"):
            if cur is None:
                cur = []
                out.append(cur)
            cur.append([c.strip() for c in line.strip("|").split("|")])
        else:
            cur = None
    return out


def merge(cells):
    """One cell from the runs' values: the value when they agree, else ``lo–hi`` of the numbers."""
    if len(set(cells)) == 1:
        return cells[0]
    nums = [float(re.match(r"[-0-9.]+", c).group()) for c in cells]
    width = max(len(c.split(".")[1]) if "." in c.split()[0] else 0 for c in cells)
    return f"{min(nums):.{width}f}–{max(nums):.{width}f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--times", type=int, default=3)
    ap.add_argument("--readme", default=str(ROOT / "README.md"))
    args = ap.parse_args()
    runs = []
    for k in range(args.times):
        with tempfile.TemporaryDirectory() as d:
            res = subprocess.run([sys.executable, "-c", "from vistrack.cli import main; main()", "demo", "--out",
                                  str(Path(d) / "demo")], capture_output=True, text=True, cwd=ROOT)
            if res.returncode:
                sys.exit(res.stderr)
            runs.append(tables(res.stdout))
            print(f"run {k + 1}: {len(runs[-1])} tables", file=sys.stderr)
    names = ["The generated clip (`jumps`)", "The first 60 frames of girl_otb"]
    lines = [f"What `vistrack demo` printed ({args.times} runs; a cell that changed between them is the range "
             "seen: frames/s, and OpenCV's MIL, randomised inside OpenCV):", ""]
    for t, name in zip(range(len(runs[0])), names):
        lines += [f"{name}:", ""]
        for r, row in enumerate(runs[0][t]):
            if all(set(c) == {"-"} for c in row):  # the header's separator
                lines.append("|" + "---|" * len(row))
                continue
            cells = [merge([run[t][r][c] for run in runs]) for c in range(len(row))]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    block = "\n".join(lines)
    text = Path(args.readme).read_text()
    begin, end = text.find("<!-- BEGIN demo"), text.find("<!-- END demo -->")
    if begin < 0 or end < begin:
        sys.exit(f"{args.readme} has no <!-- BEGIN demo ... --> ... <!-- END demo --> block")
    begin = text.index("\n", begin) + 1
    Path(args.readme).write_text(text[:begin] + block + text[end:])
    print(block)


if __name__ == "__main__":
    main()
