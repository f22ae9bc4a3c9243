"""Imported by each worker of a ``"local"`` Dask cluster as it starts (``preload``): the library's heavy imports.

A local cluster's workers are fresh processes (spawned, not forked), so each would import numpy, SciPy,
python-control, numba and the engine on its first chunk, about 1.5 s; started in the background
(:func:`ctrl_analysis.runs.cluster.use_cluster`), they do it while the driver does its serial start.
"""

import control  # noqa: F401
import numba  # noqa: F401
import numpy  # noqa: F401
import scipy.signal  # noqa: F401

import ctrl_analysis.engine.compiled  # noqa: F401
import ctrl_analysis.engine.loop  # noqa: F401
