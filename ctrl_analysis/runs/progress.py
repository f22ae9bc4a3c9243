"""Progress bars for long loops: tqdm on stderr, shown only when stderr is a terminal.

A study or runner asks for a bar with :func:`bar` and calls ``update(n)`` as work completes; when
stderr is not a terminal (a log file, a pipe, the test suite) the bar is a silent no-op, so logs
and results stay clean. ``CTRL_ANALYSIS_PROGRESS=1`` forces bars on, ``=0`` forces them off.
"""

from __future__ import annotations

import os
import sys

from .._validate import check_int, check_str

__all__ = ["NullBar", "bar", "enabled", "set_context", "updater", "write"]

# what the CLI sets in each process that runs a study: the label in front of every bar, and the
# terminal line the process's bars use (studies side by side draw on different lines)
_CONTEXT: dict = {"label": "", "position": None}


def set_context(label: str = "", position: int | None = None) -> None:
    """Label (e.g. the study's name) and terminal line of every bar this process shows from now on.

    Parameters
    ----------
    label : str
        Text put in front of every bar's description (``""``: none).
    position : int, optional
        tqdm's ``position`` (the line, counted from the cursor) for this process's bars.
    """
    check_str("label", label, empty=True)
    if position is not None:
        position = check_int("position", position, minimum=0)
    _CONTEXT["label"], _CONTEXT["position"] = label, position


def write(message: str, stream=None) -> None:
    """Write one line to ``stream`` (default stderr) without breaking the bars drawn there.

    Parameters
    ----------
    message : str
    stream : file-like, optional
    """
    check_str("message", message, empty=True)
    stream = _check_stream(stream)
    if enabled(stream):
        from tqdm import tqdm

        tqdm.write(message, file=stream)
    else:
        stream.write(message + "\n")
        stream.flush()


def enabled(stream=None) -> bool:
    """Whether progress bars are shown: ``CTRL_ANALYSIS_PROGRESS`` if set, else whether ``stream`` is a tty.

    Parameters
    ----------
    stream : file-like, optional
        The stream bars are written to (default ``sys.stderr``).

    Returns
    -------
    bool
    """
    forced = os.environ.get("CTRL_ANALYSIS_PROGRESS")
    if forced in ("0", "1"):
        return forced == "1"
    stream = _check_stream(stream)
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def _check_stream(stream):
    """``sys.stderr`` for ``None``, else a writable text stream (anything with ``write``)."""
    if stream is None:
        return sys.stderr
    if not callable(getattr(stream, "write", None)):
        raise TypeError(f"stream must be a writable file-like object (with write()), got {stream!r}")
    return stream


class NullBar:
    """The bar used when bars are off: accepts the tqdm calls a loop makes and does nothing."""

    n = 0

    def update(self, n: int = 1) -> None:
        """Count ``n`` more units (nothing is shown).

        Parameters
        ----------
        n : int
            Units finished.
        """
        self.n += n

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        """Ignore a postfix text (tqdm's signature).

        Parameters
        ----------
        s : str
            The text tqdm would show after the bar.
        refresh : bool
            Whether tqdm would redraw.
        """
        return None

    def close(self) -> None:
        """Do nothing (tqdm's signature)."""
        return None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def bar(total: int | None = None, desc: str = "", unit: str = "it", stream=None):
    """A progress bar over ``total`` units of work (a context manager with ``update(n)``).

    Parameters
    ----------
    total : int, optional
        Units of work (steps, runs, chunks); ``None`` shows a counter only.
    desc : str
        Label shown left of the bar (e.g. the study name).
    unit : str
        Name of one unit.
    stream : file-like, optional
        Where the bar goes (default ``sys.stderr``).

    Returns
    -------
    tqdm.tqdm or NullBar
        A tqdm bar on ``stream`` when :func:`enabled`, otherwise a :class:`NullBar`; labelled and
        positioned as :func:`set_context` said.
    """
    if total is not None:
        total = check_int("total", total, minimum=0)
    check_str("desc", desc, empty=True)
    check_str("unit", unit)
    stream = _check_stream(stream)
    if not enabled(stream):
        return NullBar()
    from tqdm import tqdm

    label = _CONTEXT["label"]
    desc = f"{label}: {desc}" if label and desc else (label or desc)
    return tqdm(total=total, desc=desc, unit=unit, file=stream, leave=False, dynamic_ncols=True,
                position=_CONTEXT["position"], unit_scale=total is not None and total >= 10_000)  # 3.79M, not 3790000


def updater(progress, total: int, desc: str = "", unit: str = "it"):
    """A context manager giving a ``progress(n)`` callable for a long loop, or ``None``.

    Parameters
    ----------
    progress : callable or bool
        A callable is given back unchanged (the caller's own sink); ``True``: a :func:`bar` of
        ``total`` units (a no-op :class:`NullBar` when stderr is not a terminal); ``False``: ``None``.
    total : int
        Units of work of the bar.
    desc, unit : str
        The bar's label and unit.

    Returns
    -------
    contextlib.AbstractContextManager
        Entering it gives the callable (or ``None``); leaving it closes the bar.
    """
    import contextlib

    if not (callable(progress) or isinstance(progress, bool)):
        raise TypeError(f"progress must be a callable progress(n) or a bool, got {progress!r:.80}")
    total = check_int("total", total, minimum=0)
    check_str("desc", desc, empty=True)
    check_str("unit", unit)
    if callable(progress):
        return contextlib.nullcontext(progress)
    if progress is True:
        return _Updating(bar(total, desc=desc, unit=unit))
    return contextlib.nullcontext(None)


class _Updating:
    """Enter a bar, give its ``update``; leave it, close it."""

    def __init__(self, pbar):
        self.pbar = pbar

    def __enter__(self):
        return self.pbar.update

    def __exit__(self, *exc):
        self.pbar.close()
