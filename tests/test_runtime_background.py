"""`runtime.InBackground`: set-up started on a second thread (``rgbt track`` loads its tracker there while the inputs
are registered), its value or its error handed back in the caller's thread."""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.errors import WeightsError
from rgbt_toolkit.runtime import InBackground

SAMPLES = Path(__file__).resolve().parents[1] / "samples"


def test_work_runs_on_another_thread_and_its_value_comes_back():
    caller = threading.get_ident()
    started = threading.Event()

    def work():
        started.set()
        return threading.get_ident()

    job = InBackground(work)
    assert started.wait(5)
    assert job.result() != caller


def test_an_error_in_the_work_is_raised_in_the_caller():
    def work():
        raise WeightsError("model.onnx: not a loadable ONNX model")

    job = InBackground(work)
    try:
        job.result()
    except WeightsError as exc:
        assert "model.onnx" in str(exc)
    else:
        raise AssertionError("the background error was not raised")


def test_the_thread_does_not_hold_up_the_exit():
    gate = threading.Event()
    job = InBackground(gate.wait)
    assert job._thread.daemon  # a caller that stops first (Ctrl-C in the estimate) leaves at once
    gate.set()
    assert job.result() is True


def test_track_reports_an_unloadable_mfnet_file_built_beside_the_registration(tmp_path):
    """The tracker loads while the pair is registered; a model file that does not load still stops the run with
    the file named, exit 1, and no results written."""
    bad = tmp_path / "heads.pt"
    bad.write_bytes(np.arange(64, dtype=np.uint8).tobytes())
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"),
                                       "--init", "150,110,40,30", "--mfnet-weights", str(bad), "-o", str(out),
                                       "--max-frames", "2"])
    assert result.exit_code == 1, result.output
    assert str(bad) in result.output and "Traceback" not in result.output
    assert not any(out.glob("*")) if out.exists() else True
