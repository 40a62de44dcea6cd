"""Graph rewrites of exported networks: the same outputs, fewer nodes."""

import numpy as np
import pytest

onnx = pytest.importorskip("onnx")
ort = pytest.importorskip("onnxruntime")
from onnx import TensorProto, helper, numpy_helper  # noqa: E402

from rgbt_toolkit.fusion.onnx_graph import fold_pads_into_convs  # noqa: E402
from rgbt_toolkit.fusion.onnx_model import SHALLOW_DEEP_ONNX, SHALLOW_ONNX, TRACKING_ONNX  # noqa: E402


def padded_conv_model(path, pad_value: float = 0.0, mode: str = "constant"):
    """x -> Pad (pads from a Constant node, as the exporter writes them, asymmetric as TF "SAME" at stride 2) ->
    Conv (stride 2, with pads of its own) -> y."""
    rng = np.random.default_rng(0)
    weight = numpy_helper.from_array(rng.standard_normal((4, 3, 3, 3)).astype(np.float32), "w")
    pads = helper.make_node("Constant", [], ["pads"], value=numpy_helper.from_array(
        np.array([0, 0, 0, 1, 0, 0, 1, 2], np.int64)))
    value = helper.make_node("Constant", [], ["value"], value=numpy_helper.from_array(np.array(pad_value, np.float32)))
    pad = helper.make_node("Pad", ["x", "pads", "value"], ["xp"], mode=mode)
    conv = helper.make_node("Conv", ["xp", "w"], ["y"], strides=[2, 2], pads=[1, 0, 0, 1])
    graph = helper.make_graph([pads, value, pad, conv], "g",
                              [helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, 3, "h", "w"])],
                              [helper.make_tensor_value_info("y", TensorProto.FLOAT, None)], initializer=[weight])
    onnx.save(helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)]), str(path))


def run(path, x):
    return ort.InferenceSession(str(path), providers=["CPUExecutionProvider"]).run(None, {"x": x})[0]


def test_a_zero_pad_folds_into_the_conv_with_the_same_output(tmp_path):
    path = tmp_path / "m.onnx"
    padded_conv_model(path)
    x = np.random.default_rng(1).random((1, 3, 11, 8)).astype(np.float32)
    before = run(path, x)
    model = onnx.load(str(path))
    assert fold_pads_into_convs(model) == 1
    onnx.save(model, str(path))
    ops = [n.op_type for n in onnx.load(str(path)).graph.node]
    assert ops == ["Conv"]  # the Pad and its constants are gone
    np.testing.assert_allclose(run(path, x), before, rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize("value, mode", [(1.0, "constant"), (0.0, "reflect")])
def test_pads_that_are_not_zeros_stay(tmp_path, value, mode):
    path = tmp_path / "m.onnx"
    padded_conv_model(path, value, mode)
    model = onnx.load(str(path))
    assert fold_pads_into_convs(model) == 0
    onnx.save(model, str(path))
    assert "Pad" in [n.op_type for n in onnx.load(str(path)).graph.node]


@pytest.mark.parametrize("shipped", [TRACKING_ONNX, SHALLOW_ONNX, SHALLOW_DEEP_ONNX])
def test_shipped_networks_have_no_pad_in_front_of_a_conv(shipped):
    graph = onnx.load(str(shipped)).graph
    pads = {n.output[0] for n in graph.node if n.op_type == "Pad"}
    assert not [n.name for n in graph.node if n.op_type == "Conv" and n.input[0] in pads]
