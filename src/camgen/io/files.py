"""File writing that never leaves a partial file under the final name, and the checks that find a
path camgen cannot read or write before any work is done.

The temporary file is private (0600); a finished file gets `file_mode()`,
what a file written in place would get under the user's umask (rw-r--r-- under the usual 022), so
datasets can be shared as the user's other files are.
"""

from __future__ import annotations

import os
import secrets
import stat
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


def file_mode() -> int:
    """Permissions of a finished file: 0666 less the process's umask (read without changing it for
    longer than the two calls)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


def file_kind(mode: int) -> str:
    """What an `os.stat` mode is, as a message names it: "a file", "a directory", "a FIFO (named pipe)"…"""
    kinds = (
        (stat.S_ISREG, "a file"),
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISSOCK, "a socket"),
    )
    return next((name for test, name in kinds if test(mode)), "not a regular file")


def _size_text(size_bytes: int) -> str:
    for unit, scale in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if size_bytes >= scale:
            return f"{size_bytes / scale:.3g} {unit}"
    return f"{size_bytes} bytes"


def input_file_problem(path: str | Path, *, max_bytes: int | None = None, what: str = "file") -> str | None:
    """Why `path` cannot be read as a regular file of at most `max_bytes`, or None when it can.

    Checked with `os.stat` before the file is opened: opening a FIFO that has no writer blocks for
    ever, and a device such as /dev/zero never ends. The reason follows the path in a message:
    ``no such file``, ``is a directory, not a file``, ``is 1 GiB, more than a YAML config may be (16 MiB)``.
    """
    try:
        info = os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        return "no such file"
    except OSError as exc:
        return f"cannot read: {exc.strerror or exc}"
    if stat.S_ISDIR(info.st_mode):
        return "is a directory, not a file"
    if not stat.S_ISREG(info.st_mode):
        return f"is {file_kind(info.st_mode)}, not a regular file"
    if max_bytes is not None and info.st_size > max_bytes:
        return f"is {_size_text(info.st_size)}, more than a {what} may be ({_size_text(max_bytes)})"
    return None


def _existing(path: Path) -> os.stat_result | None:
    """`os.stat(path)`, or None for a path that is not there (or cannot be looked at: the ancestor
    that can then says why)."""
    try:
        return os.stat(path)
    except OSError:
        return None


def _cannot_make_directory_in(directory: Path) -> str | None:
    """Why no directory can be made in `directory` (the system's reason), found by making one and
    removing it again: permissions, read-only mounts and pseudo file systems (/proc) answer only to
    trying. None when one can."""
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".camgen-probe-", dir=directory))
    except OSError as exc:
        return exc.strerror or str(exc)
    return None


def output_directory_problem(path: str | Path) -> str | None:
    """Why `path` cannot be the directory outputs are written into (made, with its parents, if
    missing), or None when it can. The reason follows the path in a message: ``is a file``,
    ``cannot be created: /dev/null is a character device, not a directory``."""
    path = Path(path)
    info = _existing(path)
    if info is not None:
        if not stat.S_ISDIR(info.st_mode):
            return f"is {file_kind(info.st_mode)}"
        reason = _cannot_make_directory_in(path)
        return f"is not writable ({reason})" if reason else None
    for missing, ancestor in zip((path, *path.parents), path.parents, strict=False):
        if os.path.islink(missing):
            return f"cannot be created: {missing} is a symbolic link to {os.readlink(missing)}, which does not exist"
        info = _existing(ancestor)
        if info is None:
            continue
        if not stat.S_ISDIR(info.st_mode):
            return f"cannot be created: {ancestor} is {file_kind(info.st_mode)}, not a directory"
        reason = _cannot_make_directory_in(ancestor)
        return f"cannot be created in {ancestor} ({reason})" if reason else None
    return None


def output_file_problem(path: str | Path) -> str | None:
    """Why `path` cannot be written as a file (replacing a file there), or None when it can. The
    reason follows the path in a message: ``is a directory``, ``is a character device``."""
    path = Path(path)
    info = _existing(path)
    if info is not None and not stat.S_ISREG(info.st_mode):
        return f"is {file_kind(info.st_mode)}"
    problem = output_directory_problem(path.parent)
    return f"cannot be written: its directory {path.parent} {problem}" if problem else None


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write `text` to a temporary file beside `path`, then rename it into place."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(8)}.partial")
    try:
        with os.fdopen(_create_private(tmp), "w", encoding="utf-8") as handle:
            handle.write(text)
        os.chmod(tmp, file_mode())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary path beside `path` to write to; renamed to `path` only if the block succeeds.

    The temporary name keeps the suffix, so writers that choose a format by extension still work.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.{secrets.token_hex(8)}.partial{path.suffix}")
    try:
        os.close(_create_private(tmp))
        yield tmp
        os.chmod(tmp, file_mode())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _create_private(tmp: Path) -> int:
    """Create the temporary file `tmp` (0600, failing if it exists) and return its descriptor.

    The name is chosen (64 random bits) before the file exists and the file is made inside the
    writer's ``try``, so an interrupt (Ctrl-C, SIGTERM) anywhere after its creation removes it;
    `tempfile.mkstemp` creates the file before its caller learns the name, and an interrupt in
    between left the file behind.
    """
    return os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
