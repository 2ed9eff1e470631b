"""Atomic writes: nothing under the final name until complete, and finished files readable by others."""

from __future__ import annotations

import os
import stat

import pytest

from camgen.io.files import atomic_path, file_mode, write_text_atomic


def test_finished_files_are_not_private(tmp_path):
    write_text_atomic(tmp_path / "a.txt", "x")
    with atomic_path(tmp_path / "b.bin") as tmp:
        tmp.write_bytes(b"x")
    for name in ("a.txt", "b.bin"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == file_mode()


@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_finished_files_follow_the_umask(tmp_path, umask, mode):
    """A finished file has the permissions a file written in place would have under the user's umask."""
    previous = os.umask(umask)
    try:
        write_text_atomic(tmp_path / "a.txt", "x")
        with atomic_path(tmp_path / "b.bin") as tmp:
            tmp.write_bytes(b"x")
    finally:
        os.umask(previous)
    for name in ("a.txt", "b.bin"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == mode


def test_a_failed_write_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError), atomic_path(tmp_path / "c.bin") as tmp:
        tmp.write_bytes(b"partial")
        raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []


def test_an_interrupt_just_after_the_temporary_file_is_made_leaves_nothing(tmp_path, monkeypatch):
    """Ctrl-C or SIGTERM can land right after the temporary file exists (tempfile.mkstemp's window left
    it behind): the writer knows its name by then and removes it."""
    import camgen.io.files as files

    create = files._create_private

    def create_then_interrupt(tmp):
        os.close(create(tmp))
        raise KeyboardInterrupt

    monkeypatch.setattr(files, "_create_private", create_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        write_text_atomic(tmp_path / "a.txt", "x")
    with pytest.raises(KeyboardInterrupt), atomic_path(tmp_path / "b.bin") as tmp:
        tmp.write_bytes(b"x")
    assert list(tmp_path.iterdir()) == []
