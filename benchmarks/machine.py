"""One line on what makes a benchmark's boxes and fits differ between machines, printed with its tables.

numpy's OpenBLAS picks its kernels by CPU (SkylakeX on AVX-512, Haswell or Zen elsewhere), and single real clips'
ECO boxes and single pairs' registration follow their rounding where a result is close to a tie
(docs/benchmarks_real.md, "Fold 0 re-run"; docs/benchmarks_registration.md, "Results and the BLAS kernels").
``OPENBLAS_CORETYPE`` chooses them by hand.
"""

from __future__ import annotations

import os
from pathlib import Path


def describe() -> str:
    """``numpy X, OpenCV Y, BLAS kernels: openblas SkylakeX (numpy), ..., N cores``: each loaded BLAS library with
    the package that ships it (numpy, SciPy and OpenCV wheels each bring their own)."""
    import cv2
    import numpy as np
    from threadpoolctl import threadpool_info

    blas = sorted({f"{i.get('internal_api', '?')} {i.get('architecture') or '?'} "
                   f"({Path(i.get('filepath', '?')).parent.name.removesuffix('.libs')})"
                   for i in threadpool_info() if i.get("user_api") == "blas"})
    return (f"numpy {np.__version__}, OpenCV {cv2.__version__}, BLAS kernels: {', '.join(blas) or 'unknown'}, "
            f"{os.cpu_count()} cores")
