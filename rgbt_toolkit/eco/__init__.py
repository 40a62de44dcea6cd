"""ECO (Danelljan et al., CVPR 2017) for one modality: continuous-domain correlation filters with factorised
convolution, a generative sample space and sparse updates, exposed with the API JMMAC needs."""

from rgbt_toolkit.eco.params import PRESETS, EcoParams, preset
from rgbt_toolkit.eco.tracker import EcoTracker, TrackResult

__all__ = ["EcoParams", "EcoTracker", "PRESETS", "TrackResult", "preset"]
