"""``rgbt synth OUTDIR``: render a synthetic RGB-T scene with exact ground truth."""

from __future__ import annotations

import click


def _parse_challenges(value: str) -> list[str]:
    from rgbt_toolkit.synth import CHALLENGES

    if value.strip().lower() == "all":
        return list(CHALLENGES)
    return [name.strip() for name in value.split(",") if name.strip()]


@click.command(epilog="Challenges: occlusion, camera_motion, low_light, thermal_crossover, fast_motion, "
                      "scale_change, distractor_color, distractor_thermal, crossing_color, crossing_thermal, "
                      "degradation, gimbal_jump, leave_view, long_occlusion, real_sensor, far_target, "
                      "appearance_change, skip_blocks, gimbal_follow, overlays (or 'all').")
@click.argument("outdir", type=click.Path(file_okay=False))
@click.option("--challenges", "-c", default="", help="Comma-separated challenge names, or 'all'.")
@click.option("--seed", type=int, default=0, show_default=True, help="Random seed; same seed, same scene.")
@click.option("--layout", type=click.Choice(["videos", "rgbt234"]), default="videos", show_default=True,
              help="Two MP4s with box files, or an RGBT234-layout sequence folder.")
@click.option("--name", default="scene", show_default=True, help="File-name stem (videos) or sequence folder name.")
@click.option("--duration", type=click.FloatRange(min=0.1), default=4.0, show_default=True, help="Seconds.")
@click.option("--rgb-size", default="320x240", show_default=True, help="RGB camera WIDTHxHEIGHT.")
@click.option("--t-size", default="256x192", show_default=True, help="Thermal camera WIDTHxHEIGHT.")
@click.option("--rgb-fps", type=click.FloatRange(min=1), default=15.0, show_default=True,
              help="RGB camera frame rate, frames per second.")
@click.option("--t-fps", type=click.FloatRange(min=1), default=15.0, show_default=True,
              help="Thermal camera frame rate (videos layout; rgbt234 pairs frames one to one at the RGB rate).")
@click.option("--aligned", is_flag=True,
              help="Register the cameras pixel to pixel (thermal at the RGB size, identity RGB->T), as benchmark "
                   "datasets are delivered.")
@click.option("--t-offset", type=float, default=0.0, show_default=True,
              help="Seconds the thermal clock lags the RGB one (videos layout): thermal frame j shows scene time "
                   "j / t-fps + T_OFFSET. The opposite sign of `track`/`register --offset` (thermal time = RGB time "
                   "+ offset): `register --sync` reports about -T_OFFSET.")
@click.option("--label-jitter", type=click.FloatRange(min=0.0), default=0.0, show_default=True, metavar="PX",
              help="Also write NAME_rgb.labels.txt and NAME_t.labels.txt: each camera's boxes as hand labels, every "
                   "x, y, w, h moved by Gaussian noise of PX pixels and rounded (videos layout; with --t-offset the "
                   "two files are shifted in time; with -c gimbal_follow the target stays near the centre).")
@click.option("--board", default=None, metavar="COLSxROWS",
              help="Instead of a scene, render a heated calibration board (COLSxROWS inner corners, or dots) seen by "
                   "both cameras of this rig: NAME_rgb/ and NAME_t/ PNG frames and NAME.json (the RGB->T "
                   "homography); NAME defaults to board here. For `rgbt register --board`.")
@click.option("--board-pattern", type=click.Choice(["chessboard", "circles"]), default="chessboard",
              show_default=True, help="Pattern of --board.")
@click.option("--board-views", type=click.IntRange(min=1, max=200), default=6, show_default=True,
              help="Board poses (one frame pair each) for --board.")
@click.option("--force", is_flag=True, help="Replace an earlier scene of the same name (and its frames).")
def command(outdir, challenges, seed, layout, name, duration, rgb_size, t_size, rgb_fps, t_fps, aligned, t_offset,
            label_jitter, board, board_pattern, board_views, force):
    """Render a paired RGB and thermal scene with both cameras' boxes, flags and the RGB->T homography."""

    from click.core import ParameterSource

    from rgbt_cli.progress import progress_bar
    from rgbt_cli.signals import sigterm_raises
    from rgbt_toolkit.errors import InputError
    from rgbt_toolkit.synth import SceneConfig, generate_scene

    ctx = click.get_current_context()
    given = {p for p in ("t_size", "t_offset", "t_fps") if ctx.get_parameter_source(p) != ParameterSource.DEFAULT}
    if aligned and "t_size" in given:
        raise InputError("--aligned sets the thermal size to the RGB size; give --rgb-size only, not --t-size")
    if layout == "rgbt234" and given & {"t_offset", "t_fps"}:
        raise InputError("--layout rgbt234 pairs frames one to one at the RGB times; --t-offset and --t-fps apply "
                         "to the videos layout only")

    def size(text: str, option: str) -> tuple[int, int]:
        try:
            w, h = (int(v) for v in text.lower().split("x"))
        except ValueError:
            raise click.BadParameter(f"'{text}' is not WIDTHxHEIGHT", param_hint=option) from None
        return w, h

    fields = dict(duration=duration, rgb_size=size(rgb_size, "--rgb-size"), t_size=size(t_size, "--t-size"),
                  rgb_fps=rgb_fps, t_fps=t_fps, t_offset=t_offset)
    if aligned:
        fields.update(t_size=fields["rgb_size"], t_zoom=1.0, t_rotation_deg=0.0, t_shift=(0.0, 0.0), t_keystone=0.0)
    config = SceneConfig(challenges=frozenset(_parse_challenges(challenges)), seed=seed, **fields)
    if board:
        from rgbt_toolkit.registration.board import BoardSpec
        from rgbt_toolkit.synth.board import write_board_pair

        scene_only = {"challenges", "layout", "duration", "rgb_fps", "t_fps", "t_offset", "label_jitter"}
        extra = sorted(p for p in scene_only if ctx.get_parameter_source(p) != ParameterSource.DEFAULT)
        if extra:
            raise InputError(f"--board renders still board views; --{extra[0].replace('_', '-')} applies to scenes")
        spec = BoardSpec.parse(board, board_pattern)
        written = write_board_pair(outdir, config, spec.cols, spec.rows, board_views, board_pattern,
                                   name if ctx.get_parameter_source("name") != ParameterSource.DEFAULT else "board",
                                   force=force)
        for key, path in written.items():
            click.echo(f"{key}: {path}")
        return
    total = config.rgb_frame_count + (config.t_frame_count if layout == "videos" else 0)
    # SIGTERM unwinds like Ctrl-C, so the staging folder is removed
    with sigterm_raises(lambda signum: SystemExit(128 + signum)), \
            progress_bar(total=total, unit="frame", desc="rendering") as bar:
        written = generate_scene(outdir, sorted(config.challenges), seed, layout, name, bar.update, force,
                                 label_jitter=label_jitter, **fields)
    if isinstance(written, dict):
        for key, path in written.items():
            click.echo(f"{key}: {path}")
    else:
        click.echo(f"sequence: {written}")
