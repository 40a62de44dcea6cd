"""Shipped weight files that more than one layer names, in a leaf module (nothing imported but pathlib).

Why here: the ONNX exporter (``fusion.onnx_model``) and the tracker's assembly (``jmmac.api``) both need the tracking
heads' path; kept in either one, the other would import it and the two packages would import each other.
"""

from pathlib import Path

WEIGHTS_DIR = Path(__file__).resolve().parent / "weights"

# MFNet heads trained for tracking on ECO responses: RoadScene pairs plus 52 generated sequences (docs/fusion.md);
# `rgbt fuse` keeps the image-fusion heads (mfnet_heads.pt), trained on RoadScene for image fusion
TRACKING_HEADS = WEIGHTS_DIR / "mfnet_heads_tracking.pt"
