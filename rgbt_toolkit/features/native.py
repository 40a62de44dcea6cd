"""The compiled feature loops (``_kernels.c``, built by ``pip install``), with a clear error when they are missing.

A source tree that was copied rather than installed has no compiled module; without this the first ECO import would
end in a bare ``ImportError`` traceback instead of saying what to run.
"""

from __future__ import annotations

from rgbt_toolkit.errors import MissingDependencyError

try:
    from rgbt_toolkit.features import _kernels as kernels
except ImportError as exc:  # the extension was not built for this interpreter
    raise MissingDependencyError(
        f"rgbt_toolkit's compiled module rgbt_toolkit/features/_kernels.c is not built for this Python ({exc}); "
        "reinstall the package (pip install -c constraints.txt -e .), which needs a C compiler and the Python "
        "headers") from None

__all__ = ["kernels"]
