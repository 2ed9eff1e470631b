"""What a local pool worker finds when it starts, for tests/batch/test_pool_workers.py. Stdlib only: unpickling
`probe` in a worker imports this module, which must not import what it checks for."""

from __future__ import annotations

import multiprocessing.forkserver
import os
import sys
import threading
from pathlib import Path


def threads_of(pid: int) -> int:
    """The number of threads of process `pid` (native ones included)."""
    return len(list(Path(f"/proc/{pid}/task").iterdir()))


def maps_of(pid: int) -> str:
    return Path(f"/proc/{pid}/maps").read_text()


def probe(modules: tuple[str, ...]) -> dict:
    """In a worker, before any job: which of `modules` it has imported, how it was started, what its parent
    process (the fork server) holds."""
    server = os.getppid()
    return {
        "pid": os.getpid(),
        "server": server,
        "batch": multiprocessing.parent_process().pid,
        "forked_by_server": multiprocessing.forkserver.get_inherited_fds() is not None,
        "imported": sorted(name for name in modules if name in sys.modules),
        "python_threads": [thread.name for thread in threading.enumerate()],
        "server_threads": threads_of(server),
        "server_maps": maps_of(server),
        "gl_platform": type(getattr(sys.modules.get("OpenGL.platform"), "PLATFORM", None)).__name__,
    }
