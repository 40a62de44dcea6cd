"""Assemble the real JMMAC parts, and one-call entry points for the CLI and batch jobs."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from rgbt_toolkit.eco.params import EcoParams
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.fusion.shipped import TRACKING_HEADS  # re-exported: the tracker's default MFNet heads
from rgbt_toolkit.jmmac.config import JMMAC_HC_SAMPLE_AREA, JmmacConfig, preset
from rgbt_toolkit.jmmac.pipeline import JmmacTracker


def eco_params(config: JmmacConfig) -> EcoParams:
    """The settings of JMMAC's two ECO trackers: ``config``'s ECO preset with its sample patch (``hc``:
    :data:`~rgbt_toolkit.jmmac.config.JMMAC_HC_SAMPLE_AREA`; unless the config sets one) and the config's scale-search
    interval. MFNet's training responses are made with them too
    (``fusion.responses.EcoResponseSource``)."""
    from rgbt_toolkit.eco import preset as eco_preset

    params = eco_preset(config.eco_preset).with_(scale_search_interval=config.scale_search_interval)
    area = config.sample_area
    if area is None:
        if config.eco_preset != "hc":
            return params
        area = JMMAC_HC_SAMPLE_AREA
    return params.with_(min_sample_area=area[0], max_sample_area=area[1])


def build_tracker(config: JmmacConfig, *, mfnet_weights: str | os.PathLike | None = None,
                  detector: str | os.PathLike | None = None, mfnet=None) -> JmmacTracker:
    """A :class:`JmmacTracker` with ECO, MFNet, CME, Kalman + DDIS switcher and the box refiner as ``config`` asks.

    ``mfnet`` lets batch callers share one loaded network between runs; otherwise it comes from ``mfnet_weights``
    (default: the shipped tracking heads, run through ONNX Runtime: :func:`load_tracking_mfnet`). ``detector`` is a user ONNX detector for box refinement; without
    one the first-frame box regressor is used.
    """
    from rgbt_toolkit.jmmac.eco_part import EcoAppearance

    params = eco_params(config)
    rgb = EcoAppearance(params) if config.uses_rgb else None
    thermal = EcoAppearance(params) if config.uses_t else None
    fusion = None
    if config.fusion in ("global", "local", "mfnet"):
        from rgbt_toolkit.jmmac.fusion_part import MfnetWeighting

        fusion = MfnetWeighting(mfnet if mfnet is not None else load_tracking_mfnet(mfnet_weights),
                                patch=config.fusion_patch)
    parts: dict = {}
    if config.camera_motion or config.target_motion:
        from dataclasses import replace

        from rgbt_toolkit.motion.camera_motion import FAST_CAMERA_MOTION, CameraMotionSettings
        from rgbt_toolkit.motion.parts import build_motion_parts
        from rgbt_toolkit.motion.trigger import FAST_TRIGGER, TriggerSettings

        camera = FAST_CAMERA_MOTION if config.fast_camera_motion else CameraMotionSettings()
        trigger = FAST_TRIGGER if config.fast_camera_motion else TriggerSettings()
        parts = build_motion_parts(camera=replace(camera, model=config.motion_model), trigger=trigger,
                                   dark_level=config.dark_level)
        if not config.camera_motion:
            parts.pop("camera_motion")
        if not config.target_motion:
            for key in ("kalman", "quality", "template", "switch"):
                parts.pop(key)
    refiner = None
    if config.refine:
        from rgbt_toolkit.refinement import make_refiner

        refiner = make_refiner("detector" if detector else "regressor", model_path=detector)
    return JmmacTracker(config, rgb, thermal, fusion, refiner=refiner, **parts)


def load_tracking_mfnet(weights: str | os.PathLike | None = None):
    """The tracker's MFNet: the shipped ONNX export of :data:`TRACKING_HEADS` run by ONNX Runtime (no torch import:
    3-4 s less start-up, and faster per frame), a user ``.onnx`` export the same way, or user torch heads (``.pt``)."""
    if weights is None or str(weights).lower().endswith(".onnx"):
        from rgbt_toolkit.fusion.onnx_model import OnnxMfnet

        return OnnxMfnet(weights)
    from rgbt_toolkit.fusion.model import MFNet

    return MFNet.from_file(weights)


def load_rig_calibration(path: str | os.PathLike) -> tuple[np.ndarray, float, tuple]:
    """``(H_rgb->t, offset, sizes)`` from an ``rgbt register`` calibration file; ``offset`` is in the convention of
    :func:`~rgbt_toolkit.jmmac.inputs.resolve_inputs` (seconds added to thermal timestamps), ``sizes`` the
    ``(rgb (w, h), thermal (w, h))`` it was made for (see :func:`~rgbt_toolkit.registration.check_frame_sizes`)."""
    from rgbt_toolkit.registration import load_calibration

    calibration = load_calibration(path)
    sizes = (tuple(calibration.rgb_size), tuple(calibration.thermal_size))
    return np.asarray(calibration.matrix, dtype=float), -float(calibration.time_offset), sizes


def registration_estimator(masks: tuple[np.ndarray | None, np.ndarray | None] = (None, None)):
    """``(rgb_path, t_path) -> H_rgb->t`` estimated from a few frame pairs of the two inputs; ``masks`` (RGB,
    thermal; non-zero = leave out) as for ``registration.pipeline.register_streams``."""
    from rgbt_toolkit.registration.pipeline import register_for_tracking

    def estimate(rgb_path, t_path) -> np.ndarray:
        return np.asarray(register_for_tracking(rgb_path, t_path, masks=masks).calibration.matrix, dtype=float)

    return estimate


def track_sequence_folder(seq_dir: str | os.PathLike, preset_name: str = "default",
                          config_overrides: dict | None = None, **build_options) -> np.ndarray:
    """Track one benchmark sequence folder; the (N, 4) boxes in the RGB camera, as benchmark result files hold.

    ``config_overrides`` replaces fields of the preset's :class:`JmmacConfig` (benchmarks of a setting).
    """
    from rgbt_toolkit.jmmac.inputs import resolve_inputs

    inputs = resolve_inputs(seq_dir)
    tracker = build_tracker(preset(preset_name, **(config_overrides or {})), **build_options)
    boxes = []
    for index, (rgb, thermal, _) in enumerate(inputs.pairs):
        if rgb is None or thermal is None:  # unreadable frame (warned): keep the count, repeat the last box
            if index == 0:
                raise InputError(f"{seq_dir}: the first frame pair is unreadable; the target cannot be initialised "
                                 "there")
            boxes.append(boxes[-1].copy())
            continue
        aligned = inputs.thermal_in_rgb(thermal)
        result = tracker.initialize(rgb, aligned, inputs.init_box) if index == 0 else tracker.track(rgb, aligned)
        boxes.append(result.box)
    return np.asarray(boxes)


def track_video_pair(rgb_path: str | os.PathLike, t_path: str | os.PathLike, out_dir: str | os.PathLike,
                     preset_name: str = "default", video: bool = False, assume_aligned: bool = False,
                     **build_options) -> dict[str, Path]:
    """Track a video pair into ``out_dir`` (the files ``rgbt track`` writes); returns the written paths.

    The RGB->T transform is estimated from the pair, or with ``assume_aligned`` a resolution-only scaling; a failed
    estimate raises ``RegistrationError`` (the batch reports the item as failed) rather than tracking on a guess.
    """
    from rgbt_toolkit.jmmac.inputs import resolve_inputs
    from rgbt_toolkit.jmmac.run import run_tracking

    inputs = resolve_inputs(rgb_path, t_path, assume_aligned=assume_aligned,
                            estimate_registration=None if assume_aligned else registration_estimator())
    summary = run_tracking(inputs, build_tracker(preset(preset_name), **build_options), out_dir, video=video)
    if summary["interrupted"]:  # its outputs are closed, complete up to that frame; the caller must stop too
        raise KeyboardInterrupt
    return {k: Path(v) for k, v in summary["outputs"].items()}
