"""Fixtures for the registration tests: procedural RGB/thermal pairs with a known transform (no data needed)."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.registration.synthetic import procedural_scene, random_similarity, warp_and_crop


@pytest.fixture(autouse=True, scope="session")
def _one_opencv_thread():
    """The 2-core CI machine runs other tests alongside; OpenCV's own pool only adds contention here."""
    import cv2

    before = cv2.getNumThreads()
    cv2.setNumThreads(1)
    yield
    cv2.setNumThreads(before)


def _make_pair(seed: int, size=(320, 240), perspective: float = 1e-4):
    """(visible, thermal, true RGB->T homography): the thermal render warped by a random homography and cropped."""
    rng = np.random.default_rng(seed)
    visible, thermal = procedural_scene(rng, size)
    matrix = random_similarity(rng, size)
    matrix[2, :2] = rng.uniform(-1, 1, 2) * perspective
    cropped, truth = warp_and_crop(thermal, matrix)
    return visible, cropped, truth


@pytest.fixture(scope="session")
def make_pair():
    """Factory: ``make_pair(seed)`` -> (visible, thermal, truth)."""
    return _make_pair


@pytest.fixture(scope="session")
def pair():
    return _make_pair(0)
