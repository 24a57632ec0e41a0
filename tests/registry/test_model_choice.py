"""One rule for the model (issue 46, item 2): `run` says on one line which model and algorithm it
tracks with and why (the option, the clip's meta.json, or the default)."""

import pytest

from cli_helpers import run
from clip_helpers import square_clip


@pytest.fixture(scope="module")
def contour_clip(tmp_path_factory):
    from vistrack.data_synth.contour_clip import make_contour_clip

    folder = tmp_path_factory.mktemp("choice") / "c"
    make_contour_clip(folder, frames=4, size=(96, 72), seed=1, clutter="low", distractor=False)
    return folder


def said(err):
    return [line for line in err.splitlines() if line.startswith("tracking with")]


def test_the_clip_s_meta_json_model_is_said(contour_clip):
    code, _, err = run(["run", contour_clip, "--init-gt", "-n", "30"])
    assert code == 0, err
    assert said(err) == [f"tracking with the contour model (named in {contour_clip / 'meta.json'}; --model box "
                         "tracks any object) and lis (the contour model's default), N=30"]


def test_the_options_are_said(contour_clip):
    code, _, err = run(["run", contour_clip, "--init-gt", "--model", "box", "--algo", "bootstrap", "-n", "40"])
    assert code == 0, err
    assert said(err) == ["tracking with the box model (--model) and bootstrap (--algo), N=40"]


def test_the_default_is_said_and_quiet_says_nothing(tmp_path):
    square_clip(tmp_path / "sq", 4)
    code, _, err = run(["run", tmp_path / "sq" / "sq.mp4", "--init", "20,20,20,20", "-n", "30"])
    assert code == 0, err
    assert said(err) == ["tracking with the box model (the default with a start box: any object, its appearance "
                         "learned from the box) and lis (the box model's default), N=30"]
    code, _, err = run(["run", tmp_path / "sq" / "sq.mp4", "--init", "20,20,20,20", "-q"])
    assert code == 0 and not said(err), err


def test_a_model_the_version_lacks_is_one_line(tmp_path):
    import json

    square_clip(tmp_path / "sq", 4)
    (tmp_path / "sq" / "meta.json").write_text(json.dumps({"model": "hovercraft"}))
    code, _, err = run(["run", tmp_path / "sq", "--init-gt"])
    assert code != 0 and err.strip() == (f"Error: {tmp_path / 'sq'}: meta.json names model 'hovercraft', which this "
                                         "version cannot track")


def test_demo_says_runs_in_english():
    from vistrack.demo.steps import runs_phrase

    assert (runs_phrase(1), runs_phrase(4)) == ("1 run", "4 runs")
