"""The local pool's workers are forked from a fork server that imported what a job needs (so a worker starts
without seconds of imports), and that server holds no thread and no OpenGL driver when it forks."""

from __future__ import annotations

import os

from camgen.batch.executor import POOL_PRELOAD_MODULES
from camgen.batch.run import PoolExecutor
from tests.batch.pool_probe import probe

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
        assert worker["gl_platform"] == "EGLPlatform"  # not GLX: camgen.render.gl chose it before PyOpenGL loaded
        # The watcher of the batch process (`_stop_with_parent`) is the worker's one thread beside its main one.
        assert worker["python_threads"] == ["MainThread", "camgen-batch-watch"]
        # The server has forked: no thread of its own (OpenBLAS's stopped before the fork), no GL driver loaded.
        assert worker["server_threads"] == 1
        assert not [name for name in GL_DRIVER_LIBRARIES if name in worker["server_maps"]]
