"""Loading the compiled modules (built from ``.c`` files by ``pip install``), with a clear error when one is missing.

A source tree that was copied rather than installed has no compiled modules; without this the first ECO import would
end in a bare ``ImportError`` traceback instead of saying what to run.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from rgbt_toolkit.errors import MissingDependencyError


def load_compiled(name: str) -> ModuleType:
    """Import the compiled module ``name`` (e.g. ``rgbt_toolkit.eco._spectra``) or say how to build it."""
    try:
        return importlib.import_module(name)
    except ImportError as exc:  # the extension was not built for this interpreter
        source = name.replace(".", "/") + ".c"
        raise MissingDependencyError(
            f"rgbt_toolkit's compiled module {source} is not built for this Python ({exc}); reinstall the package "
            "(pip install -c constraints.txt -e .), which needs a C compiler and the Python headers") from None
