"""eval's closing line names every file it wrote (issue 54, item 2), counted where there are several."""

from pathlib import Path

from vistrack.evaluation.pipeline import Evaluation


def test_the_closing_line_names_every_file():
    out = Path("ev")
    one = Evaluation([], [out / "a.png"], out / "report.md", videos=[out / "videos" / "lis.mp4"])
    assert one.wrote() == "wrote ev/results.json, results.csv, report.md, report.html, 1 plot and 1 annotated video " \
                          "(videos/)"
    many = Evaluation([], [out / "a.png", out / "b.png"], out / "report.md", videos=[out / "v1.mp4", out / "v2.mp4"])
    assert many.wrote().endswith("report.html, 2 plots and 2 annotated videos (videos/)")


def test_several_targets_write_no_html_plots_or_videos():
    mot = Evaluation([], [], Path("ev") / "report.md", files=("results.json", "results.csv", "report.md"))
    assert mot.wrote() == "wrote ev/results.json, results.csv and report.md"
