"""`rgbt track` on a pair whose target leaves the view: `present: false` in track.json, `--absent zeros` rows, and
the Anti-UAV result files that `rgbt eval --benchmark anti-uav` scores."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
from click.testing import CliRunner

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "eco"))
from test_reacquire import cut_sequence  # noqa: E402

from rgbt_cli.main import main  # noqa: E402
from rgbt_toolkit.io.images import write_image  # noqa: E402


def _sequence(root: Path) -> tuple[Path, np.ndarray]:
    """An RGBT234-layout sequence (visible/, infrared/, init.txt) whose target is out of view on frames 18-29."""
    rgb, truth = cut_sequence(n=40, cut=40, absent=(18, 30))
    thermal, _ = cut_sequence(n=40, cut=40, absent=(18, 30), grey=True)
    seq = root / "leaves"
    for sub, frames in (("visible", rgb), ("infrared", thermal)):
        (seq / sub).mkdir(parents=True)
        for k, f in enumerate(frames):
            write_image(seq / sub / f"{k:05d}.png", f)
    (seq / "init.txt").write_text(",".join(str(int(v)) for v in truth[0]) + "\n")
    return seq, truth


def test_absent_frames_in_every_output(tmp_path):
    seq, truth = _sequence(tmp_path)
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["track", str(seq), "--no-video", "--no-plot", "--absent", "zeros",
                                    "--anti-uav", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert "target judged absent on" in res.output
    frames = json.loads((out / "track.json").read_text())["frames"]
    present = np.array([f["present"] for f in frames])
    assert not present[22:30].any() and present[:18].all() and present[34:].all()
    assert all(f["confidence"] is None or f["confidence"] >= 0 for f in frames)
    rows = np.loadtxt(out / "boxes_rgb.txt", delimiter=",")
    assert np.array_equal(~rows.any(axis=1), ~present)  # 0,0,0,0 exactly on the absent frames
    for name in ("leaves_RGB.json", "leaves_IR.json"):
        res_list = json.loads((out / name).read_text())["res"]
        assert len(res_list) == 40 and all((r == []) == (not p) for r, p in zip(res_list, present))
    # the files are what `rgbt eval --benchmark anti-uav` reads: score them against the scene's truth
    gt = tmp_path / "gt" / "leaves"
    gt.mkdir(parents=True)
    exist = [int(b.any()) for b in truth]
    label = {"exist": exist, "gt_rect": [b.tolist() if e else [] for b, e in zip(truth, exist)]}
    (gt / "IR_label.json").write_text(json.dumps(label))
    (gt / "RGB_label.json").write_text(json.dumps(label))
    res = CliRunner().invoke(main, ["eval", "--benchmark", "anti-uav", "--gt", str(tmp_path / "gt"),
                                    "--results", str(out)])
    assert res.exit_code == 0, res.output
    row = res.output.strip().splitlines()[-1].split()
    assert row[0] == "out" and float(row[1]) > 85  # 10 of the 12 absent frames said absent, boxes on target
    # without the module the held box scores 0 on every absent frame
    res = CliRunner().invoke(main, ["track", str(seq), "--no-video", "--no-plot", "--anti-uav", "--preset", "+TMP",
                                    "-o", str(tmp_path / "tmp_run")])
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(main, ["eval", "--benchmark", "anti-uav", "--gt", str(tmp_path / "gt"),
                                    "--results", str(tmp_path / "tmp_run")])
    assert float(res.output.strip().splitlines()[-1].split()[1]) < 75


def test_held_rows_are_the_default(tmp_path):
    seq, _ = _sequence(tmp_path)
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["track", str(seq), "--no-video", "--no-plot", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert np.loadtxt(out / "boxes_rgb.txt", delimiter=",").all()
    assert not list(out.glob("*_IR.json"))
