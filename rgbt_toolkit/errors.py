"""The project's error classes.

Each derives from the matching built-in so callers can catch either. The CLI turns any :class:`RgbtError` into one
line on stderr and a non-zero exit; messages therefore name the file and say how to fix the problem.
"""

from __future__ import annotations


class RgbtError(Exception):
    """Base class of every error the library raises on purpose."""


class InputError(RgbtError, ValueError):
    """Input data is malformed: a bad box line, mismatched sizes, an unknown layout."""


class FileFormatError(InputError):
    """A file exists but cannot be parsed; the message names the file (and line, where there is one)."""


class MissingFileError(RgbtError, FileNotFoundError):
    """A file or folder the user named does not exist."""


class MissingDependencyError(RgbtError, ImportError):
    """A dependency needed for the requested feature is not installed, or the package's compiled module not built."""


class WeightsError(RgbtError, ValueError):
    """Network weights are missing or do not fit the model."""


class RegistrationError(RgbtError, RuntimeError):
    """Two views could not be registered (no overlap, blank frames); never reported as a good transform.

    ``details`` holds the refused estimate's evidence (coarse z, correlations, agreeing blocks) where there was one,
    so reports and benchmarks can show how close a refusal was.
    """

    def __init__(self, message: str, details: dict | None = None):
        super().__init__(message)
        self.details = dict(details or {})

    def __reduce__(self):  # keep the details across process boundaries (batch jobs run in worker processes)
        return type(self), (str(self), self.details)
