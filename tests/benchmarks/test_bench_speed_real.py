"""`bench_speed_real.py`'s per-round ratio: each round's peer (its better thread setting) against our run of the same
round, so one lucky run of either side does not set the figure."""

from __future__ import annotations

import pytest


def test_each_round_is_compared_with_itself(load_benchmark):
    bench = load_benchmark("bench_speed_real")
    row = {"ours": [10.0, 8.0, 9.0], "peer": {1: [9.0, 9.0, 12.0], 2: [8.0, 10.0, 9.9]}}
    assert bench.round_ratios(row) == pytest.approx([0.8, 9.0 / 8.0, 1.1])
    # the fastest-of ratio pairs the peer's 8.0 (round 1) with our 8.0 (round 2): 1.00, while rounds read 0.8-1.125
