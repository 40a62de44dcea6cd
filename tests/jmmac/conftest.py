"""Fixtures shared by the tracking-run tests."""

from __future__ import annotations

import pytest


@pytest.fixture
def interrupt_after():
    """``interrupt_after(pairs, n)``: the frame pairs, with a Ctrl-C (KeyboardInterrupt) in place of pair ``n``."""

    def wrap(pairs, n: int):
        for k, item in enumerate(pairs):
            if k == n:
                raise KeyboardInterrupt
            yield item
    return wrap
