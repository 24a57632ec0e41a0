"""One list of models and algorithms (the registry) behind run, eval and demo (issues 36 item 3, 37 item 1)."""

import json

from cli_helpers import run
from clip_helpers import square_clip
from vistrack.cli.eval import eval_cmd
from vistrack.cli.run import RUN_ALGOS
from vistrack.data_synth.contour import make_contour_clip
from vistrack.engine.evaluation import check_algos
from vistrack.models.registry import DEFAULT_MODEL, MODELS, all_algos


def test_every_algorithm_run_offers_is_one_eval_accepts():
    assert set(RUN_ALGOS) == set(all_algos())
    assert {"ls-n-ips-nn", "partitioned-lis", "pf-eis-mt", "rb-ss-hs-sir"} <= set(RUN_ALGOS)
    check_algos(list(RUN_ALGOS))  # raises on any it does not take
    help_text = " ".join(o.help or "" for o in eval_cmd.params if o.name == "algos")
    assert all(a in help_text for a in RUN_ALGOS)
    for spec in MODELS.values():
        assert set(spec.algos) <= set(RUN_ALGOS)


def test_eval_without_model_tracks_a_real_clip_with_run_s_default(tmp_path, capsys):
    clip = tmp_path / "sq"
    square_clip(clip)
    code, _, err = run(["eval", str(clip), "--algos", "lis", "--particles", "20", "--runs", "1", "--in-process",
                        "--workers", "1", "--out", str(tmp_path / "e"), "-q"], capsys)
    assert code == 0, err
    assert DEFAULT_MODEL == "box"
    assert json.loads((tmp_path / "e" / "results.json").read_text())["config"]["model"] == "box"


def test_eval_without_model_takes_the_model_the_clips_name(tmp_path, capsys):
    make_contour_clip(tmp_path / "s" / "c1", frames=6, size=(128, 96), seed=1, clutter="low", distractor=False)
    code, _, err = run(["eval", str(tmp_path / "s"), "--algos", "lis", "--particles", "20", "--runs", "1",
                        "--in-process", "--workers", "1", "--out", str(tmp_path / "e"), "-q"], capsys)
    assert code == 0, err
    assert json.loads((tmp_path / "e" / "results.json").read_text())["config"]["model"] == "contour"
    square_clip(tmp_path / "s" / "c2")
    code, _, err = run(["eval", str(tmp_path / "s"), "--algos", "lis", "--out", str(tmp_path / "e2")], capsys)
    assert code == 1
    assert err.strip() == "Error: the clips name different models in meta.json (box, contour): give --model"
