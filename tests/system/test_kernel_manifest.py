"""The kernels a run compiles up front (issue 54, item 1): ``kernel_manifest.json`` names, for each model and
algorithm, compiled kernels of the package with argument types numba reads back; a first run counts them
(``compiling kernels k/n``) and tells nothing when every one loads from the cache."""

from importlib.resources import files

import pytest

from vistrack.registry import MODELS
from vistrack.system.compiling import Compiler, compiling, kernel, kernels_for, manifest, signature_text


def test_the_manifest_ships_with_the_package():
    assert files("vistrack.system").joinpath("kernel_manifest.json").is_file()


def test_every_entry_is_a_cached_kernel_of_the_package_with_types_numba_reads_back():
    from numba.core import sigutils
    from numba.core.caching import NullCache
    from numba.core.registry import CPUDispatcher

    entries = manifest()["kernels"]
    assert entries
    for module, name, args in entries.values():
        k = kernel(module, name)
        assert module.startswith("vistrack.") and isinstance(k, CPUDispatcher), (module, name)
        assert not isinstance(k._cache, NullCache), (module, name)  # cache=True: compiled once per install
        assert signature_text(sigutils.normalize_signature(f"({args},)")[0]) == args


def test_each_run_lists_known_kernels_and_the_models_with_kernels_have_their_defaults():
    m = manifest()
    assert all(k in m["kernels"] for ids in m["runs"].values() for k in ids)
    assert {key.split("/")[0] for key in m["runs"]} <= set(MODELS)
    for model in ("box", "contour", "plate"):  # landmarks have no compiled kernels
        assert kernels_for(model, [MODELS[model].default_algo]), model
    assert kernels_for("box", ["no-such-algo"]) == []


def test_a_kernel_list_is_the_union_in_order_each_once():
    lis, boot = kernels_for("box", ["lis"]), kernels_for("box", ["bootstrap"])
    both = kernels_for("box", ["lis", "bootstrap"])
    assert both[:len(lis)] == lis and set(both) == set(lis) | set(boot) and len(both) == len(set(both))


@pytest.mark.parametrize("events, said", [
    # every kernel loaded from the cache: nothing said
    ([], []),
    # the second of three compiles (one nested kernel inside it): counted from there, 1/3 then 2/3, 3/3
    ([None, "compile", None], [(1, 3), (2, 3), (3, 3)]),
])
def test_the_count_starts_at_the_first_compile(monkeypatch, events, said):
    """:meth:`Compiler.compile` over three listed kernels whose ``compile`` fires numba's events as given."""
    told = []
    compiler = Compiler(lambda done, total: told.append((done, total)))

    class Kernel:
        def __init__(self, event):
            self.event = event

        def compile(self, sig):
            if self.event:
                compiler._start()
                compiler._start()  # a kernel it calls, compiled with it
                compiler._end()
                compiler._end()

    kernels = [Kernel(e) for e in events]
    monkeypatch.setattr("vistrack.system.compiling.kernels_for",
                        lambda *a: [("m", str(i), "int64") for i in range(len(kernels))])
    monkeypatch.setattr("vistrack.system.compiling.kernel", lambda module, name: kernels[int(name)])
    compiler.compile("box", ["lis"])
    assert told == said


def test_a_kernel_the_list_does_not_name_is_counted_when_it_compiles():
    told = []
    with compiling(lambda done, total: told.append((done, total))) as compiler:
        compiler._start()  # numba compiles a kernel nobody listed (a model option's)
        compiler._end()
    assert told == [(0, 1), (1, 1)]
