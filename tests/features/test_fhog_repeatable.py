"""fHOG must give the same features for the same patch every time: tracking runs are then repeatable."""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.features.fhog import _gradients


def test_colour_gradients_are_identical_on_every_call():
    # where channels tie in gradient magnitude (grey areas of a colour image), the channel was picked by the last
    # bit of cv2.magnitude, which varied between calls: on this frame 299 of 300 calls differed from the first, and
    # two runs of the tracker on the same frames gave different boxes
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer

    cfg = SceneConfig.aligned(rgb_size=(320, 240), challenges=frozenset({"scale_change"}), seed=0, duration=1.0)
    patch = np.ascontiguousarray(SceneRenderer(cfg).render(0.0, "rgb", 0).image[:, :250])
    first_mag, first_theta = _gradients(patch[None])
    for _ in range(30):
        mag, theta = _gradients(patch[None])
        np.testing.assert_array_equal(mag, first_mag)
        np.testing.assert_array_equal(theta, first_theta)
