"""Folder mode: pair fused images with their sources by file stem and score every triple.

A fused file pairs with the visible/infrared images of stem ``S`` when it is named ``S.<ext>`` (method '') or
``S_<method>.<ext>``; method names may themselves contain underscores (``HMSD_GF``), so the longest matching source
stem wins. Problems with one image (missing partner, unreadable file, size mismatch) are collected and the rest
is still scored.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError, RgbtError
from rgbt_toolkit.io.images import list_images, natural_key, read_image
from rgbt_toolkit.io.pixels import as_uint8
from rgbt_toolkit.metrics.conventions import Convention, get_convention, score_triple


@dataclass(frozen=True)
class Triple:
    """One fused image and the sources it was made from."""

    image: str
    method: str
    visible: Path
    infrared: Path
    fused: Path


@dataclass
class ScoreTable:
    """Scores per fused image, per-method means and the problems met on the way."""

    convention: str
    metrics: list[str]
    rows: list[dict] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)

    def means(self) -> list[dict]:
        """One row per method: the mean of each metric over that method's images."""
        methods = sorted({row["method"] for row in self.rows}, key=natural_key)
        out = []
        for method in methods:
            rows = [row for row in self.rows if row["method"] == method]
            entry = {"image": "mean", "method": method, "count": len(rows)}
            entry.update({m: float(np.mean([row[m] for row in rows])) for m in self.metrics})
            out.append(entry)
        return out


def _files(path: Path) -> list[Path]:
    if path.is_dir():
        return list_images(path)
    if path.is_file():
        return [path]
    raise MissingFileError(f"{path}: no such file or folder")


def pair_by_stem(visible: str | os.PathLike, infrared: str | os.PathLike, fused: str | os.PathLike
                 ) -> tuple[list[Triple], list[str]]:
    """Match every fused image to a visible and an infrared image; return (triples, problems).

    Paths may be files or folders. A fused image without a source stem, or whose stem lacks one of the two
    sources, becomes a problem naming the file.
    """
    vis_files, ir_files, fused_files = (_files(Path(p)) for p in (visible, infrared, fused))
    for files, where in ((vis_files, visible), (ir_files, infrared), (fused_files, fused)):
        if not files:
            raise InputError(f"{where}: no images found (PNG, JPEG, BMP or TIFF)")
    vis = {p.stem: p for p in vis_files}
    ir = {p.stem: p for p in ir_files}
    stems = sorted(set(vis) | set(ir), key=len, reverse=True)
    single_source = Path(visible).is_file() and Path(infrared).is_file()
    triples, problems = [], []
    for path in fused_files:
        stem = path.stem
        if single_source:  # one pair given explicitly: every fused file belongs to it
            base = vis_files[0].stem
            method = stem[len(base) + 1 :] if stem.startswith(base + "_") else ""
            triples.append(Triple(base, method, vis_files[0], ir_files[0], path))
            continue
        match = next((s for s in stems if stem == s or stem.startswith(s + "_")), None)
        if match is None:
            problems.append(f"{path}: no visible/infrared image with a matching stem (expected <stem>.<ext> "
                            f"or <stem>_<method>.<ext>)")
            continue
        method = stem[len(match) + 1 :] if stem != match else ""
        missing = [name for name, table in (("visible", vis), ("infrared", ir)) if match not in table]
        if missing:
            problems.append(f"{path}: no {' or '.join(missing)} image with stem '{match}'")
            continue
        triples.append(Triple(match, method, vis[match], ir[match], path))
    triples.sort(key=lambda t: (natural_key(t.image), natural_key(t.method)))
    return triples, problems


def read_scored_image(path: str | os.PathLike) -> np.ndarray:
    """Read an image file as the metrics take it.

    A float file holding 0..1 (the usual float TIFF) is brought to 8 bits as ``rgbt fuse`` reads it
    (:func:`rgbt_toolkit.io.pixels.as_uint8`); scored as it is, its entropy and gradients would be those of an
    almost black image. Other files are returned as decoded (the metrics refuse floats outside 0..255).
    """
    image = read_image(path)
    if np.issubdtype(image.dtype, np.floating):
        finite = image[np.isfinite(image)]
        if finite.size and finite.min() >= 0.0 and finite.max() <= 1.0:
            return as_uint8(image, str(path))
    return image


def score_folders(
    visible: str | os.PathLike,
    infrared: str | os.PathLike,
    fused: str | os.PathLike,
    convention: str = "paper",
    metrics: list[str] | None = None,
    progress: Callable[[int], None] | None = None,
) -> ScoreTable:
    """Score every fused image found under ``fused`` (file or folder) against its sources.

    Parameters
    ----------
    visible, infrared, fused : path
        Files or folders of images (PNG, JPEG, BMP, TIFF; grey or colour).
    convention : str
        'paper', 'vifb' or 'standard'.
    metrics : list of str, optional
        Metric names (the convention's default set when omitted); unknown names raise :class:`InputError`.
    progress : callable, optional
        Called with 1 after each fused image (e.g. a tqdm bar's ``update``).

    Returns
    -------
    ScoreTable
        Rows for the images that could be scored; ``errors`` lists one line per image that could not.
    """
    conv: Convention = get_convention(convention)
    names = list(metrics) if metrics else list(conv.default_metrics)
    for name in names:
        conv.metric(name)  # unknown names fail before any work
    triples, problems = pair_by_stem(visible, infrared, fused)
    table = ScoreTable(convention=conv.name, metrics=names, errors=list(problems))
    cache: dict[Path, np.ndarray] = {}  # the current sources: triples are sorted by image

    def load(path: Path) -> np.ndarray:
        if path not in cache:
            if len(cache) >= 2:
                cache.clear()
            cache[path] = read_scored_image(path)
        return cache[path]

    for triple in triples:
        try:
            values = score_triple(load(triple.visible), load(triple.infrared), read_scored_image(triple.fused), conv,
                                  names)
        except (FileFormatError, MissingFileError) as exc:  # unreadable or missing file: the message names it
            table.errors.append(str(exc))
        except InputError as exc:
            table.errors.append(f"{triple.fused}: {exc}")
        except RgbtError as exc:
            table.errors.append(str(exc))
        else:
            table.rows.append({"image": triple.image, "method": triple.method, **values})
        if progress is not None:
            progress(1)
    return table
