"""Memory of a batch: the chunks a batch is stepped in, and the limit on what a simulation stores.

A batch whose working arrays exceed :data:`CHUNK_BYTES` is stepped in chunks of runs (each run's
result unchanged); a stored result larger than :data:`RESULT_BYTES` (half the physical memory)
raises a :class:`MemoryError` saying what to change (:func:`check_result_memory`).
"""

from __future__ import annotations

import os

from .._validate import check_int, check_nonnegative, check_positive, check_str

__all__ = ["CHUNK_BYTES", "MAX_CHUNKS", "RESULT_BYTES", "check_result_memory", "chunk_bounds"]



def _physical_memory() -> int:
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - non-POSIX
        return 8 * 2**30


#: Most chunks :func:`chunk_bounds` lists (its list alone would take about 100 MB).
MAX_CHUNKS = 10**6
#: Working memory (bytes) one chunk of a batch may use; larger batches are stepped in chunks.
CHUNK_BYTES = 256 * 2**20
#: Largest stored result (bytes) a runner allocates: half the machine's physical memory.
RESULT_BYTES = _physical_memory() // 2


def chunk_bounds(runs: int, size: int) -> list[tuple[int, int]]:
    """``[(lo, hi), ...]`` splitting ``range(runs)`` into consecutive chunks of at most ``size`` runs.

    Parameters
    ----------
    runs : int
        Batch size (>= 1).
    size : int
        Largest chunk (>= 1).

    Returns
    -------
    list of tuple of int
    """
    runs = check_int("runs", runs, minimum=1)
    size = check_int("size", size, minimum=1)
    if -(-runs // size) > MAX_CHUNKS:
        raise ValueError(f"runs={runs} in chunks of size={size} would make {-(-runs // size)} chunks "
                         f"(at most MAX_CHUNKS = {MAX_CHUNKS}): pass a larger size")
    return [(lo, min(lo + size, runs)) for lo in range(0, runs, size)]


def check_result_memory(nbytes: float, limit: float, where: str) -> None:
    """Raise a :class:`MemoryError` that says what to do when a result would not fit in ``limit`` bytes.

    Parameters
    ----------
    nbytes : float
        Bytes the result would take (>= 0).
    limit : float
        Bytes allowed (> 0).
    where : str
        What would store them, for the message.

    Returns
    -------
    None

    Raises
    ------
    MemoryError
        If ``nbytes > limit``.
    """
    nbytes = check_nonnegative("nbytes", nbytes, scalar=True)
    limit = check_positive("limit", limit, scalar=True)
    where = check_str("where", where)
    if nbytes > limit:
        raise MemoryError(
            f"{where} would store {nbytes / 2**30:.1f} GiB of trajectories (limit {limit / 2**30:.1f} GiB, half "
            f"the physical memory): pass save=Save(states=False, keep=[...]) with fewer signals, or split the "
            f"runs with "
            f"ctrl_analysis.runs.parallel.map_chunks and reduce each chunk to the quantities you need")
