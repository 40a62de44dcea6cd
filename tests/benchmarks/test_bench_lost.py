"""`bench_lost.py`'s frame costs: tracked and lost frames apart, and each loss's first frame, the costliest (the
whole-frame search has nothing to reuse yet), counted once per loss."""

from __future__ import annotations

from types import SimpleNamespace

import pytest


def test_the_first_frame_of_each_loss_is_counted_apart(load_benchmark):
    bench = load_benchmark("bench_lost")
    ms = [900, 10, 30, 10, 10, 20, 10]  # the first frame trains the model: left out
    present = [True, True, False, False, True, False, True]
    records = [SimpleNamespace(present=p, timings={"appearance": m / 1000, "reacquire": 0.004 * (not p)})
               for m, p in zip(ms, present)]
    costs = bench.frame_costs(records)
    assert (costs["tracked_frames"], costs["lost_frames"], costs["losses"]) == (3, 3, 2)
    assert costs["tracked_ms"] == pytest.approx(10.0)
    assert costs["lost_ms"] == pytest.approx((34 + 14 + 24) / 3)
    assert costs["first_lost_ms"] == pytest.approx((34 + 24) / 2)
    assert costs["reacquire_ms"] == pytest.approx(4.0)
