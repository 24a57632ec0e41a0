"""One list of models and algorithms (the registry) behind run, eval and demo (issues 36 item 3, 37 item 1)."""

import json

import numpy as np
import pytest

from cli_helpers import run
from clip_helpers import square_clip
from vistrack.cli.eval import eval_cmd
from vistrack.cli.run import RUN_ALGOS
from vistrack.data_synth.contour_clip import make_contour_clip
from vistrack.evaluation.experiment import check_algos
from vistrack.registry import DEFAULT_MODEL, MODELS, all_algos


def test_every_algorithm_run_offers_is_one_eval_accepts():
    assert set(RUN_ALGOS) == set(all_algos())
    assert {"ls-n-ips-nn", "partitioned-lis", "pf-eis-mt", "rb-ss-hs-sir"} <= set(RUN_ALGOS)
    check_algos(list(RUN_ALGOS))  # raises on any it does not take
    help_text = " ".join(o.help or "" for o in eval_cmd.params if o.name == "algos")
    assert all(a in help_text for a in RUN_ALGOS)
    for spec in MODELS.values():
        assert set(spec.algos) <= set(RUN_ALGOS)


@pytest.mark.slow
def test_eval_without_model_tracks_a_real_clip_with_run_s_default(tmp_path, capsys):
    clip = tmp_path / "sq"
    square_clip(clip)
    code, _, err = run(["eval", str(clip), "--algos", "lis", "--particles", "20", "--runs", "1", "--in-process",
                        "--workers", "1", "--out", str(tmp_path / "e"), "-q"], capsys)
    assert code == 0, err
    assert DEFAULT_MODEL == "box"
    assert json.loads((tmp_path / "e" / "results.json").read_text())["config"]["model"] == "box"


@pytest.mark.slow
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


def test_eval_of_an_algorithm_the_model_does_not_run_is_one_line_naming_those_it_does(tmp_path, capsys):
    """eval --algos pf-eis-mt on box clips: refused before any task, as run refuses it, with the box
    model's algorithms (the registry derives them from the protocols the box model offers)."""
    clip = tmp_path / "sq"
    square_clip(clip)
    code, out, err = run(["eval", str(clip), "--algos", "lis,pf-eis-mt", "--particles", "20", "--runs", "1",
                          "--in-process", "--out", str(tmp_path / "e"), "-q"], capsys)
    box = MODELS["box"].algos
    assert code != 0 and err.strip() == ("Error: --algos pf-eis-mt does not run on the box model; choose from "
                                         + ", ".join(box))
    assert box[:2] == ("lis", "bootstrap") and "pf-eis-mt" not in box and "Traceback" not in out + err
    assert not (tmp_path / "e" / "tasks").exists()


def test_every_algorithm_a_model_lists_builds_on_it_and_no_other_does():
    """The derived lists are the truth: each algorithm listed for the box model builds a filter on a
    box model, and every registered one not listed (under any name of it) fails with one line."""
    from vistrack.registry import FILTERS, make_filter, model_from_box

    frame = np.full((72, 96, 3), 40, np.uint8)
    frame[20:40, 20:40] = (40, 60, 220)
    model = model_from_box("box", frame, (20, 20, 20, 20))
    listed = set(MODELS["box"].algos)
    for name, spec in FILTERS.items():
        if name in listed or (spec.alias_of or name) in listed:
            make_filter(name, model)
        else:
            with pytest.raises(ValueError, match=f"^{name}( [(].*[)])? needs a model with .*; Box does not supply"):
                make_filter(name, model)


def test_a_model_registered_without_algorithms_runs_what_its_protocols_offer():
    """A model class that gains a protocol gains its filters: nothing lists them by hand. The default
    is the first in the filter registry's order that runs on it."""
    from vistrack.models.protocol import VideoModelBase
    from vistrack.registry import ModelSpec, register

    class Walk(VideoModelBase):
        dim = 2

        def sample_prior(self, n, rng): ...
        def prior_logpdf(self, states): ...
        def predict(self, states, rng): ...
        def transition_logpdf(self, new, old): ...
        def loglik(self, obs, states): ...

    class WalkWithProposal(Walk):
        def lis_proposal(self, kernel=None): ...

    try:
        walk = register(ModelSpec("walk", description="a random walk", model_class=Walk))
        assert walk.algos == ("bootstrap", "condensation", "avpf") and walk.default_algo == "bootstrap"
        assert walk.multi_algos == ()
        lis = register(ModelSpec("walk-lis", description="a random walk", model_class=WalkWithProposal))
        assert lis.algos == ("lis", "bootstrap", "condensation", "avpf")
        with pytest.raises(ValueError, match="model 'walk': lis does not run on Walk"):
            register(ModelSpec("walk", ("lis",), "a random walk", model_class=Walk))
    finally:
        MODELS.pop("walk", None)
        MODELS.pop("walk-lis", None)


def test_a_filter_s_options_come_from_its_class():
    from vistrack.registry import FILTERS

    opts = {o.name: o for o in FILTERS["pf-eis-mt"].options}
    assert list(opts)[:2] == ["mt_dims", "mt_weight"] and opts["mt_weight"].default == "sampled"
    assert opts["mt_dims"].default is None and opts["mt_dims"].help.startswith("Number of trailing entries of")
    assert opts["resample"].default == "systematic" and opts["ess_threshold"].help.startswith("Resample every step")
    assert [o.name for o in FILTERS["avpf"].options][:2] == ["first_stage", "point"]
