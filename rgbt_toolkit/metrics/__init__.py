"""Image-fusion quality metrics with the conventions of the published MATLAB code families.

Plain functions over numpy arrays (EN, MI, CE, Qabf, Nabf, FMI, SSIM, MS-SSIM, MEF-SSIM, SD, SF, AG, EI, PSNR,
RMSE, CC, SCD, VIF, Qcb, Qcv) plus named conventions (``paper``, ``vifb``, ``standard``) and folder scoring.
"""

from rgbt_toolkit.metrics.conventions import CONVENTIONS, Convention, get_convention, score_triple
from rgbt_toolkit.metrics.feature_mi import fmi
from rgbt_toolkit.metrics.gradient import nabf, qabf
from rgbt_toolkit.metrics.information import (
    cross_entropy,
    entropy,
    fusion_mutual_information,
    mutual_information,
    paper_mutual_information,
)
from rgbt_toolkit.metrics.perceptual import qcb, qcv, vif
from rgbt_toolkit.metrics.spatial import (
    average_gradient,
    correlation_coefficient,
    edge_intensity,
    psnr,
    rmse,
    scd,
    spatial_frequency,
    standard_deviation,
)
from rgbt_toolkit.metrics.ssim import mef_ssim, ms_ssim, ssim_same, ssim_valid

__all__ = [
    "CONVENTIONS",
    "Convention",
    "average_gradient",
    "correlation_coefficient",
    "cross_entropy",
    "edge_intensity",
    "entropy",
    "fmi",
    "fusion_mutual_information",
    "get_convention",
    "mef_ssim",
    "ms_ssim",
    "mutual_information",
    "nabf",
    "paper_mutual_information",
    "psnr",
    "qabf",
    "qcb",
    "qcv",
    "rmse",
    "scd",
    "score_triple",
    "spatial_frequency",
    "ssim_same",
    "ssim_valid",
    "standard_deviation",
    "vif",
]
