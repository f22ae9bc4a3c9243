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
from hang import limit

from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.blocks import DiscreteBlock
from ctrl_analysis.engine.jit import cacheable, source_key
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
        res = {e: loop.simulate(3, inputs={"u": 1.0}, execution=Execution(engine=e)) for e in ("numpy", "compiled")}
        np.testing.assert_array_equal(res["compiled"].x, res["numpy"].x)
        ys.append(res["compiled"].x[-1, 0, 0])
    # three steps of 1 (gain v, a = p[0] = 1), then of 2 (gain 2v, or a = p[1] = 2); a stale runner gives 3 again
    assert ys == [3.0, 6.0]


EXECD = """
import numpy as np
from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.blocks import DiscreteBlock
from ctrl_analysis.engine.kernels import KernelBlock, Kernels, Layout
from ctrl_analysis.engine.loop import Loop, place

SRC = '''
import numpy as np
from ctrl_analysis.engine.kernels import Layout, jitable

AT = Layout("rate", "T").at


@jitable
def output(t, x, u, p, y):
    step = p[AT.rate] * p[AT.T]
    y[0] = x[0] + np.minimum(np.maximum(u[0] - x[0], -step), step)


def update(t, x, u, p, x_next):
    output(t, x, u, p, x_next)
'''
ns = {"__name__": "not_a_module"}
exec(compile(SRC, "<cell>", "exec"), ns)


class Acc(KernelBlock, DiscreteBlock):
    inputs, outputs, states = ("u",), ("y",), ("y",)
    kernels = Kernels(update=ns["update"])

    def __init__(self):
        self.kernel_params = np.array([2.0, 1.0])  # rate 2, T 1


loop = Loop([place(Acc(), "acc")], dt=1.0)
print(loop.simulate(3, inputs={"u": 10.0}, execution=Execution(engine="compiled")).x[-1, 0, 0])  # 2, 4, 6
"""


def test_a_kernel_without_a_module_file_is_not_disk_cached(tmp_path):
    """An exec'd kernel (a notebook cell, a doctest) has no module numba can re-import: its runner is compiled
    in each process, not cached (the second process failed with ``No module named '<dynamic>'``)."""
    import os
    import subprocess

    ns = {"__name__": "not_a_module"}
    exec(compile("def f(t, x, u, p, out):\n    out[0] = 1.0\n", "<cell>", "exec"), ns)  # noqa: S102
    assert not cacheable([ns["f"]]) and cacheable([source_key])
    env = dict(os.environ, CTRL_ANALYSIS_CACHE=str(tmp_path / "cache"))
    for _ in range(2):  # the second process meets whatever the first left in the cache
        out = subprocess.run([sys.executable, "-c", EXECD], env=env, capture_output=True, text=True, timeout=limit(300))
        assert out.returncode == 0, out.stderr[-2000:]
        assert out.stdout.split()[-1] == "6.0"


MOVED = """
import importlib, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
mod = importlib.import_module(sys.argv[2])
from ctrl_analysis.engine import Execution
from ctrl_analysis.engine.blocks import DiscreteBlock
from ctrl_analysis.engine.kernels import KernelBlock, Kernels
from ctrl_analysis.engine.loop import Loop, place


class Acc(KernelBlock, DiscreteBlock):
    inputs, outputs, states = ("u",), ("y",), ("y",)
    kernels = Kernels(update=mod.update)

    def __init__(self):
        self.kernel_params = np.array([1.0])


print(Loop([place(Acc(), "acc")], dt=1.0).simulate(3, inputs={"u": 1.0},
                                                   execution=Execution(engine="compiled")).x[-1, 0, 0])
"""


def test_a_kernel_moved_to_another_module_does_not_load_the_old_modules_runner(tmp_path):
    """Same source, another module (a package reorganised): the cached runner named the old module, which numba
    re-imported and failed on (``No module named ...``); the module is part of the runner's key now."""
    import os
    import subprocess

    env = dict(os.environ, CTRL_ANALYSIS_CACHE=str(tmp_path / "cache"))
    text = textwrap.dedent(MODULE.format(helper="v", fields='"a"'))
    for name in ("kmod_before_move", "kmod_after_move"):
        (tmp_path / f"{name}.py").write_text(text)
        out = subprocess.run([sys.executable, "-c", MOVED, str(tmp_path), name], env=env, capture_output=True,
                             text=True, timeout=limit(300))
        (tmp_path / f"{name}.py").unlink()  # moved away: the old module no longer exists
        assert out.returncode == 0, out.stderr[-2000:]
        assert out.stdout.split()[-1] == "3.0"
