"""All ECO settings in one frozen dataclass, with the presets ``hc``, ``hc+cnn`` and ``deep``.

Values come from the authors' JMMAC code (``../shared/reference/jmmac_official_code_notes.md``, "ECO (thermal)
settings"), which follows ECO (Danelljan et al., CVPR 2017). Values derived at run time (sample size, scale limits)
live in the tracker state, never here.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from rgbt_toolkit.errors import InputError


@dataclass(frozen=True)
class EcoParams:
    """ECO tracker settings (source of each value in the comment)."""

    # --- features ---------------------------------------------------------------------------------------------------
    # "fhog", "colour" (colour names on colour frames, intensity on grey ones: ECO's useForColor/useForGray),
    # "colornames", "intensity", "deep" (the backbone layers named in deep_layers).
    features: tuple[str, ...] = ("fhog", "colour")
    cell_size: int = 4                   # fHOG / CN / intensity cell (JMMAC code)
    fhog_dim: int = 10                   # fHOG compressed dims (JMMAC code)
    colour_dim: int = 3                  # ColorNames / intensity compressed dims (JMMAC code)
    colour_table: str | None = None      # optional user table in CNnorm.mat format; None = the project's own
    intensity_bins: int = 6              # soft intensity histogram levels (project choice)
    exposure_target: float = 110.0       # ours: a dark colour frame is brightened to this mean grey before features
    exposure_min_gain: float = 1.2       # ... when it needs more than this gain (0 target: off); see docs/eco.md
    backbone: str = "efficientnet-lite0"  # deep features (VGG-M in the paper; weights not redistributable)
    backbone_weights: str | None = None  # None = weights shipped with the backbone
    deep_layers: tuple[str, ...] = ("shallow", "deep")  # like VGG-M conv1 / conv5
    deep_dims: tuple[int, ...] = (16, 64)  # compressed dims (JMMAC code: 16 for conv1, 64 for conv4/5)
    normalize_power: float = 2.0         # feature normalisation (JMMAC code: power 2, size and dim on)
    cos_window: bool = True              # Hann window on feature maps (ECO)

    # --- search region ------------------------------------------------------------------------------------------------
    search_area_scale: float = 4.0       # square search area, 4x the target (JMMAC code)
    # ours, off (0) by default (docs/decisions.md, D40): when the blob that stands out at the box centre covers at most
    # this share of the first box, the regularisation window and the label are built on the blob (the search region,
    # grid and reported boxes stay the box's). Rescues a 3 px bird in an 11 px label (svan_ir_bird_014 3.5 -> 63.6)
    # but loses more than it gains over the folds (svan_v_bird_001 68.7 -> 12.7; fold means -0.95, -0.73, +0.85, -0.53)
    loose_box_share: float = 0.0
    loose_box_offset: float = 0.1        # ... and the blob's centre lies within this share of the box of its centre
    min_sample_area: float = 200.0**2    # sample patch area bounds in pixels (JMMAC code; "hc": ECO-HC's, below)
    max_sample_area: float = 250.0**2
    sample_stride: int = 4               # patch side is an odd multiple of this (coarsest feature stride)
    response_stride: int = 4             # response grid step in patch pixels (grid shared by RGB and T trackers)

    # --- learning -----------------------------------------------------------------------------------------------------
    output_sigma_factor: float = 1.0 / 12.0  # label width (JMMAC code)
    learning_rate: float = 0.011         # (JMMAC code)
    n_samples: int = 50                  # GMM components (JMMAC code)
    train_gap: int = 5                   # frames without training between updates (JMMAC code)
    projection_reg: float = 2e-7         # lambda on ||P||^2 (JMMAC code)
    init_gn_iter: int = 10               # first frame: Gauss-Newton steps (JMMAC code)
    init_cg_iter: int = 200              # first frame: CG iterations in total (JMMAC code)
    cg_iter: int = 5                     # CG iterations per update (JMMAC code)
    cg_forgetting_rate: float = 50.0     # (JMMAC code)
    precond_data: float = 0.3            # preconditioner data / reg / proj weights (JMMAC code)
    precond_reg: float = 0.05
    precond_proj: float = 70.0

    # --- spatial regularisation (JMMAC code) ------------------------------------------------------------------------
    reg_window_min: float = 1e-4
    reg_window_edge: float = 10e-3
    reg_window_power: float = 2.0
    reg_sparsity: float = 0.15

    # --- interpolation (JMMAC code) ---------------------------------------------------------------------------------
    interp_a: float = -0.75
    interp_centering: bool = True

    # --- detection / scale (JMMAC code) -------------------------------------------------------------------------------
    n_scales: int = 7
    scale_step: float = 1.01
    newton_iter: int = 5
    scale_filter: bool = False           # fDSST scale filter instead of the in-filter scale search (ECO option)
    # ours, from real footage (docs/eco.md, "Scale on real footage"): another scale must beat the current one by 2 %
    # per step (peak x penalty^|k|); without it the box size drifted (median |log area error| 0.81 on 34 real clips)
    scale_penalty: float = 0.98
    # ours (docs/eco.md, "Scale bias"): divide each scale's peak by that scale's peak on the first frame, where the
    # true relative scale is 1, so the search compares evidence of a size change rather than the filter's own
    # preference for a zoomed sample. Real clips: neutral (25 tuning clips 67.5 -> 67.2); generated scale_change
    # 76.9 -> 88.9, JMMAC ablation 88.9 -> 92.1 mean MSR
    scale_bias_calibration: bool = True
    # ours (issue #21, speed): search the n_scales scales on every k-th frame only, the current scale in between
    # (features cost about a fifth there); 1 = every frame, as ECO
    scale_search_interval: int = 1
    # ours (docs/decisions.md, D4): the hysteresis decides whether the size moves, not
    # where to: a step goes only to the scale whose bias-corrected peak is the highest before the penalty. On small
    # real targets the peaks tilt by 1-3 % per step towards one side (a preference the updated filter builds up);
    # the penalised maximum then lands a step off the centre while the plain one sits at the edge of the search,
    # and those steps were the drift (svan_v_drone_003: 14 of 14). A true size change peaks where the step goes.
    scale_step_to_peak: bool = True

    def __post_init__(self) -> None:
        known = {"fhog", "colour", "colornames", "intensity", "deep"}
        bad = [f for f in self.features if f not in known]
        if bad or not self.features:
            raise InputError(f"unknown ECO feature {bad[0] if bad else '(none)'!r}; choose from {sorted(known)}")
        if self.n_scales < 1 or self.n_scales % 2 == 0:
            raise InputError(f"n_scales must be odd and positive, got {self.n_scales}")
        if self.sample_stride % self.response_stride and self.response_stride % self.sample_stride:
            raise InputError("sample_stride and response_stride must divide one another")
        if self.scale_search_interval < 1:
            raise InputError(f"scale_search_interval must be at least 1, got {self.scale_search_interval}")
        if not 0 < self.scale_penalty <= 1:
            raise InputError(f"scale_penalty must be in (0, 1], got {self.scale_penalty}")
        if not 0 <= self.loose_box_share < 1 or self.loose_box_offset < 0:
            raise InputError(f"loose_box_share must be in [0, 1) and loose_box_offset >= 0, got "
                             f"{self.loose_box_share}, {self.loose_box_offset}")
        if len(self.deep_dims) != len(self.deep_layers):  # a layer without a width was dropped without a word
            raise InputError(f"deep_dims needs one width per deep layer: {len(self.deep_layers)} layers "
                             f"{list(self.deep_layers)}, {len(self.deep_dims)} widths {list(self.deep_dims)}")
        if not 0 < self.learning_rate < 1:
            raise InputError(f"learning_rate must be in (0, 1), got {self.learning_rate}")

    def with_(self, **changes) -> "EcoParams":
        """A copy with some fields changed (settings stay immutable)."""
        return replace(self, **changes)


# ECO-HC's own sample patch (Danelljan et al.'s hand-crafted run file: 150^2..200^2 pixels, search area 4x). The
# JMMAC code's 200^2..250^2 belongs to its VGG-M tracker; JMMAC keeps it (JmmacConfig.sample_area). On the 34 real
# clips the smaller patch is 23 % less CPU with ECO-hc level or better (docs/decisions.md, D6).
ECO_HC_SAMPLE_AREA = (150.0**2, 200.0**2)
JMMAC_SAMPLE_AREA = (200.0**2, 250.0**2)  # the JMMAC code's (= the EcoParams defaults)

PRESETS: dict[str, EcoParams] = {
    # hand-crafted: fHOG + colour names (or intensity on grey/thermal frames), on ECO-HC's sample patch
    "hc": EcoParams(min_sample_area=ECO_HC_SAMPLE_AREA[0], max_sample_area=ECO_HC_SAMPLE_AREA[1]),
    # deep: backbone shallow + deep layers, plus fHOG and colour as in the JMMAC code; the coarsest stride (16) sets
    # the patch size, so the response grid differs from "hc": pair two "deep" trackers for RGB-T fusion.
    "deep": EcoParams(features=("deep", "fhog", "colour"), sample_stride=16),
}
# hc plus the backbone's stride-4 "shallow" layer on hc's own patch and grid (the backbone stops there: its stride-16
# stages are most of deep's cost); the small targets hc loses to the background (docs/decisions.md, D49)
PRESETS["hc+cnn"] = PRESETS["hc"].with_(features=("deep", "fhog", "colour"), deep_layers=("shallow",), deep_dims=(16,))


def preset(name: str) -> EcoParams:
    """Settings by preset name (``"hc"``, ``"hc+cnn"`` or ``"deep"``)."""
    if name not in PRESETS:
        raise InputError(f"unknown ECO preset {name!r}; choose from {sorted(PRESETS)}")
    return PRESETS[name]
