"""How runs execute across processes: chunks and studies in parallel, a Dask cluster, one shared pool, progress.

:mod:`~ctrl_analysis.runs.parallel` splits a batch or a list of calls into chunks and runs them serially,
in local processes or on Dask (``map_chunks``, ``monte_carlo``, ``sweep``), with the results of one process
bit for bit; :mod:`~ctrl_analysis.runs.cluster` connects to a Dask cluster, makes it process-wide and fails
in bounded time, in one line; :mod:`~ctrl_analysis.runs.taskpool` is the one pool of worker processes a whole
run of the command shares between its studies' drivers, and its trace; :mod:`~ctrl_analysis.runs.chains`
advances chains of maps side by side (a slow one holds no other back) and opens a command's own pool;
:mod:`~ctrl_analysis.runs.progress`
draws progress bars on stderr, only on a terminal; ``_threads`` sets one BLAS thread per process for the
command line, before numpy loads. This ``__init__`` imports none of them (nor numpy, Dask or numba):
import the module you use, e.g. ``from ctrl_analysis.runs.parallel import map_chunks``.
"""
