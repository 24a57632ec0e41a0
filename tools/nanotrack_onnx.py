"""Write the NanoTrack v3 networks that vistrack ships (``vistrack/models/siam/weights/``) from the authors'
ONNX files (``../shared/data/baselines/nanotrack_v3``, Apache-2.0), changed only where their shapes are fixed:

- the backbone takes a batch of crops of any size: its input ``[N, 3, H, W]`` symbolic, and its
  squeeze-and-excitation reshapes ``[1, C]`` / ``[1, C, 1, 1]`` made ``[0, C]`` / ``[0, C, 1, 1]`` (``0``: the
  input's own first dimension, the batch);
- the head takes a batch of search maps (``input2`` ``[N, 96, 16, 16]``, one exemplar ``input1``
  ``[1, 96, 8, 8]``): its reshapes keep their input's first dimension (``0``) alike;
- a head for one exemplar, ``nanotrack_head_exemplar.onnx``: ``input1`` is no input but an initializer holding
  a placeholder (:data:`PLACEHOLDER_SEED`'s uniform draws), whose bytes vistrack replaces by the exemplar's
  features before it makes the session: onnxruntime then folds the exemplar's branch into constants and
  pre-packs the depthwise correlation's weights (a 255 crop's head 0.9 ms against 1.2 ms, the same outputs
  within 1e-4; ``vistrack.models.siam.network.SiamNetwork``);
- a second head, ``nanotrack_head_wide.onnx``, made for a wider search map (``--wide``, 32 x 32: a 511 x 511
  crop), whose spatial reshapes say so; its logits differ from a normal crop's (the head pools globally), so
  vistrack uses it to find candidates only.

Weights and operators are unchanged; ``tests/models/siam/test_network.py`` checks that the outputs equal the
authors' files' on a fixed crop. Run from the repository root (needs the ``onnx`` package, a development
tool, not a dependency of vistrack)::

    python tools/nanotrack_onnx.py
"""

from __future__ import annotations

import argparse
import hashlib
import shutil
from pathlib import Path

import numpy as np
import onnx
from onnx import numpy_helper

ROOT = Path(__file__).resolve().parents[1]
SOURCE = ROOT.parent / "shared" / "data" / "baselines" / "nanotrack_v3"
OUT = ROOT / "vistrack" / "models" / "siam" / "weights"
#: the placeholder of the exemplar head's ``input1``: ``default_rng(PLACEHOLDER_SEED).uniform(-1, 1, (1, 96, 8, 8))``
#: in float32 (its bytes occur once in the file)
PLACEHOLDER_SEED = 20261128
#: the authors' files (SOURCE.txt's sha256)
SHA256 = {"nanotrack_backbone.onnx": "50be1320abf9384fd3479ea829f95e244cf3f3838190c5ab60c750fb8c1ce828",
          "nanotrack_head.onnx": "75357903be3f4817c965af16cb5a11fd32b1467f597a408405a98635ac63f61d"}


def _constants(model):
    """``{name: TensorProto}`` of the graph's initializers and Constant nodes' values."""
    out = {t.name: t for t in model.graph.initializer}
    for n in model.graph.node:
        if n.op_type == "Constant":
            out[n.output[0]] = n.attribute[0].t
    return out


def _set(tensor, value):
    tensor.CopyFrom(numpy_helper.from_array(np.asarray(value, np.int64), tensor.name))


def _shape(value_info, dims):
    """Set the declared shape of an input or output: a name for a symbolic dimension, else a size."""
    for d, v in zip(value_info.type.tensor_type.shape.dim, dims):
        if isinstance(v, str):
            d.ClearField("dim_value")
            d.dim_param = v
        else:
            d.ClearField("dim_param")
            d.dim_value = int(v)


def backbone(model):
    """The backbone for a batch of crops of any size."""
    consts = _constants(model)
    for n in model.graph.node:
        if n.op_type == "Reshape":
            t = consts[n.input[1]]
            shape = numpy_helper.to_array(t).copy()
            shape[0] = 0  # the input's own first dimension: the batch
            _set(t, shape)
    _shape(model.graph.input[0], ["N", 3, "H", "W"])
    _shape(model.graph.output[0], ["N", 96, "h", "w"])
    return model


def head(model, size=16):
    """The head for a batch of ``size x size`` search maps and one exemplar."""
    consts = _constants(model)
    out = size - 1
    for n in model.graph.node:
        if n.op_type != "Reshape":
            continue
        t = consts[n.input[1]]
        shape = numpy_helper.to_array(t).copy()
        if list(shape) == [96, 1, 4, 4]:  # the exemplar's centre as depthwise kernels: one exemplar
            continue
        if len(shape) == 4 and shape[2] == 16:
            shape[2:] = size
        elif len(shape) == 4 and shape[2] == 15:
            shape[2:] = out
        shape[0] = 0  # the input's own first dimension: the batch
        _set(t, shape)
    _shape(model.graph.input[1], ["N", 96, size, size])
    for o in model.graph.output:
        _shape(o, ["N", o.type.tensor_type.shape.dim[1].dim_value, out, out])
    return model


def exemplar_head(model):
    """The head with ``input1`` an initializer holding the placeholder (module docstring)."""
    model = head(model)
    inp = next(i for i in model.graph.input if i.name == "input1")
    model.graph.input.remove(inp)
    ph = np.random.default_rng(PLACEHOLDER_SEED).uniform(-1, 1, (1, 96, 8, 8)).astype(np.float32)
    model.graph.initializer.append(numpy_helper.from_array(ph, "input1"))
    if model.SerializeToString().count(ph.tobytes()) != 1:
        raise SystemExit("the placeholder's bytes are not unique in the exemplar head")
    return model


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--source", default=str(SOURCE))
    ap.add_argument("--out", default=str(OUT))
    args = ap.parse_args()
    src, out = Path(args.source), Path(args.out)
    for name, digest in SHA256.items():
        got = hashlib.sha256((src / name).read_bytes()).hexdigest()
        if got != digest:
            raise SystemExit(f"{src / name}: sha256 {got}, not the authors' {digest}")
    out.mkdir(parents=True, exist_ok=True)
    made = {"nanotrack_backbone.onnx": backbone(onnx.load(src / "nanotrack_backbone.onnx")),
            "nanotrack_head.onnx": head(onnx.load(src / "nanotrack_head.onnx")),
            "nanotrack_head_wide.onnx": head(onnx.load(src / "nanotrack_head.onnx"), 32),
            "nanotrack_head_exemplar.onnx": exemplar_head(onnx.load(src / "nanotrack_head.onnx"))}
    for name, model in made.items():
        onnx.checker.check_model(model)
        onnx.save(model, out / name)
        print(f"wrote {out / name} ({(out / name).stat().st_size} bytes)")
    shutil.copy(src / "LICENSE", out / "LICENSE")


if __name__ == "__main__":
    main()
