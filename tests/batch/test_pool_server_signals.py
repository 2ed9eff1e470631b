"""The local pool's fork server starts with SIGINT blocked (`camgen.batch.executor.start_pool_server`), so that a
Ctrl-C while it imports (about 3 s) or while a worker it forked starts up ends neither with a traceback; the
workers unblock it in `init_pool_worker`. multiprocessing's resource tracker, started on the way to the server,
unblocks SIGINT in the caller after starting itself: the server must be started after it.

Each check runs in a fresh interpreter: the fork server and the resource tracker are started once per process."""

from __future__ import annotations

import json
import subprocess
import sys

from tests.conftest import REPO

SIGINT_BIT = 1 << 1  # SIGINT is signal 2: bit 1 of /proc/PID/status's SigBlk

CHECK = """
import json, multiprocessing.forkserver, signal, time

def blocked(pid):
    status = open(f"/proc/{pid}/status").read()
    return int(next(line for line in status.splitlines() if line.startswith("SigBlk:")).split()[1], 16)

if __name__ == "__main__":
    from camgen.batch.executor import pool_context, start_pool_server

    before = sorted(int(s) for s in signal.pthread_sigmask(signal.SIG_BLOCK, set()))
    start_pool_server()
    server = blocked(multiprocessing.forkserver._forkserver._forkserver_pid)
    caller = sorted(int(s) for s in signal.pthread_sigmask(signal.SIG_BLOCK, set()))
    child = pool_context().Process(target=time.sleep, args=(3.0,))  # forked by the server, no initializer
    child.start()
    time.sleep(1.0)
    print(json.dumps({"server": server, "child": blocked(child.pid), "caller": caller, "before": before}))
    child.join()
"""


def test_the_server_and_its_children_start_with_sigint_blocked_and_the_caller_keeps_its_mask():
    done = subprocess.run(
        [sys.executable, "-c", CHECK], cwd=REPO, capture_output=True, text=True, timeout=180, check=True
    )
    found = json.loads(done.stdout.strip().splitlines()[-1])
    assert found["server"] & SIGINT_BIT, found
    assert found["child"] & SIGINT_BIT, found  # inherited from the server
    assert found["caller"] == found["before"], found  # the batch process's own mask is as it was
