"""Settings of one synthetic scene: sizes, timing, the two cameras, and which challenges are on."""

from __future__ import annotations

from dataclasses import dataclass, field

from rgbt_toolkit.errors import InputError

# Each name switches on one challenge; the comment says what the renderer does for it.
CHALLENGES: dict[str, str] = {
    "occlusion": "an opaque vehicle crosses in front of the target mid-sequence",
    "camera_motion": "the rig pans, shakes and zooms (a per-frame affine of the world)",
    "low_light": "RGB illumination drops to night (gain, noise, colour loss); thermal unaffected",
    "thermal_crossover": "the target's temperature approaches the background's for a while",
    "fast_motion": "the target moves fast with abrupt direction changes",
    "scale_change": "the target approaches and recedes (size changes about 2x)",
    "distractor_color": "a second object with the target's colour but background temperature",
    "distractor_thermal": "a second warm object with the target's temperature but another colour",
    "degradation": "sensor noise, blur and strong JPEG compression in both cameras",
    "crossing_color": "a look-alike in the target's colours (background temperature) passes just behind the target "
                      "at 60 % of the sequence",
    "crossing_thermal": "a warm body (target's temperature, another colour) passes just behind the target at 60 % "
                        "of the sequence",
    "gimbal_jump": "the rig re-centres abruptly 1-3 times: both cameras jump 150-250 px (at 640 px wide) in one frame",
    "leave_view": "the target walks out of the view, stays out for a quarter of the sequence and comes back from the "
                  "same or the other side (truth 0,0,0,0 while wholly outside)",
    "long_occlusion": "a vehicle drives alongside the target and hides it in both cameras for 1-2 s (flagged absent)",
    "real_sensor": "fixed-pattern column stripes and vignetting, dead/hot pixels, temporal noise, codec blocking and "
                   "a burned-in timestamp overlay in both cameras",
    "far_target": "a small far target (a drone, 8-20 px) against a low-texture sky with faint clouds",
    "skip_blocks": "a low-bit-rate stream: the whole picture is refreshed every 128 frames, in between a 16x16 block "
                   "is sent again only when it changed by more than 8 grey levels on average, so a small or slow "
                   "target moves in jumps and can leave a stale copy behind",
    "appearance_change": "the target turns: from a fifth of the sequence on, its visible colours and stripes change "
                         "gradually until it shows another side (its look drifts from the first frame's)",
    "gimbal_follow": "the rig pans after the target with a lag of about half a second, so the target stays near the "
                     "view centre (a gimbal that follows it)",
    "overlays": "each camera burns in its own on-screen display (clock top right, camera name and azimuth / elevation "
                "top left, in its own font, size and margins; corner brackets around the centre on the RGB camera "
                "only); the truth is unchanged",
}

# the challenges that can take the target out of sight: with them on, truth boxes are clipped to the image,
# 0,0,0,0 while the target is wholly outside it, and frames without a visible target are flagged absent
VISIBILITY_CHALLENGES = frozenset({"gimbal_jump", "leave_view", "long_occlusion"})


@dataclass(frozen=True)
class SceneConfig:
    """Everything that defines a scene; the same config and seed always render the same frames."""

    challenges: frozenset[str] = field(default_factory=frozenset)
    seed: int = 0
    duration: float = 4.0  # seconds of scene time
    rgb_size: tuple[int, int] = (320, 240)  # (width, height)
    t_size: tuple[int, int] = (256, 192)  # thermal sensors have fewer pixels
    rgb_fps: float = 15.0
    t_fps: float = 15.0
    t_offset: float = 0.0  # seconds: the thermal camera's clock runs this much behind the RGB one
    t_zoom: float = 1.1  # thermal field of view is this much narrower than RGB's
    t_rotation_deg: float = 1.5  # mounting roll between the two cameras
    t_shift: tuple[float, float] = (-6.0, 4.0)  # thermal principal-point offset, thermal pixels
    t_keystone: float = 0.03  # perspective: relative scale change across the RGB width (lens/mount tilt)
    target_size: tuple[float, float] = (0.09, 0.25)  # target (width, height) as fractions of the RGB height

    def __post_init__(self) -> None:
        unknown = set(self.challenges) - set(CHALLENGES)
        if unknown:
            raise InputError(
                f"unknown challenge(s) {', '.join(sorted(unknown))}; choose from {', '.join(CHALLENGES)}"
            )
        if self.duration <= 0 or self.rgb_fps <= 0 or self.t_fps <= 0:
            raise InputError("duration and frame rates must be positive")
        if min(self.rgb_size) < 32 or min(self.t_size) < 32:
            raise InputError("camera sizes must be at least 32x32 pixels")
        if self.rgb_frame_count < 1:
            raise InputError(f"duration {self.duration:g} s at {self.rgb_fps:g} fps gives no RGB frame; make the "
                             "duration longer or the frame rate higher")
        object.__setattr__(self, "challenges", frozenset(self.challenges))

    @classmethod
    def aligned(cls, **fields) -> "SceneConfig":
        """Cameras registered pixel to pixel (same size, identity RGB->T), as benchmark datasets are delivered."""
        size = fields.pop("rgb_size", (320, 240))
        return cls(rgb_size=size, t_size=size, t_zoom=1.0, t_rotation_deg=0.0, t_shift=(0.0, 0.0), t_keystone=0.0,
                   **fields)

    def has(self, challenge: str) -> bool:
        return challenge in self.challenges

    @property
    def rgb_frame_count(self) -> int:
        return int(round(self.duration * self.rgb_fps))

    @property
    def t_frame_count(self) -> int:
        return int(round(self.duration * self.t_fps))
