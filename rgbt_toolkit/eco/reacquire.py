"""Losing and finding the target again: a watchdog on ECO's peak score and a whole-frame search.

ECO only searches around its last position, so after a shot cut, a gimbal jump or a long occlusion it keeps
learning whatever lies there. This module decides when the result is unreliable (the peak stays far below its usual
value for a few frames), stops the model updates (the caller keeps the old model), and looks for the target over the
whole frame: candidates from normalised cross-correlation with the target's appearance (plus the warmest blobs on a
thermal frame), each verified by the tracker's own filter before the tracker moves there.
"""

from __future__ import annotations

from collections import deque
from concurrent.futures import Executor
from dataclasses import dataclass
from typing import NamedTuple

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.images import block_mean


@dataclass(frozen=True)
class ReacquireParams:
    """When the target counts as lost and what it takes to find it (tuned on the real tuning clips)."""

    lost_ratio: float = 0.4      # a peak below this x the median peak of confident frames is a weak frame
    patience: int = 3            # this many weak frames in a row: lost
    found_ratio: float = 0.7     # a candidate's verified peak must reach this x the median confident peak
    # ...or, when it stands out among the candidates (peak >= distinct_margin x that of every other candidate more
    # than one target size away), this lower share. A filter that learned the background before it lost the target
    # gives the target itself a modest peak, but the other places score lower still (svan_ir_bird_003, ECO-deep:
    # the bird 0.34-0.51 against 0.17-0.24 elsewhere, while 0.7x its usual peak was 0.57). A margin of 1.5 took a
    # wrong candidate at the frame's corner on svan_ir_bird_005 (docs/eco.md, "Re-acquisition after loss")
    distinct_ratio: float = 0.5
    distinct_margin: float = 2.0
    history: int = 30            # confident peaks kept for the median
    candidates: int = 4          # whole-frame candidates verified per frame while lost
    warm_blobs: bool = True      # on grey (thermal) frames also try the warmest blobs
    # Candidates verified per frame while lost (0: all). Each verification is a full appearance step (two ECO
    # searches in JMMAC), so verifying all 8 cost 190 ms/frame while lost; with a budget the best ones are looked at
    # every frame and the rest in turn on the following frames (near-duplicates are dropped first).
    verify_budget: int = 0
    # Candidates verified on the first search of a loss (0: verify_budget). That frame has already run a tracked
    # frame's full appearance step (the target is declared lost after it), and none of its candidates has an earlier
    # answer to reuse, so it is the costliest frame of a loss; its strongest candidates are looked at there, the rest
    # on the next frames.
    first_budget: int = 0
    # The whole-frame search runs on frames shrunk by a whole factor that leaves the template's smaller side at least
    # this many pixels (never enlarged); its candidates are verified at full size by the tracker's filter, which finds
    # the peak itself, so a candidate only has to land near the target. On the generated 1080p leave_view scene
    # (working scale 0.39, a 37x104 px template) the search was about a third of the 34 ms a lost frame spent
    # re-acquiring (`python benchmarks/bench_lost.py`, profiled with pyinstrument), the verifications the rest.
    match_side: int = 16
    # While lost no model learns, so a candidate's verification gives the same answer as long as the pixels around
    # it stay the same: a candidate at the very place (the same cell of the shrunk frame) of one verified at most
    # `reuse_frames` searches ago, whose template-sized patch of the shrunk grey frame changed by at most
    # `reuse_change` grey levels (mean absolute difference), keeps that answer - if it was one that could not be
    # taken (below distinct_ratio x the usual peak). A promising or moving candidate is verified every time: with a
    # quarter of the target size as "the same place" and any answer reused, svan_ir_bird_003's bird (moving 1 px a
    # frame against the sky, its answer rising from 0.65 to 0.73) was found 26 frames late (bench_real JMMAC 39.8
    # -> 33.6).
    reuse_frames: int = 15
    reuse_change: float = 6.0

    def __post_init__(self) -> None:
        if not 0 < self.lost_ratio < self.found_ratio:
            raise InputError(f"reacquire: need 0 < lost_ratio < found_ratio, got {self.lost_ratio}, "
                             f"{self.found_ratio}")
        if not self.lost_ratio < self.distinct_ratio <= self.found_ratio or self.distinct_margin < 1:
            raise InputError(f"reacquire: need lost_ratio < distinct_ratio <= found_ratio and distinct_margin >= 1, "
                             f"got {self.distinct_ratio}, {self.distinct_margin}")
        if self.patience < 1 or self.history < 1 or self.candidates < 1:
            raise InputError("reacquire: patience, history and candidates must be at least 1")
        if self.verify_budget < 0 or self.first_budget < 0:
            raise InputError(f"reacquire: verify_budget and first_budget must be 0 or positive, got "
                             f"{self.verify_budget}, {self.first_budget}")
        if self.match_side < 4 or self.reuse_frames < 0 or self.reuse_change < 0:
            raise InputError(f"reacquire: need match_side >= 4 and reuse_frames, reuse_change >= 0, got "
                             f"{self.match_side}, {self.reuse_frames}, {self.reuse_change}")


def _grey(frame: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY) if frame.ndim == 3 else frame


def _crop(grey: np.ndarray, box: np.ndarray) -> np.ndarray | None:
    h, w = grey.shape
    x0, y0 = int(round(max(box[0], 0))), int(round(max(box[1], 0)))
    x1, y1 = int(round(min(box[0] + box[2], w))), int(round(min(box[1] + box[3], h)))
    if x1 - x0 < 3 or y1 - y0 < 3:
        return None
    return grey[y0:y1, x0:x1].copy()


def shrink_factor(template_hw: tuple[int, int], match_side: int) -> int:
    """The whole factor frames are shrunk by for the whole-frame search: the largest that leaves the template's
    smaller side at least ``match_side`` pixels (1: full size)."""
    return max(1, int(min(template_hw) // match_side))


def to_full(point: np.ndarray, k: int) -> np.ndarray:
    """A position ``[x, y]`` on a frame shrunk by :func:`block_mean` in full-size pixels (block k covers pixels
    k*i .. k*i + k - 1, centred at k*i + (k - 1) / 2)."""
    return np.asarray(point, float) * k + (k - 1) / 2


def local_maxima(score: np.ndarray, size: tuple[int, int], count: int) -> list[tuple[int, int]]:
    """Up to ``count`` ``(row, col)`` maxima of ``score`` at least ``size`` (h, w) apart, best first."""
    kernel = np.ones((max(1, size[0]), max(1, size[1])), np.uint8)
    peaks = (score >= cv2.dilate(score, kernel)) & np.isfinite(score)
    rows, cols = np.nonzero(peaks)
    order = np.argsort(score[rows, cols])[::-1][:count]
    return [(int(rows[i]), int(cols[i])) for i in order]


class _Verified(NamedTuple):
    """One whole-frame candidate looked at by the tracker's filter (``Reacquirer.search``)."""

    centre: np.ndarray
    peak: float
    found: np.ndarray  # where the filter's answer lies
    payload: object


class _Remembered(NamedTuple):
    """A verification kept for later searches while the target stays lost."""

    patch: np.ndarray  # the template-sized patch of the shrunk grey frame around the candidate, when it was verified
    search: int  # the search it was verified in
    verified: _Verified


class Reacquirer:
    """State of the watchdog; the tracking loop calls :meth:`observe` every frame and :meth:`search` while lost."""

    def __init__(self, params: ReacquireParams | None = None) -> None:
        self.params = ReacquireParams() if params is None else params
        self.peaks: deque[float] = deque(maxlen=self.params.history)
        self.weak = 0
        self.lost = False
        self.template: np.ndarray | None = None
        self.verified = 0  # candidates looked at by the tracker's filter so far (reused answers not counted)
        self._turn = 0  # which of the candidates beyond the budget's fixed ones is verified this frame
        self._k = 1  # the whole factor the whole-frame search shrinks frames by
        self._small_template: np.ndarray | None = None
        self._small: np.ndarray | None = None  # the shrunk grey frame of the last candidates (patches to compare)
        self._memo: list[_Remembered] = []
        self._searches = 0
        self._searches_in_loss = 0  # searches since the target was last declared lost

    def start(self, frame: np.ndarray, box) -> None:
        """Remember the target's first appearance (the template never drifts with the model)."""
        self.template = _crop(_grey(np.asarray(frame)), np.asarray(box, float))
        if self.template is not None:
            self._k = shrink_factor(self.template.shape, self.params.match_side)
            self._small_template = block_mean(self.template, self._k)
        self.peaks.clear()
        self.weak, self.lost = 0, False
        self._forget()

    @property
    def usual_peak(self) -> float:
        return float(np.median(self.peaks)) if self.peaks else float("nan")

    def observe(self, peak: float) -> bool:
        """Take a tracked frame's peak; True when the target now counts as lost (the caller skips the update)."""
        if not np.isfinite(peak):
            return self.lost
        usual = self.usual_peak
        if len(self.peaks) < 5 or peak >= self.params.lost_ratio * usual:
            self.weak = 0
            self.peaks.append(peak)
            return False
        self.weak += 1
        self.lost = self.weak >= self.params.patience
        if self.lost:
            self._forget()  # the model learned since any earlier loss: old answers mean nothing
            self._searches_in_loss = 0
        return self.lost

    def candidates(self, frame: np.ndarray, thermal: np.ndarray | None = None, *,
                   executor: Executor | None = None) -> list[np.ndarray]:
        """Whole-frame candidate centres ``[x, y]`` (full-size pixels): template matches in ``frame``, and the
        warmest blobs of the grey ``thermal`` frame (by default ``frame`` itself when it is grey), in the same
        geometry, both found on frames shrunk by :func:`shrink_factor`.

        ``executor``: a pool with an idle worker finds the warm blobs there while this thread matches the template
        (OpenCV releases the GIL in both); the candidates are the same either way.
        """
        if self.template is None:
            return []
        blobs = thermal if thermal is not None else (frame if np.asarray(frame).ndim == 2 else None)
        want_blobs = self.params.warm_blobs and blobs is not None
        warm = executor.submit(self._warm_blobs, blobs) if want_blobs and executor is not None else None
        self._small = _grey(block_mean(np.asarray(frame), self._k))
        matches = self._template_matches(self._small)
        blobs_found = warm.result() if warm is not None else (self._warm_blobs(blobs) if want_blobs else [])
        # by rank, the two sources taken in turn: a budgeted search (verify_budget) looks at the best of each first
        out = [c for pair in zip(matches, blobs_found) for c in pair]
        short = min(len(matches), len(blobs_found))
        out += matches[short:] + blobs_found[short:]
        return out

    def _template_matches(self, small: np.ndarray) -> list[np.ndarray]:
        """Centres of the best matches of the first-frame template in the shrunk grey frame ``small``
        (normalised cross-correlation)."""
        th, tw = self._small_template.shape
        if th >= small.shape[0] or tw >= small.shape[1]:
            return []
        score = cv2.matchTemplate(small, self._small_template, cv2.TM_CCOEFF_NORMED)
        return [to_full([c + (tw - 1) / 2, r + (th - 1) / 2], self._k)
                for r, c in local_maxima(score, (th, tw), self.params.candidates)]

    def _warm_blobs(self, blobs: np.ndarray) -> list[np.ndarray]:
        """Centres of the warmest blobs of about the template's size: maxima of the blurred, shrunk grey frame."""
        th, tw = self._small_template.shape
        small = _grey(block_mean(np.asarray(blobs), self._k)).astype(np.float32)
        blur = cv2.GaussianBlur(small, (0, 0), max(1.0, min(th, tw) / 4))
        return [to_full([c, r], self._k) for r, c in local_maxima(blur, (th, tw), self.params.candidates)]

    def search(self, candidates: list[np.ndarray], verify, size: float):
        """The best verified candidate's payload, or None (the target stays lost).

        ``verify(centre)`` looks at a candidate with the tracker's own filter, without changing any model, and
        returns ``(peak, found_centre, payload)``. A candidate counts when the filter's answer lands within ``size``
        pixels (one target size) of it and its peak reaches ``found_ratio`` x the usual peak, or ``distinct_ratio`` x
        the usual peak while standing out (``distinct_margin`` x the peak of every other candidate farther than
        ``size`` away). A candidate at an unchanged place keeps an earlier search's answer if that answer could not
        be taken (``reuse_frames``), so the one taken is always verified afresh.
        """
        self._searches += 1
        self._searches_in_loss += 1
        self._memo = [m for m in self._memo if self._searches - m.search <= self.params.reuse_frames]
        seen = [self._recall(c) or self._check(c, verify) for c in self._within_budget(candidates, size)]
        best = self._decide(seen, size)
        if best is None:
            return None
        self.lost, self.weak = False, 0
        self.peaks.append(float(best.peak))
        self._forget()
        return best.payload

    def _decide(self, seen: list[_Verified], size: float) -> _Verified | None:
        """The candidate to take among the verified ones (see :meth:`search`), or None."""
        usual = self.usual_peak
        near = [v for v in seen if np.hypot(*(np.asarray(v.found) - v.centre)) <= size]  # the filter agrees
        placed = [v for v in near if v.peak >= self.params.distinct_ratio * usual]
        if not placed:
            return None
        best = max(placed, key=lambda v: v.peak)
        rivals = [v.peak for v in seen if np.hypot(*(v.centre - best.centre)) > size]
        stands_out = bool(rivals) and all(best.peak >= self.params.distinct_margin * r for r in rivals)
        if best.peak < self.params.found_ratio * usual and not stands_out:
            return None
        return best

    def _check(self, centre: np.ndarray, verify) -> _Verified:
        """``centre`` verified by the tracker's filter now; an answer that could not be taken is kept for later
        searches."""
        seen = _Verified(np.asarray(centre, float), *verify(centre))
        self.verified += 1
        patch = self._patch(seen.centre)
        hopeless = seen.peak < self.params.distinct_ratio * self.usual_peak
        if patch is not None and hopeless and self.params.reuse_frames:
            self._memo.append(_Remembered(patch.copy(), self._searches, seen))  # the frame's buffer may be refilled
        return seen

    def _recall(self, centre: np.ndarray) -> _Verified | None:
        """An earlier answer for ``centre``: verified at the same place (the same cell of the shrunk frame) at most
        ``reuse_frames`` searches ago, on pixels that changed by at most ``reuse_change`` grey levels since; else
        None."""
        patch = self._patch(np.asarray(centre, float)) if self._memo else None
        if patch is None:
            return None
        for m in reversed(self._memo):
            same = np.max(np.abs(m.verified.centre - centre)) <= self._k / 2
            if same and m.patch.shape == patch.shape and float(
                    np.mean(cv2.absdiff(m.patch, patch))) <= self.params.reuse_change:
                return m.verified
        return None

    def _patch(self, centre: np.ndarray) -> np.ndarray | None:
        """The template-sized patch of the last shrunk grey frame around ``centre`` (full-size pixels; moved inside
        the frame where it would cross an edge: warm blobs lie there too), or None without such a frame."""
        if self._small is None or self._small_template is None:
            return None
        th, tw = self._small_template.shape
        x, y = (np.asarray(centre, float) - (self._k - 1) / 2) / self._k
        x0 = min(max(int(round(x - (tw - 1) / 2)), 0), max(self._small.shape[1] - tw, 0))
        y0 = min(max(int(round(y - (th - 1) / 2)), 0), max(self._small.shape[0] - th, 0))
        return self._small[y0:y0 + th, x0:x0 + tw]

    def _forget(self) -> None:
        """Drop the remembered answers (a new loss, or the target found)."""
        self._memo = []

    def _within_budget(self, candidates: list[np.ndarray], size: float) -> list[np.ndarray]:
        """The candidates verified this frame: all of them without a budget; else, after dropping any within half a
        target size of a better one, the first ``budget - 1`` (the strongest of each source) plus one of the rest,
        taken in turn frame by frame. The first search of a loss takes the strongest ``first_budget`` alone."""
        budget = self.params.verify_budget
        first = self.params.first_budget if self._searches_in_loss == 1 else 0
        if not (budget or first) or len(candidates) <= (first or budget):
            return candidates
        kept: list[np.ndarray] = []
        for centre in candidates:
            if all(np.hypot(*(centre - other)) > size / 2 for other in kept):
                kept.append(centre)
        if first:
            return kept[:first]
        if len(kept) <= budget:
            return kept
        rest = kept[budget - 1:]
        self._turn = (self._turn + 1) % len(rest)
        return kept[: budget - 1] + [rest[self._turn]]

    def search_eco(self, tracker, frame: np.ndarray):
        """:meth:`search` for one ECO tracker: its ``TrackResult`` at the best verified candidate, or None."""
        def verify(centre):
            pred = tracker.predict(frame, center=centre)
            return pred.peak, pred.center, pred

        return self.search(self.candidates(frame), verify, float(np.sqrt(np.prod(tracker.target_hw))))
