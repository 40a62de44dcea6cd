"""Streaming time pairing of two frame streams."""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.io.pairing import pair_by_time


def _stream(fps, n, start=0.0):
    return [(np.full(1, k), start + k / fps) for k in range(n)]


def test_equal_rates_pair_one_to_one():
    pairs = list(pair_by_time(_stream(10, 5), _stream(10, 5)))
    assert [(int(a[0]), int(b[0])) for a, b, _, _ in pairs] == [(k, k) for k in range(5)]


def test_faster_reference_repeats_the_nearest_partner_frame():
    pairs = list(pair_by_time(_stream(30, 30), _stream(10, 10)))
    partner = [int(b[0]) for _, b, _, _ in pairs]
    assert len(pairs) == 30  # the last RGB frame (0.967 s) is within 1.5 intervals of the last thermal one (0.9 s)
    assert partner[:6] == [0, 0, 1, 1, 1, 2]
    assert all(abs(tr - tp) <= 0.05 + 1e-9 for _, _, tr, tp in pairs if tr <= 0.95)


def test_offset_and_a_late_partner_skip_unpaired_frames():
    # thermal started 0.5 s late: its frame 0 shows reference time 0.5
    pairs = list(pair_by_time(_stream(10, 20), _stream(10, 10), offset=0.5))
    assert int(pairs[0][0][0]) == 4 and int(pairs[0][1][0]) == 0  # first pairable reference frame is t=0.4 (gap .15)
    assert int(pairs[-1][0][0]) == 15 and int(pairs[-1][1][0]) == 9
