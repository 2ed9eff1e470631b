"""The local pool's workers are forked from a fork server that imported what a job needs (so a worker starts
without seconds of imports), and that server holds no thread and no OpenGL driver when it forks."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from camgen.batch.executor import POOL_PRELOAD_MODULES
from camgen.batch.run import PoolExecutor
from tests.batch.pool_probe import probe
from tests.conftest import REPO

GL_DRIVER_LIBRARIES = ("libgallium", "swrast_dri", "libLLVM", "/dev/dri")
"""What a process that had opened an EGL display on Mesa (llvmpipe) maps; importing the EGL libraries alone
maps none of them."""


def test_workers_are_forked_from_a_server_that_imported_what_a_job_needs():
    pool = PoolExecutor(2)
    try:
        found = [pool._pool.submit(probe, POOL_PRELOAD_MODULES).result(timeout=120) for _ in range(2)]
    finally:
        pool.close()
    for worker in found:
        assert worker["forked_by_server"]
        assert worker["batch"] == os.getpid() != worker["server"]
        # Imported before the worker's first call: the server had them (probe's own module imports none).
        assert worker["imported"] == sorted(POOL_PRELOAD_MODULES)
        # The watcher of the batch process (`_stop_with_parent`) is the worker's one thread beside its main one.
        assert worker["python_threads"] == ["MainThread", "camgen-batch-watch"]
        # The server has forked: no thread of its own (OpenBLAS's stopped before the fork), no GL driver loaded.
        assert worker["server_threads"] == 1
        assert not [name for name in GL_DRIVER_LIBRARIES if name in worker["server_maps"]]


EARLY_START = """
from concurrent.futures import ProcessPoolExecutor
import json, os
from camgen.batch.executor import POOL_PRELOAD_MODULES, pool_context, start_pool_server
from tests.batch.pool_probe import probe
if __name__ == "__main__":
    assert "PYOPENGL_PLATFORM" not in os.environ
    start_pool_server()
    with ProcessPoolExecutor(1, mp_context=pool_context()) as pool:
        print(json.dumps(pool.submit(probe, POOL_PRELOAD_MODULES).result(timeout=120)["gl_platform"]))
"""


def test_a_server_started_before_camgen_render_was_imported_gives_its_workers_egl():
    # A caller may start the server before it imports camgen.render (whose camgen.render.gl sets
    # PYOPENGL_PLATFORM=egl), so the server's environment does not choose the platform: its preload order does.
    env = {name: value for name, value in os.environ.items() if name != "PYOPENGL_PLATFORM"}
    done = subprocess.run(
        [sys.executable, "-c", EARLY_START], cwd=REPO, env=env, capture_output=True, text=True, timeout=180
    )
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == "EGLPlatform"  # pyrender imported first would have made it GLX
