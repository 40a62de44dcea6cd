"""Pair two timestamped frame streams in time, streaming (constant memory).

Cameras in a rig run at different rates and start at different moments. For every frame of the reference stream
the partner stream's frame nearest in time is taken (after shifting the partner's clock by ``offset``), so a 30 fps
RGB video pairs with a 9 fps thermal one without loading either.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator

import numpy as np

Timed = tuple[np.ndarray, float]


def pair_by_time(reference: Iterable[Timed], partner: Iterable[Timed], offset: float = 0.0,
                 max_gap: float | None = None) -> Iterator[tuple[np.ndarray, np.ndarray, float, float]]:
    """Yield ``(ref_frame, partner_frame, t_ref, t_partner)`` with the partner frame nearest to ``t_ref``.

    ``offset`` is added to partner timestamps to bring them onto the reference clock (a thermal camera that started
    0.2 s late has offset +0.2). Reference frames further than ``max_gap`` seconds from any partner frame (before the
    partner starts, after it ends) are skipped; the default gap is one and a half partner frame intervals.
    """
    partner_iter = iter(partner)
    current = next(partner_iter, None)
    if current is None:
        return
    upcoming = next(partner_iter, None)
    interval = (upcoming[1] - current[1]) if upcoming is not None else 0.0
    gap = max_gap if max_gap is not None else max(1.5 * interval, 1e-3)
    for ref_frame, t_ref in reference:
        while upcoming is not None and upcoming[1] + offset <= t_ref:
            current, upcoming = upcoming, next(partner_iter, None)
        best = current
        if upcoming is not None and abs(upcoming[1] + offset - t_ref) < abs(current[1] + offset - t_ref):
            best = upcoming
        if abs(best[1] + offset - t_ref) > gap:
            if upcoming is None and best[1] + offset < t_ref:
                return  # the partner stream has ended
            continue
        yield ref_frame, best[0], t_ref, best[1]
