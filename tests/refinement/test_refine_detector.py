"""Detector refinement: FastestDet on real visible images (../shared), acceptance rules with a scripted detector."""

from __future__ import annotations

import builtins
import time

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError, WeightsError
from rgbt_toolkit.io.images import read_image
from rgbt_toolkit.refinement import (Detections, DetectorRefiner, DetectorRefinerSettings, MissingDependencyError,
                                     OnnxYoloDetector, make_refiner)
from rgbt_toolkit.refinement.boxes import iou
from rgbt_toolkit.refinement.detector_refiner import search_region
from rgbt_toolkit.runtime import set_threads

# People and a car in VIFB visible images, boxes read off the images by eye (x, y, w, h)
PERSON_WALKING = np.array([167.0, 152.0, 18.0, 32.0])  # VI/walking.jpg, the pedestrian on the square
PERSON_RUNNING = np.array([41.0, 135.0, 22.0, 54.0])  # VI/running.jpg, the runner on the left
CAR_WALKING = np.array([263.0, 98.0, 40.0, 37.0])  # VI/walking.jpg, the white car on the right


@pytest.fixture(scope="module")
def fastestdet(shared_dir):
    set_threads(1)
    path = shared_dir / "models" / "FastestDet.onnx"
    if not path.is_file():
        pytest.skip("../shared/models/FastestDet.onnx is absent")
    return OnnxYoloDetector(path)


def _names(shared_dir):
    return (shared_dir / "models" / "coco.names").read_text().split("\n")


def test_fastestdet_layout(fastestdet):
    assert fastestdet.layout == "fastestdet" and fastestdet.input_size == (352, 352) and fastestdet.bgr


def test_whole_frame_detections_are_plausible(fastestdet, shared_dir):
    image = read_image(shared_dir / "data/fusion/vifb/VI/walking.jpg")
    det = fastestdet.detect(image)
    names = _names(shared_dir)
    labels = [names[i] for i in det.labels]
    assert np.all(np.diff(det.scores) <= 0) and np.all(det.scores > 0.3)
    person = iou(det.boxes, PERSON_WALKING)
    car = iou(det.boxes, CAR_WALKING)
    assert person.max() > 0.7 and labels[int(person.argmax())] == "person"
    assert car.max() > 0.7 and labels[int(car.argmax())] == "car"


def test_region_detection_maps_back_to_the_frame(fastestdet, shared_dir):
    image = read_image(shared_dir / "data/fusion/vifb/VI/running.jpg")
    det = fastestdet.detect(image, search_region(PERSON_RUNNING, 4.0))
    assert iou(det.boxes[0], PERSON_RUNNING) > 0.8 and det.scores[0] > 0.8
    # a region hanging over the frame's corner still maps boxes to frame pixels
    det = fastestdet.detect(image, np.array([-60.0, 60.0, 200.0, 200.0]))
    assert iou(det.boxes, PERSON_RUNNING).max() > 0.7


def test_detector_refiner_snaps_to_the_person(fastestdet, shared_dir):
    image = read_image(shared_dir / "data/fusion/vifb/VI/running.jpg")
    ref = DetectorRefiner(fastestdet)
    ref.initialize(image, PERSON_RUNNING)
    assert ref.enabled, ref.disabled_reason
    box = PERSON_RUNNING + np.array([0.15 * 22, -0.1 * 54, 0, 0])
    box[2:] *= [1.2, 0.9]
    t = time.perf_counter()
    out = ref.refine(image, box)
    assert time.perf_counter() - t < 1.0  # ~15 ms measured
    assert out is not None and iou(out, PERSON_RUNNING) > 0.85 > iou(box, PERSON_RUNNING)


def test_detector_refiner_frame_one_rules(fastestdet, shared_dir):
    # the pedestrian on a bright square: the authors' over-bright rule turns refinement off
    ref = DetectorRefiner(fastestdet)
    ref.initialize(read_image(shared_dir / "data/fusion/vifb/VI/walking.jpg"), PERSON_WALKING)
    assert not ref.enabled and "over-bright" in ref.disabled_reason
    # no object where the box is (a patch of lawn): not confident on the target
    image = read_image(shared_dir / "data/fusion/vifb/VI/running.jpg")
    ref.initialize(image, np.array([100.0, 200.0, 30.0, 30.0]))
    assert not ref.enabled and "not confident" in ref.disabled_reason
    assert ref.refine(image, PERSON_RUNNING) is None and "disabled" in ref.last_reason


def test_factory_builds_the_detector_refiner(shared_dir):
    ref = make_refiner("detector", shared_dir / "models" / "FastestDet.onnx")
    assert isinstance(ref, DetectorRefiner) and ref.detector.layout == "fastestdet"


# --- errors -------------------------------------------------------------------------------------------------------
def test_missing_and_unfit_model_files(tmp_path):
    pytest.importorskip("onnxruntime")
    with pytest.raises(WeightsError, match="detector model not found"):
        OnnxYoloDetector(tmp_path / "nope.onnx")
    bad = tmp_path / "bad.onnx"
    bad.write_bytes(b"this is not a protobuf")
    with pytest.raises(WeightsError, match="not a readable ONNX model"):
        OnnxYoloDetector(bad)
    with pytest.raises(InputError, match="unknown detector layout"):
        OnnxYoloDetector(bad, layout="ssd")


def test_missing_onnxruntime_says_how_to_install(tmp_path, monkeypatch):
    model = tmp_path / "m.onnx"
    model.write_bytes(b"x")
    real_import = builtins.__import__

    def fake_import(name, *args, **kwargs):
        if name == "onnxruntime":
            raise ImportError("No module named 'onnxruntime'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", fake_import)
    with pytest.raises(MissingDependencyError, match=r"pip install rgbt-toolkit\[onnx\]"):
        OnnxYoloDetector(model)


def test_factory_errors():
    with pytest.raises(InputError, match="unknown refiner"):
        make_refiner("ssd")
    with pytest.raises(InputError, match="needs model_path"):
        make_refiner("detector")
    with pytest.raises(InputError, match="takes no model file"):
        make_refiner("regressor", "x.onnx")


# --- acceptance rules with a scripted detector --------------------------------------------------------------------
class _Scripted:
    def __init__(self, boxes, scores):
        self.det = Detections(np.array(boxes, float).reshape(-1, 4), np.array(scores, float),
                              np.zeros(len(scores), int))
        self.regions = []

    def detect(self, image, region):
        self.regions.append(np.asarray(region))
        return self.det


IMAGE = np.full((240, 320, 3), 90, np.uint8)
BOX = np.array([100.0, 80.0, 30.0, 60.0])


def _refiner(boxes, scores, **settings):
    ref = DetectorRefiner(_Scripted(boxes, scores), DetectorRefinerSettings(**settings))
    ref.initialize(IMAGE, BOX)
    return ref


def test_frame_one_confidence_rules():
    assert _refiner([BOX], [0.9]).enabled  # conf > 0.83 and IoU 1 > 0.73
    assert not _refiner([BOX + [10, 0, 0, 0]], [0.9]).enabled  # IoU 0.5
    assert _refiner([BOX + [10, 0, 0, 0]], [0.96]).enabled  # conf > 0.95 whatever the IoU
    assert not _refiner([BOX], [0.8]).enabled
    assert _refiner([], [], require_initial_detection=False).enabled


def test_per_frame_acceptance():
    tight = BOX + [2, 3, -4, -6]
    ref = _refiner([tight], [0.9])
    np.testing.assert_allclose(ref.refine(IMAGE, BOX), tight)
    region = ref.detector.regions[-1]
    assert region[2] == region[3] == pytest.approx(4.0 * np.sqrt(30 * 60))  # ECO's square sample
    ref.refine(IMAGE, BOX, occluded=True)
    assert ref.detector.regions[-1][2] == pytest.approx(1.2 * region[2])
    # below 0.615, or not covering the centre, or beyond the limits: no refinement
    ref.detector.det = Detections(tight[None], np.array([0.6]), np.zeros(1, int))
    assert ref.refine(IMAGE, BOX) is None and "no confident" in ref.last_reason
    ref.detector.det = Detections(np.array([[140.0, 80, 30, 60]]), np.array([0.9]), np.zeros(1, int))
    assert ref.refine(IMAGE, BOX) is None and "no confident" in ref.last_reason
    ref.detector.det = Detections(np.array([[90.0, 60, 60, 100]]), np.array([0.9]), np.zeros(1, int))
    assert ref.refine(IMAGE, BOX) is None and "area ratio" in ref.last_reason
    # the most confident acceptable box wins
    ref.detector.det = Detections(np.array([[90.0, 60, 60, 100], tight, BOX]), np.array([0.99, 0.7, 0.8]),
                                  np.zeros(3, int))
    np.testing.assert_allclose(ref.refine(IMAGE, BOX), BOX)
