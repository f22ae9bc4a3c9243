"""The compiled runner's disk cache is keyed on everything a kernel reads, not only on the kernel's own source.

Two modules whose kernels are the same text but whose helper (or ``Layout`` offsets) differ must give two
runners: with the kernels' sources alone as the key, the second loop loaded the first one's compiled
runner from numba's disk cache and returned its numbers.
"""

import importlib.util
import sys
import textwrap

import numpy as np
import pytest

from ctrl_analysis.engine.blocks import DiscreteBlock
from ctrl_analysis.engine.jit import source_key
from ctrl_analysis.engine.kernels import KernelBlock, Kernels
from ctrl_analysis.engine.loop import Loop, place

MODULE = """
from ctrl_analysis.engine.kernels import Layout, jitable

LAYOUT = Layout({fields})
AT = LAYOUT.at


@jitable
def gain(v):
    return {helper}


def update(t, x, u, p, x_next):
    x_next[0] = x[0] + gain(u[0]) * p[AT.a]
"""


def _module(tmp_path, name, helper, fields='"a"'):
    path = tmp_path / f"{name}.py"
    path.write_text(textwrap.dedent(MODULE.format(helper=helper, fields=fields)))
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


def _block(mod):
    class Acc(KernelBlock, DiscreteBlock):
        inputs, outputs, states = ("u",), ("y",), ("y",)
        kernels = Kernels(update=mod.update)

        def __init__(self):
            self.kernel_params = np.arange(1.0, mod.LAYOUT.size + 1.0)  # p[AT.a] is 1 or 2

    return Acc()


@pytest.mark.parametrize(("second", "fields"), [("2.0 * v", '"a"'), ("v", '"z", "a"')],
                         ids=["helper-changed", "offsets-changed"])
def test_a_changed_helper_or_layout_gives_its_own_runner(tmp_path, monkeypatch, second, fields):
    monkeypatch.setenv("CTRL_ANALYSIS_CACHE", str(tmp_path / "cache"))
    first = _module(tmp_path, f"kmod_first_{tmp_path.name}", "v")
    other = _module(tmp_path, f"kmod_second_{tmp_path.name}", second, fields)
    assert source_key(first.update) != source_key(other.update)
    ys = []
    for mod in (first, other):
        loop = Loop([place(_block(mod), "acc")], dt=1.0)
        res = {e: loop.simulate(3, inputs={"u": 1.0}, engine=e) for e in ("numpy", "compiled")}
        np.testing.assert_array_equal(res["compiled"].x, res["numpy"].x)
        ys.append(res["compiled"].x[-1, 0, 0])
    # three steps of 1 (gain v, a = p[0] = 1), then of 2 (gain 2v, or a = p[1] = 2); a stale runner gives 3 again
    assert ys == [3.0, 6.0]
