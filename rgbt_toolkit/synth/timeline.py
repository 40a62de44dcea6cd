"""Everything in a scene that changes with time, as functions sampled on a fine clock.

The two cameras sample the same continuous scene at their own frame times (different rates, a clock offset), so all
motion and events are defined in seconds, precomputed on a fine grid once and interpolated per frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rgbt_toolkit.synth.config import SceneConfig

_CLOCK_HZ = 240.0  # fine grid; well above any camera rate


@dataclass(frozen=True)
class Timeline:
    """Sampled time functions of one scene (world coordinates are RGB pixels at zoom 1)."""

    times: np.ndarray  # (K,)
    target_xy: np.ndarray  # (K, 2) target centre in the world
    target_scale: np.ndarray  # (K,)
    camera_centre: np.ndarray  # (K, 2) world point at the RGB image centre
    camera_angle: np.ndarray  # (K,) radians
    camera_zoom: np.ndarray  # (K,)
    light: np.ndarray  # (K,) RGB illumination gain, 1 = day
    crossover: np.ndarray  # (K,) 0 = target at its own temperature, 1 = at the background's
    occluder_x: np.ndarray  # (K,) occluder centre x (NaN when it is out of play)
    distractor_xy: np.ndarray  # (K, 2)
    crossing_xy: np.ndarray | None = None  # (K, 2) the crossing look-alike (crossing_* challenges), else None

    def at(self, name: str, t: float) -> np.ndarray | float:
        """Linear interpolation of one function at time ``t`` (clamped to the scene's span)."""
        values = getattr(self, name)
        if values.ndim == 1:
            return float(np.interp(t, self.times, values))
        return np.array([np.interp(t, self.times, values[:, k]) for k in range(values.shape[1])])


def _window(times: np.ndarray, start: float, end: float, ramp: float) -> np.ndarray:
    """A smooth 0 -> 1 -> 0 bump that is 1 on [start, end] with cosine ramps of ``ramp`` seconds."""
    up = np.clip((times - (start - ramp)) / ramp, 0, 1)
    down = np.clip(((end + ramp) - times) / ramp, 0, 1)
    return 0.5 - 0.5 * np.cos(np.pi * np.minimum(up, down))


def _smooth_path(times: np.ndarray, rng: np.random.Generator, amplitude: np.ndarray, freqs: tuple[float, float],
                 n_terms: int = 3) -> np.ndarray:
    """Sum of a few random sines per axis, scaled so the path stays within +-amplitude."""
    path = np.zeros((len(times), 2))
    for axis in range(2):
        weights = rng.uniform(0.5, 1.0, n_terms)
        weights /= weights.sum()
        for w in weights:
            f = rng.uniform(*freqs)
            path[:, axis] += w * np.sin(2 * np.pi * f * times + rng.uniform(0, 2 * np.pi))
    return path * amplitude


def _bouncing_path(times: np.ndarray, rng: np.random.Generator, bound: np.ndarray, speed: float,
                   turn_every: float) -> np.ndarray:
    """Piecewise-straight path with abrupt direction changes, reflected at +-bound (fast-motion challenge)."""
    dt = times[1] - times[0]
    position = np.zeros(2)
    heading = rng.uniform(0, 2 * np.pi)
    path = np.empty((len(times), 2))
    next_turn = turn_every
    for k, t in enumerate(times):
        if t >= next_turn:
            heading += rng.uniform(0.6, 2.5) * rng.choice([-1, 1])
            next_turn += turn_every * rng.uniform(0.7, 1.3)
        velocity = speed * np.array([np.cos(heading), np.sin(heading)])
        position = position + velocity * dt
        for axis in range(2):
            if abs(position[axis]) > bound[axis]:
                position[axis] = np.sign(position[axis]) * (2 * bound[axis] - abs(position[axis]))
                heading = np.pi - heading if axis == 0 else -heading
        path[k] = position
    return path


def build_timeline(config: SceneConfig, rng: np.random.Generator) -> Timeline:
    """Draw every time function of the scene from ``rng`` according to the switched-on challenges."""
    w, h = config.rgb_size
    span = config.duration + abs(config.t_offset) + 1.0
    times = np.arange(0.0, span + 1.0 / _CLOCK_HZ, 1.0 / _CLOCK_HZ)
    world_centre = np.array([w, h], dtype=float) * 0.75  # the world is 1.5x the RGB view
    bound = np.array([0.17 * w, 0.10 * h])
    d = config.duration

    if config.has("fast_motion"):
        offset = _bouncing_path(times, rng, bound, speed=1.1 * w, turn_every=0.45)
    else:
        offset = _smooth_path(times, rng, bound, (0.05, 0.2))
    target_xy = world_centre + offset

    scale = np.ones_like(times)
    if config.has("scale_change"):
        # approach (grow to 1.6x), then recede to 0.7x: a 2.3x range over the sequence
        phase = np.clip(times / d, 0, 1)
        scale = np.interp(phase, [0, 0.35, 0.75, 1.0], [1.0, 1.6, 0.7, 0.8])

    camera_centre = np.tile(world_centre, (len(times), 1))
    angle = np.zeros_like(times)
    zoom = np.ones_like(times)
    if config.has("camera_motion"):
        camera_centre = camera_centre + _smooth_path(times, rng, np.array([0.08 * w, 0.05 * h]), (0.08, 0.2))
        shake = _window(times, 0.35 * d, 0.55 * d, 0.05)
        jitter = _smooth_path(times, rng, np.array([0.15 * w, 0.15 * w]), (4.0, 7.0), n_terms=2)  # jumps > a target
        camera_centre = camera_centre + shake[:, None] * jitter
        angle = shake * np.deg2rad(1.5) * np.sin(2 * np.pi * 5.5 * times + rng.uniform(0, 2 * np.pi))
        zoom = 1.0 + 0.2 * np.clip((times - 0.65 * d) / (0.2 * d), 0, 1)

    light = np.ones_like(times)
    if config.has("low_light"):
        light = 1.0 - 0.82 * np.clip((times - 0.3 * d) / (0.25 * d), 0, 1)

    crossover = np.zeros_like(times)
    if config.has("thermal_crossover"):
        crossover = 0.93 * _window(times, 0.4 * d, 0.7 * d, 0.15 * d)

    occluder_x = np.full_like(times, np.nan)
    if config.has("occlusion"):
        # the occluder's centre passes the target's x at mid-sequence, travelling one view width in 1.6 s
        t_meet = 0.5 * d
        speed = w / 1.6 * rng.choice([-1, 1])
        meet_x = float(np.interp(t_meet, times, target_xy[:, 0]))
        occluder_x = meet_x + speed * (times - t_meet)
        occluder_x[np.abs(times - t_meet) > 1.2] = np.nan

    distractor_xy = np.full((len(times), 2), np.nan)
    if config.has("distractor_color") or config.has("distractor_thermal"):
        # crosses the target's path: opposite phase around the same centre
        distractor_xy = world_centre + _smooth_path(times, rng, bound * 1.1, (0.1, 0.25))

    crossing_xy = None
    if config.has("crossing_color") or config.has("crossing_thermal"):
        # drawn last, so scenes without these challenges keep their random stream: the look-alike moves with the
        # target plus a steady horizontal drift and passes it at 60 % of the sequence (a fifth of the target's height
        # above or below its centre), as a pedestrian overtaking another
        t_meet = 0.6 * d
        drift = 0.4 * w * rng.choice([-1, 1])  # px/s relative to the target: across a 4x search region in ~1 s
        lift = 0.2 * config.target_size[1] * h * rng.choice([-1, 1])
        crossing_xy = target_xy + np.c_[drift * (times - t_meet), np.full_like(times, lift)]

    return Timeline(times, target_xy, scale, camera_centre, angle, zoom, light, crossover, occluder_x,
                    distractor_xy, crossing_xy)
