"""Finding a tracker's result files for a benchmark's sequences.

Trackers name their files differently (``JMMAC_<seq>.txt``, ``JMMAC_234_final_<seq>.txt``, ``<seq>.txt``), so a file
matches a sequence when its stem is the sequence name or ends with ``_<seq>``; when several sequence names fit
(``car`` and ``blackcar``: ``T_blackcar``), the longest wins. A ``prefix`` restricts matches to ``<prefix><seq>``.
"""

from __future__ import annotations

import os
from pathlib import Path

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError


def check_no_gaps(path: str | os.PathLike) -> None:
    """Refuse a box file with an empty line before its last row.

    Readers skip blank lines, so one in the middle would silently shift every later frame onto the previous frame's
    ground truth. Trailing blank lines are harmless. Missing files are left to the reader to report.

    Raises
    ------
    FileFormatError
        Naming the file and the first empty line.
    """
    path = Path(path)
    try:
        lines = path.read_bytes().decode("utf-8", errors="replace").splitlines()
    except OSError:
        return
    while lines and not lines[-1].strip():
        lines.pop()
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            raise FileFormatError(f"{path}, line {number}: empty line; every later row would be scored against the "
                                  f"wrong frame (write nan for a frame without a box)")


def match_sequence(stem: str, sequences: set[str], prefix: str | None = None) -> str | None:
    """The sequence a result file stem belongs to, or ``None``."""
    if prefix is not None:
        name = stem[len(prefix):] if stem.startswith(prefix) else None
        return name if name in sequences else None
    if stem in sequences:
        return stem
    start = stem.find("_")
    while start >= 0:  # earliest underscore first = longest candidate first
        candidate = stem[start + 1:]
        if candidate in sequences:
            return candidate
        start = stem.find("_", start + 1)
    return None


def find_result_files(
    folder: str | os.PathLike, sequences: list[str], prefix: str | None = None
) -> tuple[dict[str, Path], list[str]]:
    """Map each sequence to its result file in ``folder``; also return warnings about ambiguous files.

    Raises
    ------
    MissingFileError
        ``folder`` does not exist.
    InputError
        ``folder`` holds no ``.txt`` file matching any sequence (empty or wrong folder, or wrong ``--prefix``).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise MissingFileError(f"{folder}: no such results folder")
    wanted = set(sequences)
    found: dict[str, Path] = {}
    warnings: list[str] = []
    txt = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() == ".txt")
    for path in txt:
        seq = match_sequence(path.stem, wanted, prefix)
        if seq is None:
            continue
        if seq in found:
            keep = min(found[seq], path, key=lambda p: (p.stem != seq, p.name))
            warnings.append(f"{seq}: several result files ({found[seq].name}, {path.name}); using {keep.name}")
            path = keep
        found[seq] = path
    if not found:
        how = f"'{prefix}<sequence>.txt'" if prefix is not None else "'<sequence>.txt' or '<anything>_<sequence>.txt'"
        example = ", ".join(sequences[:3])
        raise InputError(
            f"{folder}: no result file for any of the {len(sequences)} sequences (expected {how}, e.g. {example}; "
            f"{len(txt)} .txt file(s) there); is this the right folder, --benchmark and --prefix?"
        )
    return found, warnings
