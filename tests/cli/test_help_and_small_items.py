"""The small items of issue 46 (item 7 of its first part): --help says what run and eval take and do,
README's demo block says how many runs it shows, `--results` makes its folder in every format, and
`eval DIR` says which folders it left out."""

import re

import pytest

from cli_helpers import run
from clip_helpers import square_clip
from path_helpers import ROOT


def text(args):
    code, out, _ = run(args)
    assert code == 0
    return " ".join(out.split())


def test_run_help_says_it_takes_cameras_streams_and_urls():
    summary = text(["run", "--help"]).split(" Examples:")[0]
    for words in ("a camera's index", "a live stream", "the URL of a video or clip folder"):
        assert words in summary, summary
    listing = text(["--help"])
    assert re.search(r"run Track the object in VIDEO: a video file, an image", listing), listing


def test_eval_help_has_examples_dataset_roots_and_report_html():
    help_text = text(["eval", "--help"])
    for words in ("Examples: vistrack eval suite", "dataset roots (a LaSOT root, a GOT-10k split, a VOT workspace)",
                  "OUT/report.html"):
        assert words in help_text, help_text


def test_readme_demo_block_says_its_run_count_once():
    readme = (ROOT / "README.md").read_text()
    marker = re.search(r"<!-- BEGIN demo: python benchmarks/readme_demo.py --times (\d+) \(vistrack demo, (\d+) runs\)",
                       readme)
    assert marker and marker[1] == marker[2], readme[:200]
    said = re.search(r"What `vistrack demo` printed \((\d+) runs;", readme)
    assert said and said[1] == marker[1]


def test_results_make_their_folder_in_every_format(tmp_path):
    square_clip(tmp_path / "sq", 4)
    for fmt, out, made in (("otb", "new/deeper/r.txt", "new/deeper/r.txt"),
                           ("got10k", "g10k", "g10k/sq/sq_001.txt"), ("vot", "vot", "vot/sq/sq_001.txt")):
        code, _, err = run(["run", tmp_path / "sq", "--init-gt", "-n", "30", "-q", "--results", tmp_path / out,
                            "--results-format", fmt])
        assert code == 0, (fmt, err)
        assert len((tmp_path / made).read_text().splitlines()) == 4, fmt
    (tmp_path / "file").write_text("")
    code, _, err = run(["run", tmp_path / "sq", "--init-gt", "-q", "--results", tmp_path / "file" / "r.txt"])
    assert code != 0 and f"{tmp_path / 'file'} is a file, not a folder" in err


@pytest.mark.slow
def test_eval_says_which_folders_it_left_out(tmp_path):
    import pytest

    from vistrack.io.clips import SkippedFoldersWarning

    square_clip(tmp_path / "suite" / "a", 6)
    (tmp_path / "suite" / "notes").mkdir()
    (tmp_path / "suite" / "raw").mkdir()
    (tmp_path / "suite" / "raw" / "take1.avi").write_bytes(b"")
    said = (f"{tmp_path / 'suite'}: 2 folder(s) hold no clip (no video.mp4, img/ or color/ frames and no ground truth) "
            "and were left out: notes, raw")
    with pytest.warns(SkippedFoldersWarning, match=re.escape(said)):  # the console shows it as a warning: line
        code, _, err = run(["eval", tmp_path / "suite", "--algos", "lis", "--particles", "20", "--runs", "1",
                            "--in-process", "--workers", "1", "--out", tmp_path / "ev", "-q"])
    assert code == 0, err
