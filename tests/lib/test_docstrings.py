"""Every public name of ``ctrl_analysis`` has a numpydoc docstring: summary, Parameters, Returns.

"Public" is everything in a module's ``__all__`` (every module of the package, private modules
such as ``_validate`` included, since their names are used across the library), plus the public
methods a public class defines itself. For each of them:

* the docstring exists and opens with a one-line summary (a non-empty first line followed by a
  blank line or nothing);
* a function or method that takes arguments beyond ``self``/``cls`` has a ``Parameters`` section;
  a class that takes constructor arguments has one in its own docstring or its ``__init__``'s
  (for a dataclass an ``Attributes`` section also counts: its fields are its arguments);
* a function or method that returns something (a ``return <value>`` in its body, or a return
  annotation other than ``None``) has a ``Returns`` (or ``Yields``) section; classes do not.

Properties need only the summary (numpydoc documents them as attributes). Constants in
``__all__`` (sympy symbols, dicts) cannot carry their own docstrings and are not checked. A method
without a docstring inherits its base class's (``inspect.getdoc``), as autodoc shows it.

The check is the standard library plus :mod:`inspect`, no numpydoc needed; every offender is
collected and printed, not just the first.
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import pkgutil
import re
import textwrap
import warnings

import ctrl_analysis

#: Names (``module.qualname`` where the object is defined) whose docstrings are known to be
#: incomplete. Empty: every public name is documented; nothing may be added here, fix the docstring.
KNOWN_INCOMPLETE: set = set()

_SECTION = re.compile(r"^(\w[\w ]*)\n[ \t]*-{3,}[ \t]*$", re.MULTILINE)


def _modules():
    """Every module of the package, imported."""
    yield ctrl_analysis
    for info in pkgutil.walk_packages(ctrl_analysis.__path__, "ctrl_analysis."):
        yield importlib.import_module(info.name)


def _sections(doc: str) -> set[str]:
    return {m.group(1).strip() for m in _SECTION.finditer(doc)}


def _returns_value(fn) -> bool:
    """True when ``fn`` returns a value: a non-None return annotation or a ``return <value>``."""
    ann = inspect.signature(fn).return_annotation
    if ann is not inspect.Signature.empty:
        return ann not in (None, "None")
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(fn)))
    except (OSError, TypeError, SyntaxError):
        return False
    body = tree.body[0]
    stack = list(getattr(body, "body", []))
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
            continue  # a nested definition's returns are not ours
        if isinstance(node, ast.Return) and node.value is not None and not (
                isinstance(node.value, ast.Constant) and node.value.value is None):
            return True
        if isinstance(node, (ast.Yield, ast.YieldFrom)):
            return True
        stack.extend(ast.iter_child_nodes(node))
    return False


def _takes_arguments(fn, *, bound: bool) -> bool:
    try:
        params = list(inspect.signature(fn).parameters)
    except (TypeError, ValueError):
        return False
    return len(params) > (1 if bound else 0)


def _summary_problem(doc: str | None) -> str | None:
    if not doc or not doc.strip():
        return "no docstring"
    lines = doc.splitlines()
    if not lines[0].strip():
        return "no one-line summary (first line empty)"
    if len(lines) > 1 and lines[1].strip():
        return "summary is not one line (second line not blank)"
    return None


def _check_routine(fn, doc, *, bound: bool) -> list[str]:
    problems = []
    summary = _summary_problem(doc)
    if summary:
        return [summary]
    sections = _sections(doc)
    if _takes_arguments(fn, bound=bound) and "Parameters" not in sections:
        problems.append("no Parameters section")
    if _returns_value(fn) and not sections & {"Returns", "Yields"}:
        problems.append("no Returns section")
    return problems


def _own_init(cls):
    """The ``__init__`` that builds ``cls`` when a class of this package defines it, else None."""
    for klass in cls.__mro__:
        if "__init__" in vars(klass):
            return vars(klass)["__init__"] if klass.__module__.startswith("ctrl_analysis") else None
    return None


def _check_class(cls) -> list[str]:
    doc = inspect.getdoc(cls)
    summary = _summary_problem(doc)
    if summary:
        return [summary]
    init = _own_init(cls)
    if init is not None and _takes_arguments(init, bound=True):
        init_doc = init.__doc__ and inspect.cleandoc(init.__doc__)
        accepted = {"Parameters", "Attributes"} if dataclasses.is_dataclass(cls) else {"Parameters"}
        if not accepted & (_sections(doc) | _sections(init_doc or "")):
            return ["no Parameters section"]
    return []


def _check_members(cls) -> dict[str, list[str]]:
    """Problems of the public methods and properties ``cls`` defines itself."""
    found = {}
    for name, raw in vars(cls).items():
        if name.startswith("_"):
            continue
        where = f"{cls.__module__}.{cls.__qualname__}.{name}"
        if isinstance(raw, property):
            problem = _summary_problem(inspect.getdoc(raw) or _inherited_doc(cls, name))
            if problem:
                found[where] = [problem]
            continue
        if isinstance(raw, (staticmethod, classmethod)):
            fn, bound = raw.__func__, isinstance(raw, classmethod)
        elif inspect.isfunction(raw):
            fn, bound = raw, True
        else:
            continue
        doc = inspect.getdoc(getattr(cls, name))
        problems = _check_routine(fn, doc, bound=bound)
        if problems:
            found[where] = problems
    return found


def _inherited_doc(cls, name):
    for klass in cls.__mro__[1:]:
        if name in vars(klass) and getattr(vars(klass)[name], "__doc__", None):
            return inspect.cleandoc(vars(klass)[name].__doc__)
    return None


def collect_offenders() -> dict[str, list[str]]:
    """``{"module.qualname": [problem, ...]}`` for every public name of the package."""
    offenders, seen = {}, set()
    for module in _modules():
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if id(obj) in seen:
                continue  # re-exported: checked where it is defined
            seen.add(id(obj))
            where = f"{getattr(obj, '__module__', module.__name__)}.{getattr(obj, '__qualname__', name)}"
            if inspect.isclass(obj):
                problems = _check_class(obj)
                offenders.update(_check_members(obj))
            elif inspect.isfunction(obj):
                problems = _check_routine(obj, inspect.getdoc(obj), bound=False)
            else:
                continue  # a constant: no docstring of its own
            if problems:
                offenders[where] = problems
    return offenders


def test_every_public_name_has_a_numpydoc_docstring():
    offenders = collect_offenders()
    stale = sorted(set(KNOWN_INCOMPLETE) - set(offenders))
    if stale:
        warnings.warn(f"KNOWN_INCOMPLETE entries now complete or gone, remove them: {stale}", stacklevel=1)
    new = {k: v for k, v in sorted(offenders.items()) if k not in KNOWN_INCOMPLETE}
    report = "\n".join(f"  {name}: {', '.join(problems)}" for name, problems in new.items())
    print(report)
    assert not new, f"{len(new)} public names lack a numpydoc docstring part:\n{report}"


def test_the_check_finds_what_it_should():
    def documented(a, b=1):
        """Add.

        Parameters
        ----------
        a, b : float

        Returns
        -------
        float
        """
        return a + b

    def no_returns(a):
        """Add one.

        Parameters
        ----------
        a : float
        """
        return a + 1

    def two_line_summary(a) -> None:
        """Add one
        to a.

        Parameters
        ----------
        a : float
        """

    def no_parameters(a) -> None:
        """Do nothing."""

    def nested_return_only(a):
        """Define a helper.

        Parameters
        ----------
        a : float
        """
        def helper():
            return a

    def check(fn):
        return _check_routine(fn, inspect.getdoc(fn), bound=False)

    assert check(documented) == []
    assert check(no_returns) == ["no Returns section"]
    assert check(two_line_summary) == ["summary is not one line (second line not blank)"]
    assert check(no_parameters) == ["no Parameters section"]
    assert check(nested_return_only) == []
    assert check(lambda: None) == ["no docstring"]
