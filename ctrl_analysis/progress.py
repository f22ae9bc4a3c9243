"""Progress bars for long loops: tqdm on stderr, shown only when stderr is a terminal.

A study or runner asks for a bar with :func:`bar` and calls ``update(n)`` as work completes; when
stderr is not a terminal (a log file, a pipe, the test suite) the bar is a silent no-op, so logs
and results stay clean. ``CTRL_ANALYSIS_PROGRESS=1`` forces bars on, ``=0`` forces them off.
"""

from __future__ import annotations

import os
import sys

__all__ = ["NullBar", "bar", "enabled"]


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
    stream = sys.stderr if stream is None else stream
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


class NullBar:
    """The bar used when bars are off: accepts the tqdm calls a loop makes and does nothing."""

    n = 0

    def update(self, n: int = 1) -> None:
        self.n += n

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        return None

    def close(self) -> None:
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
        A tqdm bar on ``stream`` when :func:`enabled`, otherwise a :class:`NullBar`.
    """
    stream = sys.stderr if stream is None else stream
    if not enabled(stream):
        return NullBar()
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, file=stream, leave=False, dynamic_ncols=True)
