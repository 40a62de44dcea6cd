"""SIGTERM handled like Ctrl-C while a command writes its outputs (``kill``, a job scheduler's time limit)."""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Callable, Iterator


@contextlib.contextmanager
def sigterm_raises(make: Callable[[int], BaseException]) -> Iterator[None]:
    """While inside, SIGTERM raises ``make(signum)``, so the clean-up a Ctrl-C gets (complete or removed partial
    files) runs too; the previous handler comes back on the way out. Main thread only, as signals are."""

    def handler(signum, frame):
        raise make(signum)

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
