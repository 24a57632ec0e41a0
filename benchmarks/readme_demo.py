"""README's demo block from `vistrack demo` itself: run it ``--times`` times (default 3) and write the
tables it prints into README.md between ``<!-- BEGIN demo`` and ``<!-- END demo -->``, a cell that
differs between the runs (frames/s; OpenCV's MIL, which is randomised inside OpenCV) as the range
seen. ``--check`` runs the demo once and compares its frames/s with README's ranges (the test
suite compares every other cell; speed is the machine's, so it is checked here, not there).
``--timings`` measures the demo's wall time as a user meets it: ``--first K`` runs each with an
empty kernel cache (``NUMBA_CACHE_DIR``: as after a fresh install, the kernels compile), then
``--later M`` runs with the cache the first left.

    python benchmarks/readme_demo.py [--times 3] [--readme README.md]
    python benchmarks/readme_demo.py --check
    python benchmarks/readme_demo.py --timings --first 3 --later 3
"""

import argparse
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
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
    first = [re.match(r"[-0-9.]+", c).group() for c in cells]  # a cell's number (of "mean ± sd": the mean)
    nums = [float(v) for v in first]
    width = max(len(v.split(".")[1]) if "." in v else 0 for v in first)
    return f"{min(nums):.{width}f}–{max(nums):.{width}f}"


def demo(env=None):
    """``(stdout, wall seconds, CPU seconds)`` of one ``vistrack demo`` into a temporary folder, from the
    repository root."""
    with tempfile.TemporaryDirectory() as d:
        cpu0, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
        res = subprocess.run([sys.executable, "-c", "from vistrack.cli import main; main()", "demo", "--out",
                              str(Path(d) / "demo")], capture_output=True, text=True, cwd=ROOT, env=env)
        took, cpu1 = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
    if res.returncode:
        sys.exit(res.stderr)
    return res.stdout, took, cpu1.ru_utime + cpu1.ru_stime - cpu0.ru_utime - cpu0.ru_stime


def readme_block(readme):
    text = Path(readme).read_text()
    return text[text.index("<!-- BEGIN demo"):text.index("<!-- END demo -->")]


def check(readme):
    """One demo's frames/s against README's ranges: each within 0.2-5 times (the machine's load moves
    them); exit 1 where one is not."""
    got, want = tables(demo()[0]), tables(readme_block(readme))
    bad = 0
    for g, w in zip(got, want):
        for gr, wr in zip(g[2:], w[2:]):
            lo, hi = (float(v) for v in re.findall(r"[0-9.]+", wr[-1])[:2] * (1 if "–" in wr[-1] else 2))
            ok = 0.2 * lo <= float(gr[-1]) <= 5 * hi
            bad += not ok
            print(f"{gr[0]:10s} N={gr[1]:4s} frames/s {gr[-1]:>6s}   README {wr[-1]:>9s}   {'ok' if ok else 'OFF'}")
    sys.exit(1 if bad else 0)


def timings(first, later):
    """Wall (and CPU) seconds of ``first`` demos, each with an empty kernel cache, then ``later`` ones."""
    env = dict(os.environ)
    runs = {"first": [], "later": []}
    with tempfile.TemporaryDirectory() as cache:
        for kind, n in (("first", first), ("later", later)):
            for k in range(n):
                if kind == "first":
                    env["NUMBA_CACHE_DIR"] = str(Path(cache) / f"c{k}")
                runs[kind].append(demo(env)[1:])
                print(f"{kind} run {k + 1}: {runs[kind][-1][0]:.1f} s ({runs[kind][-1][1]:.1f} s CPU)", file=sys.stderr)

    def span(v):
        return f"{min(v):.0f}–{max(v):.0f}"

    print("vistrack demo, wall seconds (CPU seconds): " + "; ".join(
        f"{kind} run{'s' if len(v) > 1 else ''} {span([w for w, _ in v])} ({span([c for _, c in v])})"
        for kind, v in runs.items() if v))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--times", type=int, default=3)
    ap.add_argument("--readme", default=str(ROOT / "README.md"))
    ap.add_argument("--check", action="store_true", help="one demo's frames/s against README's ranges")
    ap.add_argument("--timings", action="store_true", help="the demo's wall time, first and later runs")
    ap.add_argument("--first", type=int, default=3)
    ap.add_argument("--later", type=int, default=3)
    args = ap.parse_args()
    if args.check:
        check(args.readme)
    if args.timings:
        return timings(args.first, args.later)
    runs = []
    for k in range(args.times):
        runs.append(tables(demo()[0]))
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
    marker = (f"<!-- BEGIN demo: python benchmarks/readme_demo.py --times {args.times} (vistrack demo, "
              f"{args.times} runs) -->\n")
    Path(args.readme).write_text(text[:begin] + marker + block + text[end:])
    print(block)


if __name__ == "__main__":
    main()
