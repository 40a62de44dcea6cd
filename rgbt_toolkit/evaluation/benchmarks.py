"""Each benchmark's scoring conventions, as data.

Small deviations -- a ``+1`` in a width, pooled versus per-sequence averaging, ``<`` versus ``<=`` -- move published
numbers by 0.3 to 2.7 points, so every quirk lives here, one frozen record per benchmark, and the scoring code has no
``if benchmark == ...`` branches. Sources: ``../shared/reference/jmmac_official_code_notes.md`` ("Benchmark
conventions"), the GTOT / RGBT234 MATLAB toolkits and the MIT-licensed Python RGBT_toolkit (RGBT210, LasHeR),
VOT's legacy toolkit ``stack_vot2019_rgbtir`` (VOT-RGBT), the Anti-UAV challenges' scoring programs and the
Anti-UAV410 toolkit (Anti-UAV; see ``evaluation/anti_uav.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rgbt_toolkit.errors import InputError


@dataclass(frozen=True)
class Curve:
    """One threshold curve: its reported name, thresholds and the threshold (or area) that gives the score."""

    name: str  # as papers print it: "MPR", "MSR", "PR", "SR", "NPR"
    start: float
    stop: float
    count: int  # thresholds = linspace(start, stop, count)
    kind: str  # "error" (precision: error below t), "normalised" (NPR), "overlap" (success: IoU above t)
    score_at: float | None = None  # precision: the threshold reported; None for success curves
    strict: bool = False  # precision counts error < t (GTOT) instead of <= t
    area: str = "mean"  # success: "mean" of the curve points or "trapezoid" area

    @property
    def thresholds(self) -> np.ndarray:
        return np.linspace(self.start, self.stop, self.count)

    @property
    def score_index(self) -> int:
        """Index of :attr:`score_at` in :attr:`thresholds` (precision curves)."""
        return int(np.argmin(np.abs(self.thresholds - self.score_at)))


@dataclass(frozen=True)
class AttributeSource:
    """Where a benchmark keeps its challenge attributes."""

    kind: str  # "table": folder of <ATTR>.txt with one 0/1 line per sequence; "per_sequence": folder/<seq>.txt row
    folder: str  # relative to the benchmark root
    order_file: str = ""  # "table": sequence order file inside folder; "per_sequence": attribute names file (root)
    names: tuple[str, ...] = ()  # "per_sequence": attribute order when order_file is absent


@dataclass(frozen=True)
class OpeBenchmark:
    """A one-pass-evaluation (OPE) RGB-T benchmark."""

    key: str
    title: str
    sequence_roots: tuple[str, ...]  # sub-folders of the benchmark root holding ground truth; first existing wins
    gt_files: tuple[str, ...]  # per modality, "{seq}" replaced by the sequence name; two = visible, infrared
    gt_format: str  # read_boxes format of the ground-truth rows
    sequence_lists: tuple[str, ...]  # files naming the sequences, relative to the benchmark root; first existing wins
    curves: tuple[Curve, ...]
    pooled: bool = False  # True: all frames pooled (GTOT); False: per-sequence curves averaged
    round_results: bool = True  # result boxes rounded to integers (MATLAB round: half away from zero)
    first_frame_from_gt: bool = False  # result frame 1 replaced by the ground truth
    carry_degenerate: bool = False  # result boxes with w <= 0 or h <= 0 replaced by the previous box
    invalid_gt_nonpositive: bool = False  # gt rows with any value <= 0: error -1 (hit) and overlap -1 (miss)
    attributes: AttributeSource | None = None
    kind: str = field(default="ope", init=False)

    @property
    def metric_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.curves)


@dataclass(frozen=True)
class VotBenchmark:
    """The VOT supervised (reset-based) baseline experiment."""

    key: str
    title: str
    burnin: int = 10  # frames ignored for accuracy after each (re)initialisation, the init frame included
    skip_initialize: int = 5  # the tracker is re-initialised this many frames after a failure
    reliability_frames: float = 100.0  # S in R = exp(-S * failures / frames), as the VOT2019 report prints R
    eao_density: float = 0.5  # the EAO length interval holds this much of the sequence-length density
    sequence_list: str = "list.txt"
    groundtruth_file: str = "groundtruth.txt"
    image_folders: tuple[str, ...] = ("ir", "color")  # first image gives the bounds for the overlap
    experiment: str = "baseline"
    kind: str = field(default="vot", init=False)

    @property
    def metric_names(self) -> tuple[str, ...]:
        return ("EAO", "A", "R")


@dataclass(frozen=True)
class AntiUavBenchmark:
    """Anti-UAV: state accuracy, which rewards reporting the target absent as well as boxing it when present."""

    key: str
    title: str
    modalities: tuple[str, ...] = ("IR", "RGB")  # the first is ranked (the challenges rank on IR) and owns <seq>.*
    label_file: str = "{modality}_label.json"  # inside each sequence folder of the ground-truth folder
    result_stems: tuple[str, ...] = ("{seq}_{modality}", "{seq}")  # + .json or .txt; "{seq}" for the first only
    miss_iou: float = 1e-5  # a present target is missed unless a box overlaps it with IoU above this (challenge code)
    penalty_weight: float = 0.2  # SA-P = SA - weight * (missed / present frames) ** power (later challenges)
    penalty_power: float = 0.3
    kind: str = field(default="anti-uav", init=False)

    @property
    def metric_names(self) -> tuple[str, ...]:
        return ("SA", "SA-P")


_PR20 = Curve("MPR", 0, 50, 51, "error", score_at=20)
_SR21 = Curve("MSR", 0, 1, 21, "overlap", area="mean")
_RGBT234_ATTRS = AttributeSource("table", "attr_txt", "SequencesName.txt")

GTOT = OpeBenchmark(
    key="gtot",
    title="GTOT",
    sequence_roots=("groundtruth", "."),
    gt_files=("{seq}/groundTruth_v.txt", "{seq}/groundTruth_i.txt"),
    gt_format="xyxy",  # x1 y1 x2 y2 with w = x2 - x1 (no +1)
    sequence_lists=("SequencesName.txt", "groundtruth/SequencesName.txt"),
    curves=(
        Curve("MPR", 0, 25, 51, "error", score_at=5, strict=True),  # error < 5 px
        Curve("MSR", 0, 1, 51, "overlap", area="trapezoid"),  # t = 0:0.02:1, trapezoid area
    ),
    pooled=True,  # all 7,850 frames pooled
    attributes=AttributeSource("table", "attr_txt", "SequencesName.txt"),  # used when present
)

RGBT234 = OpeBenchmark(
    key="rgbt234",
    title="RGBT234",
    sequence_roots=("rgbt234_gt", "."),
    gt_files=("{seq}/visible.txt", "{seq}/infrared.txt"),
    gt_format="xywh",
    sequence_lists=("attr_txt/SequencesName.txt", "SequencesName.txt"),
    curves=(_PR20, _SR21),
    attributes=_RGBT234_ATTRS,
)

RGBT210 = OpeBenchmark(
    key="rgbt210",
    title="RGBT210",
    sequence_roots=("groundtruth", "."),
    gt_files=("{seq}/init.txt",),
    gt_format="xywh",
    sequence_lists=("SequencesName.txt",),
    curves=(Curve("PR", 0, 50, 51, "error", score_at=20), Curve("SR", 0, 1, 21, "overlap", area="mean")),
    first_frame_from_gt=True,
    attributes=_RGBT234_ATTRS,  # the RGBT234 table; only the RGBT210 sequences are used
)

LASHER = OpeBenchmark(
    key="lasher",
    title="LasHeR",
    sequence_roots=("lasher_gt", "."),
    gt_files=("{seq}.txt",),
    gt_format="xywh",
    sequence_lists=("lashertest.txt",),
    curves=(
        Curve("PR", 0, 50, 51, "error", score_at=20),
        Curve("SR", 0, 1, 21, "overlap", area="mean"),
        Curve("NPR", 0, 0.5, 51, "normalised", score_at=0.2),
    ),
    first_frame_from_gt=True,
    carry_degenerate=True,
    invalid_gt_nonpositive=True,
    attributes=AttributeSource(
        "per_sequence",
        "AttriSeqsTxt",
        "Attributes_order.txt",
        names=("NO", "PO", "TO", "HO", "MB", "LI", "HI", "AIV", "LR", "DEF", "BC", "SA", "CM", "TC", "FL", "OV",
               "FM", "SV", "ARC"),
    ),
)

VOT_RGBT = VotBenchmark(key="vot-rgbt", title="VOT-RGBT")

ANTI_UAV = AntiUavBenchmark(key="anti-uav", title="Anti-UAV")

Benchmark = OpeBenchmark | VotBenchmark | AntiUavBenchmark
BENCHMARKS: dict[str, Benchmark] = {b.key: b for b in (GTOT, RGBT234, RGBT210, LASHER, VOT_RGBT, ANTI_UAV)}
_ALIASES = {"vot19-rgbt": "vot-rgbt", "votrgbt": "vot-rgbt", "vot2019-rgbt": "vot-rgbt", "antiuav": "anti-uav"}


def get_benchmark(name: str) -> Benchmark:
    """The benchmark record for ``name`` (case-insensitive; ``vot19-rgbt``, ``votrgbt``, ``antiuav`` accepted too)."""
    key = name.lower().replace("_", "-")
    key = _ALIASES.get(key, key)
    if key not in BENCHMARKS:
        raise InputError(f"unknown benchmark '{name}'; choose one of {', '.join(BENCHMARKS)}")
    return BENCHMARKS[key]
