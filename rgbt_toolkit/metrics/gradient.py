"""Edge-based metrics: Qabf (Xydeas-Petrovic) and Nabf (Kumar's modified fusion artefacts).

Both compare Sobel edge strength and orientation of each source with the fused image. The published MATLAB codes
differ in padding, image scale and a legacy tie branch; these are parameters here, fixed per convention in
:mod:`rgbt_toolkit.metrics.conventions`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rgbt_toolkit.metrics._filters import as_float_image, check_same_shape, sobel_xy

HALF_PI = np.pi / 2.0


@dataclass(frozen=True)
class QabfParams:
    """Xydeas-Petrovic constants (Petrovic's code, as used by DenseFuse and VIFB)."""

    tg: float = 0.9994
    kg: float = -15.0
    dg: float = 0.5
    ta: float = 0.9879
    ka: float = -22.0
    da: float = 0.8


def _strength_angle_qabf(image: np.ndarray, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """Edge strength and orientation as Petrovic's code computes them with ``conv2``.

    ``conv2`` flips its kernel, so ``conv2(p, [-1 0 1; -2 0 2; -1 0 1])`` is minus the correlation ``gx`` while
    ``conv2(p, [1 2 1; 0 0 0; -1 -2 -1])`` equals the correlation ``gy``: the orientation is
    ``atan(gy / -gx) = -atan(gy / gx)``, and ``pi/2`` where ``gx == 0``. The sign matters: ``pi/2`` is not
    negated, so pixels with a vertical gradient compare against the others' negated angles (with the
    correlation sign VIFB's Qabf is off by up to 1.7 %; with this one it matches to the CSV's rounding).
    """
    gx, gy = sobel_xy(image, pad="zero")
    gx *= scale
    gy *= scale
    g = np.sqrt(gx * gx + gy * gy)  # as MATLAB writes it (ties must compare equal)
    zero = gx == 0
    np.negative(gy, out=gy)
    np.divide(gy, gx, out=gy, where=~zero)
    angle = np.arctan(gy, out=gy)
    angle[zero] = HALF_PI
    return g, angle


def _qabf_term(gs, angs, gf, angf, legacy_tie: bool, p: QabfParams) -> np.ndarray:
    """Q^{SF} = Qg * Qa per pixel (Xydeas-Petrovic sigmoids of strength ratio and orientation agreement)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.minimum(gs, gf)
        ratio /= np.maximum(gs, gf)  # gF/gA where gA > gF, gA/gF where gA < gF (MATLAB's two branches)
    tie = gs == gf
    if legacy_tie:
        np.copyto(ratio, gf, where=tie)
    else:
        ratio[tie] = 1.0
    orient = np.subtract(angs, angf)
    np.abs(orient, out=orient)
    orient *= -1.0 / HALF_PI
    orient += 1.0 - p.da  # 1 - |dA| / (pi/2) - Da
    orient *= p.ka
    np.exp(orient, out=orient)
    orient += 1.0
    ratio -= p.dg
    ratio *= p.kg
    np.exp(ratio, out=ratio)
    ratio += 1.0
    ratio *= orient
    return np.divide(p.tg * p.ta, ratio, out=ratio)


def qabf(
    a: np.ndarray,
    b: np.ndarray,
    f: np.ndarray,
    *,
    scale: float = 1.0,
    legacy_tie: bool = False,
    params: QabfParams = QabfParams(),
) -> float:
    """Qabf: edge information transferred from the sources to F, weighted by source edge strength.

    Parameters
    ----------
    a, b, f : ndarray
        Visible, infrared and fused 2-D images on the 0-255 scale.
    scale : float
        Factor applied to the Sobel responses, i.e. the scale the original code saw the images on:
        1/255 for DenseFuse's [0, 1] images, 255 for VIFB (which multiplies 0-255 data by 255 again), 1 otherwise.
    legacy_tie : bool
        ``True`` keeps the original code's branch ``G = gF`` where ``gA == gF`` (instead of the ratio 1). With
        ``scale=1/255`` that branch drags Qabf(A, A, A) down to about 0.48; the textbook form gives 0.9748.
    """
    check_same_shape(visible=a, infrared=b, fused=f)
    ga, aa = _strength_angle_qabf(as_float_image(a, "visible"), scale)
    gb, ab = _strength_angle_qabf(as_float_image(b, "infrared"), scale)
    gf, af = _strength_angle_qabf(as_float_image(f, "fused"), scale)
    q_af = _qabf_term(ga, aa, gf, af, legacy_tie, params)
    q_bf = _qabf_term(gb, ab, gf, af, legacy_tie, params)
    denominator = np.sum(ga + gb)
    if denominator == 0:
        return float("nan")
    q_af *= ga
    q_bf *= gb
    q_af += q_bf
    return float(np.sum(q_af) / denominator)


@dataclass(frozen=True)
class NabfParams:
    """Constants of B. K. Shreyamsha Kumar's objective_fusion_perform_fn (2011)."""

    td: float = 2.0
    wt_min: float = 0.001
    lg: float = 1.5
    nrg: float = 0.9999
    kg: float = 19.0
    sigma_g: float = 0.5
    nra: float = 0.9995
    ka: float = 22.0
    sigma_a: float = 0.5


def _sobel_nabf(image: np.ndarray, scale: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Kumar's ``sobel_fn`` (templates / 8, mirror extension): (strength, gv, gh)."""
    gv, gh = sobel_xy(image, pad="mirror")  # gv: x-derivative template, gh: y-derivative template
    gv *= scale / 8.0
    gh *= scale / 8.0
    return np.sqrt(gv * gv + gh * gh), gv, gh


def _angle_nabf(gv: np.ndarray, gh: np.ndarray) -> np.ndarray:
    """``atan(gv / gh)``, 0 where both responses are 0 (the code's branch)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        angle = np.arctan(gv / gh)
    angle[(gv == 0) & (gh == 0)] = 0.0
    return angle


def _nabf_q(gs, angs, gf, angf, p: NabfParams) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(gs > gf, gf / gs, gs / gf)
    ratio[(gs == 0) | (gf == 0)] = 0.0
    orient = np.abs(np.abs(angs - angf) - HALF_PI) / HALF_PI
    qg = p.nrg / (1.0 + np.exp(-p.kg * (ratio - p.sigma_g)))
    qa = p.nra / (1.0 + np.exp(-p.ka * (orient - p.sigma_a)))
    return np.sqrt(qg * qa)


def _nabf_weight(g: np.ndarray, p: NabfParams) -> np.ndarray:
    w = np.full_like(g, p.wt_min)
    strong = g >= p.td
    if strong.any():
        w[strong] = g[strong] ** p.lg
    return w


def nabf(
    a: np.ndarray, b: np.ndarray, f: np.ndarray, *, scale: float = 1.0, params: NabfParams = NabfParams()
) -> float:
    """Nabf: weighted share of edge-strength gained in F where F is stronger than both sources (artefacts).

    Parameters
    ----------
    a, b, f : ndarray
        Visible, infrared and fused 2-D images on the 0-255 scale.
    scale : float
        Image scale the original code saw: 1/255 for DenseFuse's [0, 1] inputs (every edge is then below
        ``td`` and all weights equal ``wt_min``), 1 for 0-255 data.

    Returns
    -------
    float
        0 when F equals both sources; larger means more artefacts.

    Notes
    -----
    Only artefact pixels (``gF > gA`` and ``gF > gB``) enter the numerator, so orientations and the Q terms are
    computed on those pixels only.
    """
    check_same_shape(visible=a, infrared=b, fused=f)
    ga, va, ha = _sobel_nabf(as_float_image(a, "visible"), scale)
    gb, vb, hb = _sobel_nabf(as_float_image(b, "infrared"), scale)
    gf, vf, hf = _sobel_nabf(as_float_image(f, "fused"), scale)
    wa, wb = _nabf_weight(ga, params), _nabf_weight(gb, params)
    denominator = np.sum(wa + wb)
    artefact = (gf > ga) & (gf > gb)
    if not artefact.any():
        return 0.0
    af = _angle_nabf(vf[artefact], hf[artefact])
    gf_m = gf[artefact]
    q_af = _nabf_q(ga[artefact], _angle_nabf(va[artefact], ha[artefact]), gf_m, af, params)
    q_bf = _nabf_q(gb[artefact], _angle_nabf(vb[artefact], hb[artefact]), gf_m, af, params)
    numerator = np.sum((1.0 - q_af) * wa[artefact] + (1.0 - q_bf) * wb[artefact])
    return float(numerator / denominator)
