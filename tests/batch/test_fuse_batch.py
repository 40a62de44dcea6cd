"""``rgbt batch fuse``: every pair of two folders fused with MFNet, the same as fusing each pair directly."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io.images import read_image, write_image

fusion = pytest.importorskip("rgbt_toolkit.fusion.image_fusion")


@pytest.fixture()
def heads_file(tmp_path):
    """Untrained heads: the batch must reproduce whatever the network does, trained or not."""
    import torch

    from rgbt_toolkit.fusion.network import HeadConfig, MFNetHeads
    from rgbt_toolkit.fusion.weights_io import save_heads

    torch.manual_seed(0)
    path = tmp_path / "heads.pt"
    save_heads(path, MFNetHeads(HeadConfig()))
    return path


def test_batch_fuse_matches_fusing_each_pair(tmp_path, heads_file):
    from rgbt_toolkit.batch import tasks

    rng = np.random.default_rng(0)
    for stem in ("a", "b", "c"):
        write_image(tmp_path / "vis" / f"{stem}.png", rng.integers(0, 255, (48, 64, 3), dtype=np.uint8))
        write_image(tmp_path / "ir" / f"{stem}.png", rng.integers(0, 255, (48, 64), dtype=np.uint8))
    write_image(tmp_path / "ir" / "lonely.png", np.zeros((48, 64), np.uint8))
    result = CliRunner().invoke(main, ["batch", "fuse", str(tmp_path / "vis"), str(tmp_path / "ir"), "-o",
                                       str(tmp_path / "out"), "--weights", str(heads_file), "--in-process",
                                       "--save-weights"])
    assert result.exit_code == 0, result.output
    assert "lonely.png: no partner found" in result.stderr and "3 done" in result.stdout
    net = tasks._NETS[str(heads_file)]  # the network the in-process batch built from the file
    for stem in ("a", "b", "c"):
        direct = fusion.fuse_images(read_image(tmp_path / "vis" / f"{stem}.png"),
                                    read_image(tmp_path / "ir" / f"{stem}.png"), net)
        np.testing.assert_array_equal(read_image(tmp_path / "out" / f"{stem}.png"), direct.fused)
        assert (tmp_path / "out" / f"{stem}_weights.png").is_file()


@pytest.mark.parametrize("extra", [[], ["--overwrite"]])
def test_batch_fuse_never_writes_over_an_input_image(tmp_path, heads_file, extra):
    vis, ir = tmp_path / "vis", tmp_path / "ir"
    write_image(vis / "a.png", np.full((32, 32, 3), 7, np.uint8))
    write_image(ir / "a.png", np.full((32, 32), 9, np.uint8))
    before = (vis / "a.png").read_bytes()
    result = CliRunner().invoke(main, ["batch", "fuse", str(vis), str(ir), "-o", str(vis), "--weights",
                                       str(heads_file), "--in-process", *extra])
    assert result.exit_code == 1
    assert "would overwrite an input image; choose another output" in result.stderr
    assert (vis / "a.png").read_bytes() == before


def test_batch_fuse_refuses_two_inputs_sharing_a_stem(tmp_path, heads_file):
    vis, ir = tmp_path / "vis", tmp_path / "ir"
    write_image(vis / "a.png", np.full((32, 32, 3), 7, np.uint8))
    write_image(vis / "a.jpg", np.full((32, 32, 3), 7, np.uint8))
    write_image(ir / "a.png", np.full((32, 32), 9, np.uint8))
    result = CliRunner().invoke(main, ["batch", "fuse", str(vis), str(ir), "-o", str(tmp_path / "out"),
                                       "--weights", str(heads_file), "--in-process"])
    assert result.exit_code == 1 and "two images with the stem 'a'" in result.stderr
    assert not (tmp_path / "out").exists()


def test_output_folder_under_a_file_is_one_line(tmp_path, heads_file):
    write_image(tmp_path / "vis" / "a.png", np.full((32, 32, 3), 7, np.uint8))
    write_image(tmp_path / "ir" / "a.png", np.full((32, 32), 9, np.uint8))
    (tmp_path / "afile").write_text("x")
    for command in (["batch", "fuse", "--in-process", "--weights", str(heads_file)],
                    ["fuse", "--weights", str(heads_file)]):
        result = CliRunner().invoke(main, [*command, str(tmp_path / "vis"), str(tmp_path / "ir"), "-o",
                                           str(tmp_path / "afile" / "out")])
        assert result.exit_code == 1 and "afile is a file, not a folder" in result.stderr, result.output
