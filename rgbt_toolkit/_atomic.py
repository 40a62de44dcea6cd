"""Atomic output: write to a temporary name in the target folder, then rename.

A crash or Ctrl-C therefore never leaves a half-written file under the final name.
"""

from __future__ import annotations

import contextlib
import errno
import os
import tempfile
from pathlib import Path
from typing import Iterator


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` when the block succeeds.

    An existing special file (``/dev/null``, a FIFO) is yielded itself: there is no half-written state to avoid.

    ``suffix`` defaults to the target's own suffix so writers that pick a format from the extension still work.
    """
    target = Path(path)
    if target.exists() and not target.is_file() and not target.is_dir():
        # a device or FIFO (-o /dev/null, -o /dev/stdout): write through; renaming would replace it with a plain file
        yield target
        return
    with _naming(target):
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp_name = tempfile.mkstemp(
            prefix=f".{target.stem}.", suffix=suffix if suffix is not None else target.suffix, dir=target.parent
        )
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        with _naming_failed_write(target):
            yield tmp
        with _naming(target):
            os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600 files; give outputs the usual permissions
            os.replace(tmp, target)
    finally:
        if tmp.exists():
            tmp.unlink()


@contextlib.contextmanager
def _naming(target: Path) -> Iterator[None]:
    """Report OS errors on the hidden temporary file under the name the user gave."""
    try:
        yield
    except OSError as exc:
        if exc.filename and Path(exc.filename).name.startswith(f".{target.stem}."):
            raise type(exc)(exc.errno, exc.strerror, str(target)) from None
        raise


@contextlib.contextmanager
def _naming_failed_write(target: Path) -> Iterator[None]:
    """Name ``target`` in a write error that names no file (a full disk or quota: ``No space left on device``)."""
    try:
        yield
    except OSError as exc:
        if exc.filename is None and exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG):
            raise OSError(exc.errno, exc.strerror, str(target)) from None
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def check_writable(path: str | os.PathLike, what: str = "output", *, overwrite: bool = False) -> Path:
    """Check, before any long work, that the file ``what`` can be written at ``path``; returns it as a Path.

    Raises :class:`~rgbt_toolkit.errors.InputError` when ``path`` is a folder, exists (unless ``overwrite``), or its
    nearest existing parent is a file or not writable. Missing parent folders are fine: writing creates them.
    """
    from rgbt_toolkit.errors import InputError

    path = Path(path)
    if path.exists() and not path.is_file() and not path.is_dir():
        return path  # a device or FIFO (-o /dev/null): written through, see atomic_path
    if path.is_dir():
        raise InputError(f"{path}: is a folder; give a file name for the {what}")
    if path.exists() and not overwrite:
        raise InputError(f"{path}: already exists; pass --force to overwrite")
    problem = _folder_problem(path.parent)
    if problem:
        raise InputError(f"{path}: cannot write the {what}: {problem}")
    return path


def nearest_existing(path: str | os.PathLike) -> Path:
    """``path`` itself, or its closest parent that exists (what decides whether ``path`` can be made)."""
    probe = Path(path)
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    return probe


def check_folder(folder: str | os.PathLike, what: str) -> None:
    """Refuse a folder that cannot be made or written in: it, or a parent, is a file (``OS: Not a directory``
    later), or the user may not write there (a read-only mount, another user's folder). Checked before the long work
    starts, so the run does not fail after it."""
    from rgbt_toolkit.errors import InputError

    problem = _folder_problem(folder)
    if problem:
        raise InputError(f"{folder}: cannot write the {what} there: {problem}")


def _folder_problem(folder: str | os.PathLike) -> str | None:
    """Why ``folder`` cannot be made or written in (its nearest existing part is a file, or not writable), or None."""
    probe = nearest_existing(folder)
    if probe.exists() and not probe.is_dir():
        return f"{probe} is a file, not a folder"
    if probe.is_dir() and not os.access(probe, os.W_OK | os.X_OK):
        return f"no permission to write in {probe}"
    return None
