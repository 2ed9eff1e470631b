"""Batch jobs as Ray tasks: one task per job, on a local Ray or the cluster at an address.

Each task runs `render_job` (`camgen.batch.executor`), as the pool does, so it writes the same bytes. Ray
reuses worker processes, so a worker keeps the one Renderer that `render_job` opens on its first job. The
output directory and the scenes must be on a filesystem that every node sees at the same path, and camgen
must be installed on every node.
Ray's own task retries are off (``max_retries=0``): `run_batch` retries failed jobs itself.
"""

from __future__ import annotations

import signal
import socket
import threading
from collections.abc import Collection

from camgen.batch.executor import STOP_GRACE_S, JobResult, error_text, render_job
from camgen.errors import ConfigError

try:
    import ray
    from ray.exceptions import RayError, RayTaskError, TaskCancelledError
except ImportError as exc:
    raise ConfigError("--executor ray needs Ray: install camgen[ray] (pip install 'camgen[ray]')") from exc

CONNECT_TIMEOUT_S = 5.0
"""How long to try reaching a cluster's address before `ray.init`, which otherwise retries for minutes."""
FORCED_SETTLE_S = 5.0
"""After a stop, how long to wait for force-cancelled tasks (their workers killed) to settle."""

_render_task = ray.remote(num_cpus=1, max_retries=0)(render_job)


class RayExecutor:
    """`JobExecutor` on Ray. address: a running cluster's ("auto", "ray://host:10001", "host:6379"), or None
    to start a local Ray with `workers` CPUs, shut down again by `close`."""

    name = "ray"

    def __init__(self, *, workers: int, address: str | None) -> None:
        self._started_ray = not ray.is_initialized()
        if not self._started_ray:
            return
        # ray.init installs its own SIGTERM handler (it aborts the process); `run_batch`'s stop takes it back.
        handlers = {signum: signal.getsignal(signum) for signum in (signal.SIGINT, signal.SIGTERM)}
        try:
            if address is None:
                # "local": a Ray of its own even where RAY_ADDRESS is set or a `ray start` cluster runs on this
                # machine (Ray would connect to that instead, and refuse the CPU count).
                ray.init(address="local", num_cpus=workers, include_dashboard=False)
            else:
                _check_reachable(address)
                ray.init(address=address)
        except Exception as exc:  # Ray raises ConnectionError, RuntimeError, ValueError… for a bad address
            if address is None:
                raise ConfigError(f"cannot start a local Ray ({error_text(exc)}); its logs are in /tmp/ray") from exc
            raise ConfigError(
                f"--address {address}: cannot reach a Ray cluster ({error_text(exc)}); start one with "
                "`ray start --head` and pass its address, or leave out --address for a local Ray"
            ) from exc
        finally:
            if threading.current_thread() is threading.main_thread():
                for signum, handler in handlers.items():
                    if handler is not None:
                        signal.signal(signum, handler)

    def submit(
        self,
        job_json: str,
        out_dir: str,
        frames: int | None,
        scene_path: str,
        resume: bool,
        checkpoint_frames: int | None,
    ) -> ray.ObjectRef:
        return _render_task.remote(job_json, out_dir, frames, scene_path, resume, checkpoint_frames)

    def wait(self, handles: Collection[ray.ObjectRef]) -> list[ray.ObjectRef]:
        refs = list(handles)
        ready, _ = ray.wait(refs, num_returns=1)
        more, _ = ray.wait(refs, num_returns=len(refs), timeout=0)
        return list({*ready, *more})

    def result(self, handle: ray.ObjectRef) -> JobResult | None:
        try:
            return ray.get(handle, timeout=0)
        except TaskCancelledError:
            return None
        except RayTaskError as exc:
            if isinstance(exc.cause, KeyboardInterrupt):
                return None
            return 0, 0.0, error_text(exc), 0
        except RayError as exc:  # the worker died, or (after a cancel) the task never settled
            return 0, 0.0, error_text(exc), 0

    def cancel(self, handles: Collection[ray.ObjectRef]) -> None:
        # As the pool does: each task is interrupted (KeyboardInterrupt: its job unwinds, deleting its temporary
        # files, or keeping its checkpoints in a batch that resumes); one still running after STOP_GRACE_S has its
        # worker killed.
        refs = list(handles)
        for ref in refs:
            ray.cancel(ref)
        if not refs:
            return
        _, unsettled = ray.wait(refs, num_returns=len(refs), timeout=STOP_GRACE_S)
        for ref in unsettled:
            ray.cancel(ref, force=True)
        if unsettled:
            ray.wait(unsettled, num_returns=len(unsettled), timeout=FORCED_SETTLE_S)

    def close(self) -> None:
        if self._started_ray:
            ray.shutdown()


def _check_reachable(address: str) -> None:
    """Raise ConnectionError if nothing listens at a HOST:PORT or ray://HOST:PORT `address` (others, such as
    "auto", are left to Ray)."""
    host, colon, port = address.removeprefix("ray://").rpartition(":")
    if not colon or not port.isdigit():
        return
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=CONNECT_TIMEOUT_S).close()
    except OSError as exc:
        raise ConnectionError(f"nothing answers at {host}:{port} within {CONNECT_TIMEOUT_S:g} s ({exc})") from exc
