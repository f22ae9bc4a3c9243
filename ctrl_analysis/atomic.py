"""Atomic output: a file replaced in one rename, a directory filled in a staging folder and swapped in whole.

An interrupted or failed study leaves its previous complete output untouched; a full disk never
leaves a truncated results.json or REPORT.md.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import tempfile
from pathlib import Path

from ._validate import check_path

__all__ = ["write_text_atomic", "staged_directory"]


@contextlib.contextmanager
def _sigint_deferred():
    """Hold SIGINT (main thread only) while a few renames complete, so they happen together."""
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    except (AttributeError, ValueError, OSError):  # not POSIX / not the main thread
        old = None
    try:
        yield
    finally:
        if old is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_text_atomic(path: Path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically: a temporary file beside it, flushed, then renamed.

    A reader sees the old file or the complete new one, never a truncated one (e.g. on a full disk
    the write fails and the old file stays).

    Parameters
    ----------
    path : str or os.PathLike
        The file (non-empty path; its directory is created).
    text : str
        The whole content.

    Returns
    -------
    pathlib.Path
    """
    path = check_path("path", path)
    if not isinstance(text, str):
        raise TypeError(f"text must be a str, got {type(text).__name__}")
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.chmod(tmp, 0o666 & ~_umask())  # as a plain open() would create it
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return path


@contextlib.contextmanager
def staged_directory(target: Path):
    """Stage a directory's new contents beside it; replace ``target`` only when the block completes.

    Yields a fresh temporary directory in ``target``'s parent. On normal exit the old ``target`` is
    moved aside, the staged directory renamed to ``target`` (SIGINT held during the swap) and the
    old one removed; on any exception (including ``KeyboardInterrupt``) the staged directory is
    removed and ``target`` is untouched. ``target`` is therefore complete or untouched.

    Parameters
    ----------
    target : str or os.PathLike
        The directory to replace (non-empty path).

    Yields
    ------
    pathlib.Path
        The staging directory to write into.
    """
    target = check_path("target", target)
    target.parent.mkdir(parents=True, exist_ok=True)
    staged = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.new-"))
    try:
        os.chmod(staged, 0o777 & ~_umask())  # as a plain mkdir would create it
        yield staged
        for entry in staged.iterdir():  # flush the staged files before they become visible
            if entry.is_file():
                with open(entry, "rb") as fh:
                    os.fsync(fh.fileno())
        with _sigint_deferred():
            old = None
            if target.exists():
                old = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.old-"))
                os.replace(target, old / "dir")
            os.replace(staged, target)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    finally:
        if staged.exists():
            shutil.rmtree(staged, ignore_errors=True)
