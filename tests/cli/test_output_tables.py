"""Output that reads cleanly when redirected (issue 54, item 2): ``vistrack demo`` and ``vistrack eval`` with
stdout and stderr going to one file, as ``> log 2>&1`` does. Every markdown table in it parses (each row
starts its own line and has the header's number of cells), no progress bar follows the last table, and
eval's closing line names every file it wrote."""

import re
import subprocess
import sys

import pytest

from clip_helpers import tiny_otb_clip

#: what a progress bar (tqdm) writes: ``12/12 [00:08<00:00, ...]``
BAR = re.compile(r"\d+/\d+ \[|\d+%\|")
#: the demo and eval end to end (over 2 s each: conftest.py's rule)
pytestmark = pytest.mark.slow


def _redirected(args, cwd):
    """Everything ``vistrack ARGS`` writes, stdout and stderr into one pipe (not a terminal)."""
    res = subprocess.run([sys.executable, "-c", "from vistrack.cli import main; main()", *map(str, args)],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=cwd)
    assert res.returncode == 0, res.stdout[-3000:]
    return res.stdout


def tables(text):
    """The markdown tables in ``text``: ``[(first line index, rows)]``, each row its cells; asserts that
    every table line starts a line of its own (nothing before it, no carriage return in it)."""
    lines = text.split("\n")
    found, k = [], 0
    while k < len(lines):
        if "| algo |" in lines[k] or "|---|" in lines[k]:
            assert lines[k].startswith("| algo |") or lines[k - 1].startswith("| algo |"), repr(lines[k][:200])
        if lines[k].startswith("| algo |"):
            start, rows = k, []
            while k < len(lines) and lines[k].startswith("|"):
                assert "\r" not in lines[k] and lines[k].endswith("|"), repr(lines[k])
                rows.append([c.strip() for c in lines[k].strip("|").split("|")])
                k += 1
            found.append((start, rows))
            continue
        k += 1
    return found


def check(text, n_tables):
    """Every table parses; nothing after the last one is a progress bar."""
    found = tables(text)
    assert len(found) == n_tables, text[-3000:]
    for _, rows in found:
        header, sep, *body = rows
        assert body and all(set(c) <= {"-"} and c for c in sep), rows[:2]
        assert all(len(r) == len(header) for r in (sep, *body)), rows
    start, rows = found[-1]
    after = "\n".join(text.split("\n")[start + len(rows):])
    assert not BAR.search(after), after


@pytest.fixture(scope="module")
def demo_out(tmp_path_factory):
    d = tmp_path_factory.mktemp("demo")
    real = tiny_otb_clip(d / "Tiny")
    text = _redirected(["demo", "--out", d / "out", "--frames", "12", "--runs", "1", "--real-clip", real,
                        "--real-frames", "10"], d)
    return d, text


def test_the_demo_s_tables_parse_and_no_bar_follows_them(demo_out):
    _, text = demo_out
    check(text, 2)
    assert BAR.search(text)  # the bars were there, each finished on a line of its own


def test_eval_s_table_parses_no_bar_follows_and_its_last_line_names_every_file(demo_out):
    d, _ = demo_out
    out = d / "ev"
    text = _redirected(["eval", d / "out" / "clips" / "jumps", "--algos", "lis,bootstrap", "--particles", "20",
                        "--runs", "2", "--workers", "1", "--out", out], d)
    check(text, 1)
    last = text.rstrip("\n").split("\n")[-1]
    plots, videos = sorted(out.glob("*.png")), sorted((out / "videos").glob("*.mp4"))
    assert plots and len(videos) == 2
    assert last == (f"wrote {out / 'results.json'}, results.csv, report.md, report.html, {len(plots)} plots and "
                    f"{len(videos)} annotated videos (videos/)")
    assert {p.name for p in out.iterdir() if p.is_file()} == {"results.json", "results.csv", "report.md",
                                                              "report.html", *(p.name for p in plots)}
