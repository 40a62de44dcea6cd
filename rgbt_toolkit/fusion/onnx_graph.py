"""Rewrites of exported ONNX graphs that change nothing they compute but how fast or small they are.

The exporter writes each layer's TF-"SAME" padding as a Pad node (fed by a small subgraph of shape constants) in
front of its Conv. On a CPU, ONNX Runtime runs convolutions in a blocked channel layout (NCHWc) and must convert every
tensor back to plain NCHW for each Pad and again after it: 29 layout conversions in the 128 px MFNet, about a quarter
of its run time. Folding the (constant, zero) padding into the Conv's own ``pads`` removes them all.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _constant_value(graph, name: str, producers: dict, initializers: dict, inputs: set,
                    opsets: dict) -> np.ndarray | None:
    """The value of tensor ``name`` when it depends on no graph input (evaluated with ONNX's reference runtime)."""
    from onnx import helper, numpy_helper
    from onnx.reference import ReferenceEvaluator

    if name in initializers:
        return numpy_helper.to_array(initializers[name])
    needed, stack, used_inits = set(), [name], {}
    while stack:
        tensor = stack.pop()
        if tensor in inputs:
            return None
        if tensor in initializers:
            used_inits[tensor] = initializers[tensor]
            continue
        node = producers.get(tensor)
        if node is None:
            return None
        if id(node) not in needed:
            needed.add(id(node))
            stack.extend(i for i in node.input if i)
    nodes = [n for n in graph.node if id(n) in needed]  # graph order is topological
    sub = helper.make_graph(nodes, "constant", [], [helper.make_empty_tensor_value_info(name)],
                            initializer=list(used_inits.values()))
    return np.asarray(ReferenceEvaluator(sub, opsets=opsets).run(None, {})[0])


def optimise_export(path: str | Path) -> None:
    """Rewrite an exported file in place: :func:`fold_pads_into_convs`, then :func:`store_exact_halves` (one load,
    one atomic save)."""
    import onnx

    from rgbt_toolkit._atomic import atomic_path

    model = onnx.load(str(path))
    fold_pads_into_convs(model)
    store_exact_halves(model)
    with atomic_path(path) as tmp:
        onnx.save(model, str(tmp))


def fold_pads_into_convs(model) -> int:
    """Merge every zero ``Pad`` of the ``onnx.ModelProto`` whose only reader is a ``Conv`` into that Conv's ``pads``
    (in place); returns how many."""
    from onnx import helper

    graph = model.graph
    initializers = {t.name: t for t in graph.initializer}
    producers = {out: node for node in graph.node for out in node.output}
    readers: dict[str, list] = {}
    for node in graph.node:
        for name in node.input:
            readers.setdefault(name, []).append(node)
    inputs = {i.name for i in graph.input}
    outputs = {o.name for o in graph.output}
    opsets = {o.domain: o.version for o in model.opset_import}
    folded = []
    for node in graph.node:
        if node.op_type != "Pad" or node.output[0] in outputs:
            continue
        attrs = {a.name: helper.get_attribute_value(a) for a in node.attribute}
        users = readers.get(node.output[0], [])
        if attrs.get("mode", b"constant") not in (b"constant", "constant") or len(users) != 1 or \
                users[0].op_type != "Conv" or len(node.input) > 3 and node.input[3]:
            continue
        pads = _constant_value(graph, node.input[1], producers, initializers, inputs, opsets)
        value = _constant_value(graph, node.input[2], producers, initializers, inputs, opsets) \
            if len(node.input) > 2 and node.input[2] else np.zeros(1)
        if pads is None or value is None or pads.size != 8 or np.any(value != 0) or np.any(pads[[0, 1, 4, 5]]) \
                or np.any(pads < 0):
            continue
        conv = users[0]
        if any(a.name == "auto_pad" and a.s not in (b"", b"NOTSET") for a in conv.attribute):
            continue  # the Conv pads itself by the input size: nothing static to add to
        old = next((a for a in conv.attribute if a.name == "pads"), None)
        current = list(old.ints) if old is not None and list(old.ints) else [0, 0, 0, 0]
        merged = [current[0] + int(pads[2]), current[1] + int(pads[3]), current[2] + int(pads[6]),
                  current[3] + int(pads[7])]
        if old is not None:
            conv.attribute.remove(old)
        conv.attribute.append(helper.make_attribute("pads", merged))
        conv.input[0] = node.input[0]
        folded.append(node)
    for node in folded:
        graph.node.remove(node)
    if folded:
        _drop_unused(graph)
    return len(folded)


def _drop_unused(graph) -> None:
    """Remove nodes and initializers nothing reads any more (the folded pads' shape subgraphs)."""
    while True:
        read = {name for node in graph.node for name in node.input} | {o.name for o in graph.output}
        dead = [node for node in graph.node if not any(out in read for out in node.output)]
        if not dead:
            break
        for node in dead:
            graph.node.remove(node)
    read = {name for node in graph.node for name in node.input}
    for tensor in [t for t in graph.initializer if t.name not in read]:
        graph.initializer.remove(tensor)


def store_exact_halves(model) -> None:
    """Store every float32 weight of the ``onnx.ModelProto`` that float16 holds exactly (the MFNet heads are saved in
    float16) as float16 plus a Cast node (in place): the same values at run time (ONNX Runtime folds the casts when it
    loads), half the bytes on disk (the shipped tracking network 7.1 -> 5.0 MB)."""
    import onnx
    from onnx import helper, numpy_helper

    casts = []
    for tensor in model.graph.initializer:
        values = numpy_helper.to_array(tensor)
        if values.dtype != np.float32 or not np.array_equal(values.astype(np.float16).astype(np.float32), values):
            continue
        name = tensor.name
        tensor.CopyFrom(numpy_helper.from_array(values.astype(np.float16), f"{name}__f16"))
        casts.append(helper.make_node("Cast", [f"{name}__f16"], [name], to=onnx.TensorProto.FLOAT))
    nodes = casts + list(model.graph.node)  # the casts first: nodes are in topological order
    del model.graph.node[:]
    model.graph.node.extend(nodes)
