"""Progress bars: tqdm on a terminal, nothing when stderr is piped.

tqdm's own ``disable=None`` makes the same choice, but importing tqdm costs about 30 ms, which a piped run (a script,
a benchmark, CI) would pay for a bar it never shows; that is part of `rgbt track`'s start-up.
"""

from __future__ import annotations

import sys


class _Silent:
    """The parts of a tqdm bar the commands use, doing nothing but pass messages on."""

    def update(self, n: int = 1) -> None:
        pass

    def write(self, message: str, file=None) -> None:
        print(message, file=file or sys.stderr)

    def close(self) -> None:
        pass

    def __enter__(self) -> "_Silent":
        return self

    def __exit__(self, *exc) -> None:
        pass


def progress_bar(**options):
    """A tqdm bar (``options`` as tqdm's) on stderr when it is a terminal, else a silent stand-in."""
    if not sys.stderr.isatty():
        return _Silent()
    from tqdm import tqdm

    return tqdm(disable=None, file=sys.stderr, **options)


def progress_items(items, **options):
    """``items`` as they are, or wrapped in a tqdm bar (``options`` as tqdm's) when stderr is a terminal."""
    return progress_bar(iterable=items, **options) if sys.stderr.isatty() else items
