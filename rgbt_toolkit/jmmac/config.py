"""JMMAC settings in one frozen dataclass, with the paper's ablation variants as presets.

Every module can be switched off, which is how the paper's ablation table (B-RGB, B-T, +MF-G, +MF-L, +MF, +CME,
+TMP, full) is reproduced; thresholds are the paper's unless noted.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.jmmac.fusion_part import TRACKING_PATCH

FUSION_MODES = ("rgb", "t", "average", "global", "local", "mfnet")
SCALE_SEARCH = ("lead", "both")


@dataclass(frozen=True)
class JmmacConfig:
    """What runs, and with which thresholds.

    ``fusion``: ``rgb`` / ``t`` use one modality's response (the paper's B-RGB / B-T baselines, the other tracker is
    not run), ``average`` a fixed 0.5 / 0.5 blend, ``global`` only MFNet's w_G (W_L = 1), ``local`` only W_L
    (w_G = 1), ``mfnet`` W_F = w_G * W_L (Sec. III-A).
    """

    fusion: str = "mfnet"
    camera_motion: bool = True  # CME, Sec. III-B-2
    motion_model: str = "affine"  # CME transform: translation, similarity, affine, projective
    parallel_trackers: bool = True  # ours: RGB and T ECO on two threads (they release the GIL in numpy/OpenCV)
    fast_camera_motion: bool = True  # ours: trigger on frames shrunk to 320 px, SIFT on half-size frames with 500
    # keypoints (motion/trigger.py FAST_TRIGGER, motion/camera_motion.py FAST_CAMERA_MOTION); False = the authors' exact
    # full-resolution operations
    target_motion: bool = True  # TMP: Kalman motion tracker + Algorithm-1 switcher, Sec. III-B-1
    refine: bool = True  # bounding-box refinement, Sec. III-C
    eco_preset: str = "hc"  # features of both ECO trackers: "hc" (fHOG + colour names / intensity) or "deep"
    # Algorithm 1 thresholds on the paper's scales (our raw q, s are mapped onto them, see motion/switcher)
    q_skip_matching: float = 250.0  # "If q is higher than 250 ... we suspend the template matching"
    # Under drastic camera motion TMP is suspended (paper), so a target hidden while the camera shakes used to follow a
    # meaningless appearance peak (bundled demo: off by 20-110 px within 9 frames, then lost). Below Algorithm 1's
    # q_low (paper scale) the box is carried by the camera motion alone and no model learns from the frame - if the
    # box it carries is trusted (an appearance result, or carried from one), else the appearance peak is kept.
    q_hold_under_camera_motion: float = 135.0
    dark_level: float = 40.0  # ours: below this mean grey the visible patch is "dark": no refinement, and
    # template matching switches to the thermal frame (motion/template.py)
    max_tail: int = 30  # frames of trajectory kept for drawing
    # ours (re-acquisition, eco/reacquire.py): when the fused peak stays far below its usual value the target counts
    # as lost (`present` false in track.json, no model learns), and the whole frame is searched for it
    reacquire: bool = False
    reacquire_budget: int = 3  # whole-frame candidates verified per frame while lost (ReacquireParams.verify_budget)
    # ... and on the frame the target is declared lost (ReacquireParams.first_budget; 0: reacquire_budget), which has
    # run a tracked frame's whole appearance step already: its strongest candidate only (docs/decisions.md, D55)
    reacquire_first_budget: int = 1
    # the whole-frame candidate search shrinks frames while the template's shorter side stays at least this many px
    # (ReacquireParams.match_side; 16 for ECO alone): a 24-31 px template is matched at half size, 1.3 against 10.7 ms
    # on a 640x512 frame; the candidates are verified at full size (docs/decisions.md, D51)
    reacquire_match_side: int = 12
    # re-acquisition looks at each candidate at the current scale only (a fifth of the feature cost of the 7-scale
    # search; it needs the peak and position, not a size); True: the full scale search. Generated ablation: the same
    # boxes either way (default preset 92.1 mean MSR), re-acquisition 29 -> 8 ms/frame on the speed scene (issue #21)
    verify_all_scales: bool = False
    scale_search_interval: int = 1  # ours (issue #21): both ECO trackers search scales every k-th frame only
    # ECO's sample patch area bounds (pixels) for both trackers; None: JMMAC_HC_SAMPLE_AREA for "hc", else the ECO
    # preset's own (the JMMAC code's 200^2..250^2 for "deep"). The JMMAC code's patch for both trackers left the box
    # size fixed on real footage where ECO-hc alone followed it; ECO-HC's takes JMMAC from 68.1 to 69.2 mean success
    # on the 34 real clips and costs 1.0 mean MSR on the generated ablation (seeds 0-1; docs/decisions.md, D7)
    sample_area: tuple[float, float] | None = None
    # side (px) of the crops of the search region MFNet sees, a multiple of 16: 80 px kept the generated benchmarks'
    # accuracy of 128 px at 60 % of MFNet's cost (issue #21; figures at fusion_part.TRACKING_PATCH)
    fusion_patch: int = TRACKING_PATCH
    # ours (issue #21): "lead" = only the tracker of the modality MFNet weighted more on the last frame searches the
    # 7 scales and sets the box size, the other looks at the current scale (both search when w_G is exactly 0.5);
    # "both" = both always search and their size changes are blended by w_G. Generated ablation, default preset:
    # 91.5 / 91.1 mean MSR (seeds 0-5), at 14-20 % less CPU per frame
    scale_search: str = "lead"

    def __post_init__(self) -> None:
        if self.fusion not in FUSION_MODES:
            raise InputError(f"unknown fusion mode {self.fusion!r}; choose one of {', '.join(FUSION_MODES)}")
        if self.scale_search not in SCALE_SEARCH:
            raise InputError(f"unknown scale search {self.scale_search!r}; choose one of {', '.join(SCALE_SEARCH)}")
        if self.fusion_patch < 32 or self.fusion_patch % 16:
            raise InputError(f"the MFNet patch side must be a multiple of 16 and at least 32 px, got "
                             f"{self.fusion_patch}")

    @property
    def uses_rgb(self) -> bool:
        return self.fusion != "t"

    @property
    def uses_t(self) -> bool:
        return self.fusion != "rgb"


# ours: the sample patch of JMMAC's two "hc" trackers, ECO-HC's 150^2..200^2 with a 190^2 upper bound. For a large
# target the bound sets the working scale too, so every whole-frame step shrinks with it: 3-4 % less wall time on the
# real 1080p street pair, while on the 116 real clips no clip moved by 3 points (mean 68.4 -> 68.3); 175^2 and 150^2
# lost targets JMMAC holds (docs/decisions.md, D54 and D57)
JMMAC_HC_SAMPLE_AREA = (150.0**2, 190.0**2)

# The paper's ablation variants (Table "Ablation analysis"), each adding one module to the previous one.
PRESETS: dict[str, JmmacConfig] = {
    "B-RGB": JmmacConfig(fusion="rgb", camera_motion=False, target_motion=False, refine=False),
    "B-T": JmmacConfig(fusion="t", camera_motion=False, target_motion=False, refine=False),
    "average": JmmacConfig(fusion="average", camera_motion=False, target_motion=False, refine=False),
    "+MF-G": JmmacConfig(fusion="global", camera_motion=False, target_motion=False, refine=False),
    "+MF-L": JmmacConfig(fusion="local", camera_motion=False, target_motion=False, refine=False),
    "+MF": JmmacConfig(fusion="mfnet", camera_motion=False, target_motion=False, refine=False),
    "+CME": JmmacConfig(fusion="mfnet", camera_motion=True, target_motion=False, refine=False),
    "+TMP": JmmacConfig(fusion="mfnet", camera_motion=True, target_motion=True, refine=False),
    "full": JmmacConfig(),
    # ours, beyond the paper: +TMP with re-acquisition after loss
    "+RA": JmmacConfig(refine=False, reacquire=True),
    # what `rgbt track` runs unless told otherwise: the full method without box refinement, which needs a detector
    # to pay off (the first-frame regressor cost 1.3 points MSR on generated sequences, docs/benchmarks.md);
    # `--detector model.onnx` switches refinement on; re-acquisition after loss is on (= "+RA")
    "default": JmmacConfig(refine=False, reacquire=True),
}


def preset(name: str, **overrides) -> JmmacConfig:
    """A named preset, optionally with some fields replaced (``preset("full", refine=False)``)."""
    try:
        base = PRESETS[name]
    except KeyError:
        raise InputError(f"unknown preset {name!r}; choose one of {', '.join(PRESETS)}") from None
    return replace(base, **overrides) if overrides else base
