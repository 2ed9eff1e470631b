"""Atomic writes: nothing under the final name until complete, and finished files readable by others."""

from __future__ import annotations

import stat

import pytest

from camgen.io.files import FILE_MODE, atomic_path, write_text_atomic


def test_finished_files_are_not_private(tmp_path):
    write_text_atomic(tmp_path / "a.txt", "x")
    with atomic_path(tmp_path / "b.bin") as tmp:
        tmp.write_bytes(b"x")
    for name in ("a.txt", "b.bin"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == FILE_MODE


def test_a_failed_write_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError), atomic_path(tmp_path / "c.bin") as tmp:
        tmp.write_bytes(b"partial")
        raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []
