"""The user guide's recipes (docs/guide.rst) run and do what they say: each ends with its own asserts."""

import re
import textwrap
from pathlib import Path

import pytest

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "guide.rst"


def _recipes():
    text = GUIDE.read_text(encoding="utf-8")
    blocks = re.findall(r"\.\. code-block:: python\n\n((?:   .*\n|\n)+)", text)
    return [textwrap.dedent(b) for b in blocks]


#: The recipes, in the order of the page.
RECIPES = ["eso_monte_carlo", "kernel_block_params", "sampled_pid_on_continuous_plant", "mfac",
           "ikf_mfac_choosing_q_and_r", "kalman_dlqe", "ckf_online_identification", "fuzzy_pd", "nlsys"]


def test_the_guide_has_nine_recipes_each_checking_its_result():
    recipes = _recipes()
    assert len(recipes) == len(RECIPES) == 9
    assert all("assert" in r for r in recipes)


@pytest.mark.filterwarnings("error:compiled engine unavailable")  # a user block in a notebook cell compiles too
@pytest.mark.parametrize("index", range(len(RECIPES)), ids=RECIPES)
def test_recipe_runs(index):
    code = _recipes()[index]
    exec(compile(code, f"docs/guide.rst (recipe {index + 1})", "exec"), {"__name__": "guide_recipe"})  # noqa: S102
