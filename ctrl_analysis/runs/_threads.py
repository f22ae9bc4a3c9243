"""One BLAS thread per process for the command line, set before numpy loads (imported first by the CLI).

The studies' linear algebra is on small matrices, where OpenBLAS's threads only spin (``reproduce pendulum
--jobs 1`` on a loaded 2-core machine: 54 CPU-s with the default threads, 28 with one), and the command
parallelises over processes (``--jobs``), whose workers inherit the setting. A setting the user made is kept.
``import ctrl_analysis`` loads nothing heavy (its names are imported on first use), so this runs in time.
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
