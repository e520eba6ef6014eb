"""cloudcore: the cloudview engine.

Model, shading, LOD policy and statistics are plain numpy; only the `gl`
sub-package touches OpenGL.

OpenBLAS runs numpy's matrix products on a thread per core, and its threads
spin for cores that llvmpipe's rasteriser threads hold while a frame draws:
the frustum test of the default scene's 90,000 splats, a (90000, 3) @ (3, 6)
product, took 40 ms so against 0.6 ms on one thread.  Every product here is
that skinny, so BLAS gets one thread, whether numpy is loaded yet (the
environment variables, read as each BLAS library loads) or already
(threadpoolctl).
"""

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import numpy  # noqa: E402  (after the variables, so that its BLAS reads them)
from threadpoolctl import threadpool_limits  # noqa: E402

threadpool_limits(limits=1, user_api="blas")
del numpy
