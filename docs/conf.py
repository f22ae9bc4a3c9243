"""Sphinx configuration of the ctrl-analysis API documentation.

Build (from the repository root)::

    pip install '.[docs]' && python -m sphinx -W -b html docs docs/_build/html

The pages are written by hand, one per family of building blocks; the API of each module comes
from its numpydoc docstrings through ``autodoc`` + ``numpydoc``. Modules still being written on
other branches keep their ``.. automodule::`` directive in the pages; while such a module does
not exist, :func:`_skip_missing_modules` replaces the directive by a note, so the build stays
warning-free (``-W``) before and after the merge.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

project = "ctrl-analysis"
author = "ctrl-analysis contributors"
copyright = "ctrl-analysis contributors"
release = version = "0.1.0"

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
]

exclude_patterns = ["_build"]
html_theme = "alabaster"
html_theme_options = {"description": "Five control papers as tested python-control building blocks",
                      "page_width": "1100px", "sidebar_width": "240px"}

# autodoc: members in source order; the library's own docstrings, never inherited ones twice
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_typehints = "none"  # the numpydoc Parameters section carries the types
autodoc_mock_imports = []

# numpydoc: no autosummary member tables (they would need stub pages), no validation at build
# time (tests/lib/test_docstrings.py checks the sections)
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
# numpydoc loads autosummary; its generator scans the pages for automodule directives before the
# hook below runs (and would fail on the planned modules); the pages need no generated stubs
autosummary_generate = False

#: Modules the pages document that are being written on other branches (issue 14): a missing one
#: is shown as a note instead of failing the build.
PLANNED_MODULES = (
    "ctrl_analysis.estimators.kalman.ikf",
    "ctrl_analysis.estimators.kalman.ckf",
    "ctrl_analysis.controllers.mfac",
    "ctrl_analysis.controllers.golden_section",
    "ctrl_analysis.controllers.fuzzy",
)


def _module_exists(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is not None
    except ModuleNotFoundError:
        return False


def _skip_missing_modules(app, docname, source):
    """Replace ``.. automodule::`` of a planned module that does not exist yet by a note."""
    text = source[0]
    for name in PLANNED_MODULES:
        if _module_exists(name):
            continue
        pattern = re.compile(rf"^\.\. automodule:: {re.escape(name)}[ \t]*\n(?:[ \t]+:.*\n)*", re.MULTILINE)
        note = (f".. note::\n\n   ``{name}`` is not part of this build yet (it is being written on "
                f"another branch); its API appears here once it is merged.\n")
        text = pattern.sub(note, text)
    source[0] = text


#: Docstrings in files being edited on other branches that docutils cannot parse, with the
#: literal markup that fixes them at build time. Remove an entry once the docstring is fixed at
#: its source (``|a| / |b|`` reads as a substitution reference in reStructuredText).
DOCSTRING_FIXES = {
    "ctrl_analysis.reporting.report.relative_error": [("|value - paper| / |paper|", "``|value - paper| / |paper|``")],
}


def _fix_docstrings(app, what, name, obj, options, lines):
    """Apply :data:`DOCSTRING_FIXES` to the docstring of ``name`` (in place, as autodoc expects)."""
    for old, new in DOCSTRING_FIXES.get(name, ()):
        lines[:] = [line.replace(old, new) for line in lines]


def setup(app):
    """Register the hooks: skip planned modules not written yet, patch known docstring markup."""
    app.connect("source-read", _skip_missing_modules)
    app.connect("autodoc-process-docstring", _fix_docstrings)
