"""Registration of paired RGB and thermal cameras in time (frame pairing, clock offset) and space (RGB->T transform).

Typical use::

    from rgbt_toolkit.registration import register_paths, save_calibration
    reg = register_paths("rgb.mp4", "thermal.mp4")
    save_calibration("calib.json", reg.calibration)

See ``docs/registration.md`` for the method and its measured accuracy.
"""

from rgbt_toolkit.registration.apply import map_boxes, preview, warp_frame
from rgbt_toolkit.registration.calib import Calibration, check_frame_sizes, load_calibration, save_calibration
from rgbt_toolkit.registration.pipeline import RegisterSettings, Registration, register_paths, register_streams
from rgbt_toolkit.registration.spatial import SpatialResult, SpatialSettings, estimate_transform
from rgbt_toolkit.registration.temporal import FramePairing, OffsetEstimate, estimate_offset, motion_signal, pair_frames
from rgbt_toolkit.registration.transforms import MODELS, corner_error, overlap_corner_error

__all__ = [
    "MODELS", "Calibration", "FramePairing", "OffsetEstimate", "RegisterSettings", "Registration", "SpatialResult",
    "SpatialSettings", "check_frame_sizes", "corner_error", "estimate_offset", "estimate_transform",
    "load_calibration", "map_boxes", "motion_signal", "overlap_corner_error", "pair_frames", "preview",
    "register_paths", "register_streams", "save_calibration", "warp_frame",
]
