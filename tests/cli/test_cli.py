"""The command line: help, the bearings reproduction's files, one-line errors."""

import json

import matplotlib.image as mpimg
import pytest

from cli_helpers import run

RESULT_KEYS = {"algo", "particles", "ships", "mean_error_final", "std_error_final", "mean_error", "ms_per_run"}




def test_version_and_help(capsys):
    code, out, _ = run(["--version"], capsys)
    assert code == 0 and out.startswith("vistrack, version")
    code, out, _ = run(["--help"], capsys)
    assert code == 0 and "reproduce" in out
    code, out, _ = run(["reproduce", "bearings", "--help"], capsys)
    assert code == 0 and "--particles" in out and "--plots" in out


@pytest.mark.slow
def test_reproduce_bearings_writes_json_and_plots(tmp_path, capsys):
    js = tmp_path / "r.json"
    argv = ["reproduce", "bearings", "--out", str(tmp_path / "res"), "--in-process", "--workers", "2",
            "--sequences", "2", "--runs", "2", "--steps", "4",
            "--particles", "10,20", "--algos", "bootstrap,lis", "--seed", "3", "-q",
            "--json", str(js), "--plots", str(tmp_path / "plots")]
    code, out, err = run(argv, capsys)
    assert code == 0, err
    assert "final err" in out and "lis" in out
    data = json.loads(js.read_text())
    assert set(data) == {"config", "results"}
    assert data["config"]["particles"] == [10, 20] and data["config"]["seed"] == 3
    assert data["config"]["proposal"] == "xi"  # LIS's default proposal on the bearings model
    assert len(data["results"]) == 4
    for row in data["results"]:
        assert RESULT_KEYS <= set(row)
        assert row["ships"] == 1 and row["mean_error_final"] > 0 and row["ms_per_run"] > 0
    for name in ("error_vs_time.png", "error_vs_n.png"):
        png = tmp_path / "plots" / name
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert mpimg.imread(png).shape[0] > 100
    # same seed, same numbers
    js2 = tmp_path / "r2.json"
    run(argv[:-4] + ["--json", str(js2)], capsys)

    def strip(d):
        return [{k: v for k, v in r.items() if k != "ms_per_run"} for r in d["results"]]

    assert strip(json.loads(js2.read_text())) == strip(data)
    # an interrupted reproduction resumed (one sequence file lost) gives the same numbers,
    # and so does the in-process loop of the library
    sorted((tmp_path / "res" / "tasks").glob("*.json"))[0].unlink()
    js3 = tmp_path / "r3.json"
    run(argv[:-4] + ["--resume", "--json", str(js3)], capsys)
    assert strip(json.loads(js3.read_text())) == strip(data)
    from vistrack.reproduce.bearings import BearingsConfig, run_bearings

    direct = run_bearings(BearingsConfig(**data["config"]))
    assert strip(direct) == strip(data)


@pytest.mark.parametrize(
    "args, message",
    [
        (["--particles", "0"], "--particles must be positive"),
        (["--particles", "10,abc"], "comma-separated integers"),
        (["--runs", "-1"], "--runs must be a positive integer"),
        (["--algos", "bootstrap,magic"], "unknown algorithm 'magic'"),
        (["--json", "/nonexistent-dir/x.json"], "does not exist"),
        (["--ships", "0"], "--ships must be at least 1"),
        (["--lis-proposal", "nope"], "'nope' is not one of 'xi', 'position'"),
    ],
)
def test_bad_input_gives_one_clear_line(args, message, capsys):
    code, out, err = run(["reproduce", "bearings", "--runs", "1", "--sequences", "1", "-q"] + args, capsys)
    assert code != 0
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("Error:") and message in lines[0]
    assert "Traceback" not in err + out


def test_unknown_command_is_one_line(capsys):
    code, _, err = run(["frobnicate"], capsys)
    assert code == 2 and err.strip().startswith("Error:") and len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_json_may_go_into_the_plots_folder(tmp_path, capsys):
    """The README's first command writes the JSON into the folder --plots creates."""
    out = tmp_path / "bearings-out"
    code, _, err = run(["reproduce", "bearings", "--out", str(tmp_path / "res"), "--in-process",
                        "--sequences", "1", "--runs", "1", "--particles", "10", "-q",
                        "--plots", str(out), "--json", str(out / "results.json")], capsys)
    assert code == 0, err
    assert json.loads((out / "results.json").read_text())["results"]


def test_reproduce_tables_align_every_column_and_mark_missing_measures():
    """``reproduce``'s tables (vistrack.reproduce.tables): one fixed width per column, and a
    measure with nothing to average (None, e.g. no plate frame) printed as '-' in its column."""
    from vistrack.reproduce.tables import format_table

    row = dict(algo="lis", particles=100, p_lost=0.25, mean_vertex_error=None, false_reports=2,
               acquired_within=None, never_acquired=0, mean_acquisition_delay=1.5, ms_per_frame=7.3,
               frames_per_s=137.0, mean_ess=20.0)
    lines = format_table("plate", [row, dict(row, mean_vertex_error=3.25)]).splitlines()
    assert len({len(line) for line in lines}) == 1  # header, rule and rows are equally wide
    assert lines[0].split() == ["algo", "N", "P(lost)", "vertex", "err", "false", "rep.", "acq<=10", "never",
                                "mean", "acq", "ms/frame", "frames/s", "ESS"]
    assert lines[2].split()[3] == "-" and lines[3].split()[3] == "3.25"
    assert lines[2].index(" - ") + 2 == lines[3].index("3.25") + 4  # the '-' sits where the number ends
    long = format_table("plate", [row, dict(row, algo="branched-partitioned")]).splitlines()
    assert len({len(line) for line in long}) == 1  # a name longer than the column widens it
    assert long[3].startswith("branched-partitioned ") and long[2].index(" 100 ") == long[3].index(" 100 ")
