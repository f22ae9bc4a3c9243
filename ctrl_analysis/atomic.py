"""Atomic output: a file replaced in one rename, a directory filled in a staging folder and swapped in whole.

An interrupted or failed study leaves its previous complete output untouched; a full disk never
leaves a truncated results.json or REPORT.md. A directory is swapped in with one atomic exchange of
the two names (Linux ``renameat2(RENAME_EXCHANGE)``), so no instant exists at which it is missing;
where the exchange is not available, two renames through a ``.<name>.old-*`` folder that
:func:`recover_staging` restores. Staging folders are named ``.<name>.new-*`` / ``.<name>.old-*``
beside the target; :func:`recover_staging` removes those a killed process left behind.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import signal
import stat
import tempfile
from pathlib import Path

from ._validate import check_path

# new_staging, swap_in, remove_tree, recover_staging and exclusive_lock are the CLI's plumbing (not exported)
__all__ = ["staged_directory", "write_text_atomic"]


@contextlib.contextmanager
def _sigint_deferred():
    """Hold SIGINT and SIGTERM (main thread only) while a few renames complete, so they happen together.

    Blocking the signals in the main thread is not enough: the kernel then delivers a signal sent to the
    process to another thread (OpenBLAS's, a process pool's manager thread), and Python still runs its
    handler in the main thread, inside the block. So the Python-level handlers are replaced for the block by
    one that notes the signal, which is raised again (to the restored handler) when the block ends.
    """
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    except (AttributeError, ValueError, OSError):  # not POSIX / not the main thread
        old = None
    held: list[int] = []
    handlers = {}
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            if signal.getsignal(sig) is not None:  # None: a handler not set from Python, left alone
                handlers[sig] = signal.signal(sig, lambda signum, frame: held.append(signum))
    except ValueError:  # not the main thread: no Python handler runs here anyway
        pass
    try:
        yield
    finally:
        for sig, handler in handlers.items():
            signal.signal(sig, handler)
        if old is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)
        if held:
            signal.raise_signal(held[0])


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


def new_staging(target: Path) -> Path:
    """A fresh, empty staging directory ``.<name>.new-*`` beside ``target``, for :func:`swap_in`.

    Parameters
    ----------
    target : str or os.PathLike
        The directory it will replace (non-empty path; its parent is created).

    Returns
    -------
    pathlib.Path
    """
    target = check_path("target", target)
    target.parent.mkdir(parents=True, exist_ok=True)
    staged = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.new-"))
    os.chmod(staged, 0o777 & ~_umask())  # as a plain mkdir would create it
    return staged


def _exchange(a: Path, b: Path) -> bool:
    """Swap the names ``a`` and ``b`` in one atomic step (Linux renameat2); False where not supported."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd, rename_exchange = -100, 2
    if renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
        return True
    err = ctypes.get_errno()
    import errno

    if err in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), str(a), None, str(b))


def swap_in(staged: Path, target: Path, *, keep_old: bool = False) -> Path | None:
    """Make the complete directory ``staged`` the new ``target``; the old one (if any) is removed.

    The staged files are flushed to disk first. Then ``staged`` and ``target`` are exchanged in one
    atomic rename (SIGINT and SIGTERM held meanwhile) and the old contents removed; ``target`` is
    never missing. A ``target`` that is not a directory is an error: nothing that is not a
    directory is replaced.

    Parameters
    ----------
    staged : str or os.PathLike
        A directory from :func:`new_staging`.
    target : str or os.PathLike
        The directory to replace (or create).
    keep_old : bool
        Leave the previous contents in a hidden folder beside ``target`` and return it, for the caller to
        remove (with :func:`remove_tree`) once it has done what must follow the swap at once.

    Returns
    -------
    Path or None
        With ``keep_old``, the folder holding the previous contents (``None`` if there were none).

    Raises
    ------
    FileExistsError
        If ``target`` exists and is not a directory.
    """
    staged, target = check_path("staged", staged), check_path("target", target)
    if target.is_symlink() or (target.exists() and not target.is_dir()):
        raise FileExistsError(f"{target} exists and is not a directory; it is not replaced")
    for entry in staged.iterdir():  # flush the staged files before they become visible
        if entry.is_file():
            with open(entry, "rb") as fh:
                os.fsync(fh.fileno())
    with _sigint_deferred():
        old = None
        if not target.exists():
            os.replace(staged, target)
        elif _exchange(staged, target):
            old = staged  # now holds the previous contents
        else:  # two renames; recover_staging() puts the old folder back if a kill falls between them
            old = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.old-"))
            os.replace(target, old / "dir")
            os.replace(staged, target)
    if keep_old:
        return old
    if old is not None:
        remove_tree(old)
    return None


def _writable_and_retry(func, path, exc_info):
    """rmtree's error hook: make the parent (and the entry) writable, try once more."""
    parent = os.path.dirname(path)
    with contextlib.suppress(OSError):
        os.chmod(parent, os.stat(parent).st_mode | stat.S_IWUSR | stat.S_IXUSR | stat.S_IRUSR)
    with contextlib.suppress(OSError):
        if os.path.isdir(path) and not os.path.islink(path):
            os.chmod(path, os.stat(path).st_mode | stat.S_IWUSR | stat.S_IXUSR | stat.S_IRUSR)
    func(path)


def remove_tree(path: Path) -> bool:
    """Remove a directory tree the project wrote, also when parts of it were made read-only.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    bool
        Whether it is gone.
    """
    path = check_path("path", path)
    import sys

    hook = {"onexc": lambda func, p, exc: _writable_and_retry(func, p, None)} if sys.version_info >= (3, 12) \
        else {"onerror": _writable_and_retry}
    with contextlib.suppress(OSError):
        shutil.rmtree(path, **hook)
    return not os.path.lexists(path)


def recover_staging(parent: Path, names) -> list[str]:
    """Repair what a killed run left in ``parent``: put back a half-swapped ``<name>``, remove staging folders.

    For each name: a ``.<name>.old-*/dir`` whose ``<name>`` is missing (a kill between the two
    renames of the fallback swap) is renamed back to ``<name>``; then every ``.<name>.new-*`` and
    ``.<name>.old-*`` directory is removed. Call it only while no other process writes into
    ``parent`` (the CLI holds the output folder's lock). Nothing else is touched.

    Parameters
    ----------
    parent : str or os.PathLike
        The output folder.
    names : iterable of str
        The directory names staged there (the study names).

    Returns
    -------
    list of str
        What was restored or removed, for a message.
    """
    parent = check_path("parent", parent)
    done = []
    for name in names:
        pattern = re.compile(rf"^\.{re.escape(name)}\.(new|old)-[A-Za-z0-9_]+$")
        leftovers = sorted(p for p in parent.iterdir() if pattern.match(p.name) and p.is_dir()
                           and not p.is_symlink()) if parent.is_dir() else []
        target = parent / name
        for p in leftovers:
            if not os.path.lexists(target) and p.name.startswith(f".{name}.old-") and (p / "dir").is_dir():
                os.replace(p / "dir", target)
                done.append(f"restored {name}")
        for p in leftovers:
            if remove_tree(p):
                done.append(f"removed {p.name}")
    return done


@contextlib.contextmanager
def staged_directory(target: Path):
    """Stage a directory's new contents beside it; replace ``target`` only when the block completes.

    Yields a fresh temporary directory in ``target``'s parent (:func:`new_staging`). On normal exit
    it replaces ``target`` (:func:`swap_in`: one atomic exchange, SIGINT held); on any exception
    (including ``KeyboardInterrupt``) the staged directory is removed and ``target`` is untouched.
    ``target`` is therefore complete or untouched.

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
    staged = new_staging(target)
    try:
        yield staged
        swap_in(staged, target)
    finally:
        if os.path.lexists(staged):
            remove_tree(staged)


class LockedError(RuntimeError):
    """Another process holds the lock of :func:`exclusive_lock`; the message says which and what to do."""


@contextlib.contextmanager
def exclusive_lock(path: Path, what: str = "this folder"):
    """Hold an exclusive lock on the file ``path`` while the block runs, or fail at once.

    ``flock`` on the lock file: the kernel releases it when the holder dies, even by ``kill -9``
    (local worker processes die with their parent, so none keeps it). The holder's pid is written
    into the file for the message; the file is removed on exit.

    Parameters
    ----------
    path : str or os.PathLike
        The lock file (created if needed).
    what : str
        What the lock protects, for the message.

    Yields
    ------
    None

    Raises
    ------
    LockedError
        If another process holds it.
    """
    import fcntl

    path = check_path("path", path)
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            try:
                holder = os.pread(fd, 32, 0).decode("ascii", "replace").strip() or "unknown"
            finally:
                os.close(fd)
            raise LockedError(f"another ctrl-analysis run (pid {holder}) is writing into {what}; wait for it to "
                              f"finish or choose another --out") from None
        try:  # the file may have been removed by the previous holder between our open and our lock
            same = os.stat(path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield
    finally:
        with contextlib.suppress(OSError):
            os.unlink(path)
        os.close(fd)
