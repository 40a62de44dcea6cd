"""``rgbt batch track`` ends with a table (status, frames, fps, success/precision, a mean row), writes it as
CSV/JSON, and with ``--plot`` draws the whole batch's precision and success curves."""

from __future__ import annotations

import csv
import json
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.evaluation.api import evaluate
from rgbt_toolkit.io.boxes import read_boxes, write_boxes

TEMPLATE = "batch_helpers:template_tracker,batch_helpers:video_tracker"


def _track(dataset, out, *extra):
    return CliRunner().invoke(main, ["batch", "track", str(dataset), "-o", str(out), "--tracker", TEMPLATE,
                                     "--in-process", *extra])


def test_table_csv_json_and_plot_hold_the_batch_scores(dataset, tmp_path):
    (dataset / "vid_rgb.mp4").unlink()  # sequences only, so `rgbt eval` scores the same set
    (dataset / "vid_t.mp4").unlink()
    # seq3's annotation is 6 px off after the first frame: the tracker follows the pixels, so seq3 scores lower
    shifted = read_boxes(dataset / "seq3" / "visible.txt")
    shifted[1:, :2] += 6.0
    write_boxes(dataset / "seq3" / "visible.txt", shifted, delimiter=",")
    write_boxes(dataset / "seq3" / "infrared.txt", shifted, delimiter=",")
    out = tmp_path / "out"
    result = _track(dataset, out, "--preset", "shifted", "--plot")
    assert result.exit_code == 0, result.output

    reference = evaluate("rgbt234", dataset, [str(out)]).trackers["out"]
    per_seq = reference.per_sequence()
    rows = {r["item"]: r for r in csv.DictReader((out / "batch_summary.csv").read_text().splitlines())}
    assert list(rows) == ["seq0", "seq1", "seq2", "seq3", "mean"]
    for seq in ("seq0", "seq1", "seq2", "seq3"):
        assert rows[seq]["status"] == "done" and int(rows[seq]["frames"]) == len(read_boxes(out / f"{seq}.txt"))
        assert float(rows[seq]["fps"]) > 0
        for metric in ("MPR", "MSR"):
            assert abs(float(rows[seq][metric]) - per_seq[seq][metric]) < 0.01, (seq, metric)
    assert float(rows["seq3"]["MSR"]) < float(rows["seq0"]["MSR"]) - 10  # the 6 px offset shows
    for metric in ("MPR", "MSR"):  # the mean row is the benchmark's aggregate, as `rgbt eval` prints it
        assert abs(float(rows["mean"][metric]) - reference.summary[metric]) < 0.01
    assert int(rows["mean"]["frames"]) == sum(int(rows[s]["frames"]) for s in ("seq0", "seq1", "seq2", "seq3"))

    document = json.loads((out / "batch_summary.json").read_text())
    assert document["tracker"] == "template_tracker shifted" and document["failed"] == []
    assert document["mean"]["MSR"] == round(reference.summary["MSR"], 2)

    mean_line = next(line for line in result.stdout.splitlines() if line.startswith("mean"))
    assert "4/4 ok" in mean_line and f"{reference.summary['MSR']:.1f}" in mean_line
    png = (out / "batch_plots.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    from matplotlib.image import imread

    image = imread(out / "batch_plots.png")
    assert image.shape[1] > 1.8 * image.shape[0]  # two panels side by side: precision and success


def test_failed_items_are_named_and_video_pairs_scored_from_their_boxes(dataset, tmp_path):
    (dataset / "seq2" / "visible.txt").write_text("1,2,3\n")
    out = tmp_path / "out"
    result = _track(dataset, out)
    assert result.exit_code == 1
    assert "failed: seq2" in result.stdout and "FileFormatError" in result.stdout
    assert "4 done, 0 skipped (finished before), 1 failed" in result.stdout
    document = json.loads((out / "batch_summary.json").read_text())
    rows = {r["item"]: r for r in document["items"]}
    assert document["failed"] == ["seq2"] and rows["seq2"]["frames"] is None and rows["seq2"]["MPR"] is None
    assert rows["vid"]["frames"] == len(read_boxes(dataset / "vid_rgb.boxes.txt"))
    assert rows["vid"]["MPR"] == 100.0  # the video tracker writes the true boxes back
    assert document["mean"]["status"] == "4/5 ok"
    assert not (out / "batch_plots.png").exists()  # no --plot

    again = _track(dataset, out)  # skipped items are read back from their result files
    rows_again = {r["item"]: r for r in json.loads((out / "batch_summary.json").read_text())["items"]}
    assert rows_again["seq0"]["status"] == "skipped" and rows_again["seq0"]["MSR"] == rows["seq0"]["MSR"]
    assert again.exit_code == 1


def test_plot_needs_ground_truth(tmp_path):
    from rgbt_toolkit.synth import generate_scene

    generate_scene(tmp_path / "data", (), seed=1, layout="videos", name="v", duration=0.3)
    for path in (tmp_path / "data").glob("*.boxes.txt"):
        path.unlink()
    result = _track(tmp_path / "data", tmp_path / "out", "--plot")
    assert result.exit_code == 1 and "--plot: no item has ground truth" in result.output
    assert not (tmp_path / "out").exists()
