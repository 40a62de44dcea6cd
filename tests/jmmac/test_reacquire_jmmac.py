"""Re-acquisition as a JMMAC module: the `default` preset finds a target again after a shot cut, `+TMP` (the same
without the module) does not, and lost frames are flagged `present: false`."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "eco"))
from test_reacquire import centre_error, cut_sequence  # noqa: E402

from rgbt_toolkit.jmmac.api import build_tracker  # noqa: E402
from rgbt_toolkit.jmmac.config import preset  # noqa: E402


def run(name: str, rgb: list, thermal: list, box) -> tuple[np.ndarray, list]:
    tracker = build_tracker(preset(name))
    results = [tracker.initialize(rgb[0], thermal[0], box)]
    results += [tracker.track(r, t) for r, t in zip(rgb[1:], thermal[1:])]
    return np.array([r.box for r in results]), results


@pytest.fixture(scope="module")
def cut_pair():
    rgb, truth = cut_sequence(n=36, cut=18)
    thermal, _ = cut_sequence(n=36, cut=18, grey=True)
    return rgb, thermal, truth


def test_default_finds_the_target_after_a_cut_and_tmp_alone_does_not(cut_pair):
    rgb, thermal, truth = cut_pair
    boxes, results = run("default", rgb, thermal, truth[0])
    err = centre_error(boxes, truth)
    assert np.all(err[:18] < 4)
    assert np.all(err[26:] < 4), err[18:]
    assert any(r.reacquired for r in results)
    without, _ = run("+TMP", rgb, thermal, truth[0])
    assert np.median(centre_error(without[26:], truth[26:])) > 50


def test_absent_target_is_flagged_and_nothing_learns():
    rgb, truth = cut_sequence(n=40, cut=40, absent=(18, 30))
    thermal, _ = cut_sequence(n=40, cut=40, absent=(18, 30), grey=True)
    boxes, results = run("default", rgb, thermal, truth[0])
    present = np.array([r.present for r in results])
    assert not present[22:30].any() and present[:18].all()
    assert present[34:].all() and np.all(centre_error(boxes[34:], truth[34:]) < 4)


def test_the_module_is_a_switch():
    assert preset("default").reacquire and preset("+RA").reacquire
    assert not preset("+TMP").reacquire and not preset("full").reacquire
