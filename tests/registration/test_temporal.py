"""Frame pairing by timestamps and clock-offset estimation from motion signals."""

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError, RegistrationError
from rgbt_toolkit.registration import estimate_offset, motion_signal, pair_frames


def test_pairing_different_frame_rates():
    rgb = np.arange(30) / 30.0  # 1 s at 30 fps
    thermal = np.arange(9) / 9.0 + 0.01  # 9 fps thermal core: the slower stream drives
    p = pair_frames(rgb, thermal)
    assert len(p) == 9 and np.array_equal(p.thermal_index, np.arange(9))
    assert np.all(np.abs(p.gap) <= 1 / 60 + 1e-9)
    assert np.array_equal(p.rgb_index, np.round((thermal - 0.0) * 30).astype(int))


def test_pairing_applies_offset_and_drops_frames_outside_the_overlap():
    rgb = np.arange(50) / 25.0
    thermal = np.arange(50) / 25.0 + 0.4  # thermal clock 0.4 s ahead: t_thermal = t_rgb + 0.4
    p = pair_frames(rgb, thermal, offset=0.4)
    assert len(p) == 50 and np.array_equal(p.rgb_index, p.thermal_index)
    shifted = pair_frames(rgb, thermal, offset=0.0)  # without the offset only the overlapping second pairs
    assert len(shifted) == 40 and shifted.rgb_index[0] == 10


def test_pairing_checks_timestamps():
    with pytest.raises(InputError, match="non-decreasing"):
        pair_frames([0.0, 0.2, 0.1], [0.0])
    with pytest.raises(InputError, match="no thermal timestamps"):
        pair_frames([0.0], [])


def _moving_scene(times, rng_seed=0, invert=False):
    """Small frames of a bright square that moves in bursts (events both cameras see) at the given times."""
    rng = np.random.default_rng(rng_seed)
    starts = np.sort(rng.uniform(0, 8, 12))
    frames = []
    for t in times:
        moving = np.sum(np.clip((t - starts) / 0.3, 0, 1))  # each burst moves the square by one step
        x = int(4 + 4 * moving) % 48
        img = np.full((48, 64), 0.2, np.float32)
        img[20:30, x:x + 10] = 0.9
        frames.append(1 - img if invert else img)
    return frames


def test_offset_recovered_across_frame_rates_and_contrast():
    t_rgb = np.arange(0, 8, 1 / 30)
    t_th = np.arange(0, 8, 1 / 25)
    true_offset = -0.3  # the thermal stream stamps each event 0.3 s earlier
    rgb = _moving_scene(t_rgb)
    thermal = _moving_scene(t_th - true_offset, invert=True)  # thermal frame at stamp s shows scene time s + 0.3
    est = estimate_offset(*motion_signal(rgb, t_rgb), *motion_signal(thermal, t_th))
    assert est.offset == pytest.approx(true_offset, abs=1 / 30)
    assert est.correlation > 0.5


def test_offset_fails_clearly_on_static_or_short_input():
    t = np.arange(0, 4, 1 / 25)
    still = [np.full((48, 64), 0.5, np.float32) + 0.001 * (i % 2) for i in range(len(t))]
    rgb = _moving_scene(t)
    with pytest.raises(RegistrationError, match="cannot synchronise"):
        estimate_offset(*motion_signal(rgb, t), *motion_signal(still, t))
    with pytest.raises(RegistrationError, match="at least 9 frames"):
        estimate_offset(*motion_signal(rgb[:3], t[:3]), *motion_signal(rgb, t))
