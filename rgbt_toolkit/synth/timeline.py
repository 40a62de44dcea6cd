"""Everything in a scene that changes with time, as functions sampled on a fine clock.

The two cameras sample the same continuous scene at their own frame times (different rates, a clock offset), so all
motion and events are defined in seconds, precomputed on a fine grid once and interpolated per frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rgbt_toolkit.synth.config import VISIBILITY_CHALLENGES, SceneConfig

_CLOCK_HZ = 240.0  # fine grid; well above any camera rate
GIMBAL_LAG_S = 0.5  # gimbal_follow: time constant of the camera's pan after the target, seconds


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
    long_occluder_xy: np.ndarray | None = None  # (K, 2) the long_occlusion vehicle (NaN out of play), else None
    jump_times: np.ndarray | None = None  # seconds of the gimbal re-centring steps (gimbal_jump), else None

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


def gimbal_steps(times: np.ndarray, duration: float, size: tuple[int, int],
                 rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Camera-centre offsets (K, 2) that jump 1-3 times between two clock ticks, and the jump times.

    The rig re-centres between aim points on alternate sides of the view centre, 0.117-0.195 of the width out, so
    each jump spans 0.234-0.39 of the width (150-250 px of a 640-px frame) and the target stays in view.
    """
    w, h = size
    n = int(rng.integers(1, 4))
    slots = (np.arange(n) + rng.uniform(0.2, 0.8, n)) / n
    jump_times = 0.15 * duration + 0.7 * duration * slots
    side = rng.choice([-1, 1]) * (-1.0) ** np.arange(n + 1)
    aims = np.c_[side * rng.uniform(0.117, 0.195, n + 1) * w, rng.uniform(-0.04, 0.04, n + 1) * h]
    return aims[np.searchsorted(jump_times, times, side="right")], jump_times


def follow_path(times: np.ndarray, target_xy: np.ndarray, lag: float = GIMBAL_LAG_S) -> np.ndarray:
    """Camera-centre path (K, 2) of a gimbal that follows ``target_xy`` as a first-order lag of ``lag`` seconds.

    A gimbal holds the target near the view centre but reacts late, so the target's offset from the centre is about
    its velocity times the lag: the boxes cover a small area around the centre, as on footage of a followed drone.
    """
    alpha = 1.0 - np.exp(-np.diff(times, prepend=times[0]) / lag)
    path = np.empty_like(target_xy)
    path[0] = target_xy[0]
    for k in range(1, len(times)):
        path[k] = path[k - 1] + alpha[k] * (target_xy[k] - path[k - 1])
    return path


def leave_view_x(times: np.ndarray, target_x: np.ndarray, camera_x: np.ndarray, duration: float, width: int,
                 rng: np.random.Generator) -> np.ndarray:
    """Target x that walks out past a view edge, stays out for a quarter of the scene and walks back in.

    Out of view it stands a fifth of the width beyond the edge (wider than any target); halfway through the stay
    it may switch sides unseen, so it comes back from the same or the other edge.
    """
    ramp, start, stay = 0.12 * duration, 0.3 * duration, 0.25 * duration
    out, back = rng.choice([-1, 1]), rng.choice([-1, 1])
    side = np.where(times < start + stay / 2, out, out * back)
    outside = camera_x + side * 0.7 * width
    blend = _window(times, start, start + stay, ramp)
    return (1 - blend) * target_x + blend * outside


def long_occluder_path(times: np.ndarray, target_xy: np.ndarray, duration: float, width: int,
                       rng: np.random.Generator) -> np.ndarray:
    """Centre (K, 2) of a vehicle that catches up with the target, drives alongside it for 1-2 s, then pulls away.

    Alongside it is centred on the target, so it hides it whole; NaN while it is more than a width away.
    """
    hold = min(rng.uniform(1.0, 2.0), 0.5 * duration)
    start = 0.5 * duration - hold / 2
    speed = width / 1.6 * rng.choice([-1, 1])
    relative = speed * (np.minimum(times - start, 0) + np.maximum(times - start - hold, 0))
    path = target_xy + np.c_[relative, np.zeros_like(times)]
    path[np.abs(relative) > width] = np.nan
    return path


def _visibility_events(config: SceneConfig, times: np.ndarray, target_xy: np.ndarray,
                       camera_centre: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray | None,
                                                           np.ndarray | None]:
    """Apply gimbal_jump, leave_view and long_occlusion with their own random stream (seeded from the config), so
    every other time function, and every scene without these challenges, stays as it was."""
    rng = np.random.default_rng([config.seed, 20261201])
    d, w = config.duration, config.rgb_size[0]
    jump_times = occluder = None
    if config.has("gimbal_jump"):
        steps, jump_times = gimbal_steps(times, d, config.rgb_size, rng)
        camera_centre = camera_centre + steps
    if config.has("leave_view"):
        target_xy = np.c_[leave_view_x(times, target_xy[:, 0], camera_centre[:, 0], d, w, rng), target_xy[:, 1]]
    if config.has("long_occlusion"):
        occluder = long_occluder_path(times, target_xy, d, w, rng)
    return target_xy, camera_centre, occluder, jump_times


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
    if config.has("gimbal_follow"):  # no draw from rng: every other time function stays as without it
        camera_centre = follow_path(times, target_xy)
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

    occluder_xy = jump_times = None
    if config.challenges & VISIBILITY_CHALLENGES:
        target_xy, camera_centre, occluder_xy, jump_times = _visibility_events(config, times, target_xy,
                                                                                camera_centre)
    return Timeline(times, target_xy, scale, camera_centre, angle, zoom, light, crossover, occluder_x,
                    distractor_xy, crossing_xy, occluder_xy, jump_times)
