"""manifest.json: what a job directory holds, and a check that it still holds exactly that.

The manifest records the camgen version that wrote the files, the job id (the Job's content hash), the
scene, the plan settings, every camera's resolved profile and serial, and a table of every file in the
job directory with its SHA-256 and size. It carries no timestamp, host or user: the same job rendered
twice gives byte-identical files and so a byte-identical manifest, which makes the manifest itself
comparable between runs and machines.

Layout (keys sorted, one-space indent, a final newline)::

    {
     "cameras": [{"name": "cam", "profile": {...}, "profile_name": "fixed", "serial": 1234}],
     "camgen_version": "0.1.0",
     "files": {
      "cam/camera.jsonl": {"sha256": "9f2c…", "size_bytes": 40211},
      "cam/video.mp4": {"sha256": "4be0…", "size_bytes": 1093344},
      "job.json": {"sha256": "07aa…", "size_bytes": 151872}
     },
     "fps": 10.0,
     "frame_count": 10,
     "job_id": "c7e150fa…",
     "manifest_version": 1,
     "scene": {...},
     "scene_name": "walk",
     "seed": 1,
     "settings": {...}
    }
"""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Callable, Collection
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING, Any, Literal

import camgen
from camgen.errors import ConfigError
from camgen.io.files import write_text_atomic

if TYPE_CHECKING:
    from camgen.job import Job

MANIFEST_NAME = "manifest.json"
JOB_NAME = "job.json"
JOB_DIRECTORY_NAME = re.compile(r".+-[0-9a-f]{8}")
"""`<scene>-<hash8>`, as `camgen.plan.execute.job_directory_name` names a job's directory."""
MANIFEST_VERSION = 1
"""Version of the manifest layout; bumped when a reader would misread an older one."""
CHUNK_BYTES = 1 << 20
"""Files are hashed in pieces of this size, so a long video never sits in memory whole."""

ProgressCallback = Callable[[int, int], None]
"""Called as ``on_progress(bytes_done, bytes_total)`` while files are hashed."""

ProblemKind = Literal["manifest", "missing", "modified", "extra", "unreadable"]


@dataclass(frozen=True)
class FileProblem:
    """One way a job directory differs from its manifest.

    path: the file's path relative to the job directory, POSIX style (``cam/video.mp4``); for a
    problem with the manifest itself, ``manifest.json``. kind: ``manifest`` (missing or unreadable
    manifest; nothing else was checked), ``missing`` (listed, not on disk), ``modified`` (size or
    SHA-256 differs), ``extra`` (on disk, not listed: a stray partial write, a file added later),
    ``unreadable`` (listed and present, but reading it failed). message: what is wrong, for people.
    """

    path: str
    kind: ProblemKind
    message: str

    def __str__(self) -> str:
        return f"{self.path}: {self.kind}: {self.message}"


def build_manifest(
    job: Job,
    job_dir: str | Path,
    *,
    rendered: dict | None = None,
    on_progress: ProgressCallback | None = None,
    exclude: Collection[str] = (),
) -> dict[str, Any]:
    """The manifest of `job` rendered into `job_dir`: resolved configuration and every file's hash.

    Every regular file under `job_dir` is listed, except ``manifest.json`` at its top and the relative POSIX
    paths in `exclude` (files the writer deletes once the manifest is written: a render's checkpoints).
    Deterministic: the same job and the same file contents give an equal dict, and `manifest_text` of it the
    same bytes.
    """
    job_dir = Path(job_dir)
    config = job.model_dump(
        mode="json",
        by_alias=True,
        include={
            "scene_name": True,
            "scene": True,
            "settings": True,
            "frame_count": True,
            "fps": True,
            "seed": True,
            "job_id": True,
            "cameras": {"__all__": {"name", "profile_name", "profile", "serial"}},
        },
    )
    paths = [name for name in _files_on_disk(job_dir) if name not in exclude]
    sizes = {name: (job_dir / name).stat().st_size for name in paths}
    progress = _Progress(sum(sizes.values()), on_progress)
    files = {}
    for name in paths:
        files[name] = {"sha256": file_sha256(job_dir / name, progress.advance), "size_bytes": sizes[name]}
    return {
        "manifest_version": MANIFEST_VERSION,
        "camgen_version": camgen.__version__,
        **config,
        **({} if rendered is None else {"rendered": rendered}),
        "files": files,
    }


def manifest_text(manifest: dict[str, Any]) -> str:
    """The canonical JSON of a manifest: sorted keys, one-space indent, UTF-8 text, final newline."""
    return json.dumps(manifest, sort_keys=True, indent=1, ensure_ascii=False) + "\n"


def write_manifest(
    job: Job,
    job_dir: str | Path,
    *,
    rendered: dict | None = None,
    on_progress: ProgressCallback | None = None,
    exclude: Collection[str] = (),
) -> Path:
    """Write ``job_dir/manifest.json`` atomically and return its path.

    Call it last, after job.json: it hashes what is in `job_dir` now (less `exclude`: `build_manifest`), and
    any file written after it will read as modified or extra to `verify`.
    """
    path = Path(job_dir) / MANIFEST_NAME
    manifest = build_manifest(job, job_dir, rendered=rendered, on_progress=on_progress, exclude=exclude)
    write_text_atomic(path, manifest_text(manifest))
    return path


def read_manifest(job_dir: str | Path) -> tuple[dict[str, Any] | None, list[FileProblem]]:
    """The manifest of `job_dir` and its problems: (manifest, []) if it is usable, else (None, problems)."""
    path = Path(job_dir) / MANIFEST_NAME

    def problem(message: str) -> tuple[None, list[FileProblem]]:
        return None, [FileProblem(MANIFEST_NAME, "manifest", message)]

    if not path.is_file():
        return problem("missing: the render did not finish, or wrote no manifest; nothing was checked")
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as exc:
        return problem(f"not UTF-8 text ({exc.reason} at byte {exc.start}); nothing was checked")
    except json.JSONDecodeError as exc:
        return problem(f"not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg}); nothing was checked")
    except OSError as exc:
        return problem(f"cannot be read ({exc.strerror}); nothing was checked")
    if not isinstance(manifest, dict) or not isinstance(manifest.get("files"), dict):
        return problem("not a camgen manifest: it has no 'files' table; nothing was checked")
    problems = [
        FileProblem(MANIFEST_NAME, "manifest", message)
        for name, entry in manifest["files"].items()
        if (message := _entry_problem(name, entry)) is not None
    ]
    return (None, problems) if problems else (manifest, [])


def verify(job_dir: str | Path, *, on_progress: ProgressCallback | None = None) -> list[FileProblem]:
    """Compare `job_dir` with its manifest.json; an empty list means every file is as recorded.

    Reports, in path order: files listed but missing, files whose size or SHA-256 differs, files on
    disk but not listed, files that cannot be read; or, alone, a manifest that is missing or unreadable.
    on_progress(bytes_done, bytes_total) follows the hashing.
    """
    job_dir = Path(job_dir)
    manifest, problems = read_manifest(job_dir)
    if manifest is None:
        return problems
    expected: dict[str, dict[str, Any]] = manifest["files"]
    on_disk = set(_files_on_disk(job_dir))
    progress = _Progress(sum(entry["size_bytes"] for entry in expected.values()), on_progress)
    for name in sorted(on_disk | set(expected)):
        entry = expected.get(name)
        if entry is None:
            problems.append(FileProblem(name, "extra", "on disk but not in the manifest"))
            continue
        if name not in on_disk:
            problems.append(FileProblem(name, "missing", "in the manifest but not on disk"))
            progress.advance(entry["size_bytes"])  # counted as done, so the bar still ends full
            continue
        path = job_dir / name
        try:
            size_bytes = path.stat().st_size
            if size_bytes != entry["size_bytes"]:
                problems.append(
                    FileProblem(name, "modified", f"size {size_bytes} B, the manifest says {entry['size_bytes']} B")
                )
                progress.advance(entry["size_bytes"])
                continue
            digest = file_sha256(path, progress.advance)
        except OSError as exc:
            problems.append(FileProblem(name, "unreadable", exc.strerror or str(exc)))
            continue
        if digest != entry["sha256"]:
            problems.append(
                FileProblem(
                    name,
                    "modified",
                    f"content differs: SHA-256 {digest[:12]}…, the manifest says {entry['sha256'][:12]}…",
                )
            )
    return problems


def find_job_directories(path: str | Path) -> list[Path]:
    """The job directories `path` names: itself, or the job directories directly inside it.

    A job directory has manifest.json or job.json, or a `<scene>-<hash8>` name: a render that stopped
    before its manifest is still found, and then fails `verify`. A path to a manifest.json file names
    its directory. Raises ConfigError when `path` is missing, another file, or holds no job directory.
    """
    path = Path(path)
    if not path.exists():
        raise ConfigError(f"{path}: no such file or directory")
    if path.is_file():
        if path.name == MANIFEST_NAME:
            return [path.parent]
        raise ConfigError(f"{path}: is a file; give a job directory (with {MANIFEST_NAME}) or a directory of them")
    if _has_job_files(path):
        return [path]
    jobs = [
        child
        for child in sorted(path.iterdir())
        if child.is_dir() and (_has_job_files(child) or JOB_DIRECTORY_NAME.fullmatch(child.name))
    ]
    if jobs:
        return jobs
    if JOB_DIRECTORY_NAME.fullmatch(path.name):
        return [path]
    raise ConfigError(
        f"{path}: nothing to verify: no {MANIFEST_NAME} or {JOB_NAME} in it or in a directory directly inside it; "
        "give the job directory a render wrote (<scene>-<hash8>) or the directory holding them"
    )


def file_sha256(path: str | Path, on_chunk: Callable[[int], None] | None = None) -> str:
    """Hex SHA-256 of a file, read in `CHUNK_BYTES` pieces; on_chunk(bytes) after each piece."""
    digest = hashlib.sha256()
    buffer = bytearray(CHUNK_BYTES)
    view = memoryview(buffer)
    with open(path, "rb") as handle:
        while count := handle.readinto(buffer):
            digest.update(view[:count])
            if on_chunk is not None:
                on_chunk(count)
    return digest.hexdigest()


def _files_on_disk(job_dir: Path) -> list[str]:
    """Relative POSIX paths of the regular files under `job_dir`, sorted, without the manifest."""
    names = (path.relative_to(job_dir).as_posix() for path in job_dir.rglob("*") if path.is_file())
    return sorted(name for name in names if name != MANIFEST_NAME)


def _has_job_files(directory: Path) -> bool:
    return (directory / MANIFEST_NAME).is_file() or (directory / JOB_NAME).is_file()


def _entry_problem(name: str, entry: Any) -> str | None:
    """Why a row of a manifest's files table is unusable, or None."""
    posix = PurePosixPath(name)
    if not name or posix.is_absolute() or ".." in posix.parts or "\\" in name or name != posix.as_posix():
        return f"files[{name!r}]: not a relative path inside the job directory"
    if not isinstance(entry, dict):
        return f"files[{name!r}]: must be an object with sha256 and size_bytes"
    digest, size_bytes = entry.get("sha256"), entry.get("size_bytes")
    if not (isinstance(digest, str) and len(digest) == 64 and all(c in "0123456789abcdef" for c in digest)):
        return f"files[{name!r}].sha256 must be 64 lowercase hex digits, got {digest!r}"
    if not (isinstance(size_bytes, int) and not isinstance(size_bytes, bool) and size_bytes >= 0):
        return f"files[{name!r}].size_bytes must be an integer ≥ 0, got {size_bytes!r}"
    return None


class _Progress:
    """Bytes hashed so far against a total, reported through an optional callback."""

    def __init__(self, total_bytes: int, callback: ProgressCallback | None):
        self.total_bytes, self.done_bytes, self.callback = total_bytes, 0, callback
        self._report()

    def advance(self, count: int) -> None:
        self.done_bytes += count
        self._report()

    def _report(self) -> None:
        if self.callback is not None:
            self.callback(self.done_bytes, self.total_bytes)
