"""Image reading edge cases."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from rgbt_toolkit.io.images import read_image


def test_cmyk_jpeg_is_read_as_its_rgb_colours(tmp_path):
    rgb = np.zeros((16, 16, 3), np.uint8)
    rgb[:, :8] = (200, 40, 40)
    rgb[:, 8:] = (30, 160, 220)
    Image.fromarray(rgb).convert("CMYK").save(tmp_path / "cmyk.jpg", quality=95)
    back = read_image(tmp_path / "cmyk.jpg")
    assert back.shape == (16, 16, 3)
    assert np.abs(back.astype(int) - rgb).mean() < 6  # JPEG loss only, not CMY read as RGB


def test_empty_file_is_a_one_line_error_without_a_leaked_handle(tmp_path):
    """imageio failing on an empty file left its handle open (a ResourceWarning, an error under pytest)."""
    from rgbt_toolkit.errors import FileFormatError

    empty = tmp_path / "empty.png"
    empty.write_bytes(b"")
    with pytest.raises(FileFormatError, match="empty.png: empty file"):
        read_image(empty)
