"""Scale-out (issue 23): a 100-job dataset on a real local Ray cluster and on the local process pool, the
same bytes from both.

The cluster is started with the commands README.md's Datasets section gives (`ray start --head`, then
`ray start --address=…` for a second node on the same machine, one CPU each: two task slots, as the pool's
two workers) and `camgen batch … --executor ray --address 127.0.0.1:PORT` runs on it, a separate process,
as a user runs it; the pool's run is `camgen batch … --workers 2`. Both run twice, interleaved (pool, Ray,
Ray, pool), each into a fresh directory. Every file of every job directory of each run is hashed (sha256),
the trees are compared with the first pool run's, and `camgen verify` checks each run.

The cluster is this bench's own: its own Ray temporary directory (so a `ray.init()` elsewhere on the machine
does not find it through /tmp/ray), free ports, and a token of its own (`RAY_AUTH_MODE=token`,
`RAY_AUTH_TOKEN_PATH`). Its `ray start` processes run with `--block`, and stopping it is a SIGTERM to each
(Ray's own shutdown of the processes it started), then SIGKILL to whatever of their process groups is
left: `ray stop` would stop every Ray of this user on the machine, other people's included.
"""

from __future__ import annotations

import hashlib
import os
import re
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from camgen.batch.dataset_files import CARD_PLOTS_DIR
from camgen.bench.batch_cases import bench_profile, walker_scene
from camgen.bench.harness import Case

JOBS = 100
FRAMES = 3
NODES = 2
"""The head and one worker node, on this machine."""
NODE_CPUS = 1
POOL_WORKERS = NODES * NODE_CPUS
ORDER = ("pool", "ray", "ray", "pool")
"""The runs, interleaved (ABBA) so that a drift in the machine's load falls on both alike."""
START_TIMEOUT_S = 180.0
STOP_TIMEOUT_S = 60.0
BATCH_TIMEOUT_S = 900.0
KILL_SETTLE_S = 10.0
"""After SIGKILL to a node's process group, how long to wait for its processes to be gone."""
READY_LINE = "Ray runtime started"
"""What `ray start` prints once its node runs (before it blocks)."""

PROFILE = bench_profile(160, 120, 1.0, "scale bench camera")
SCENE = walker_scene("small")


def dataset_text(jobs: int) -> str:
    return (
        f"description: {jobs} seeds of one walker through a 160×120 camera\n"
        "scenes: [scenes/walk.yaml]\n"
        f"seeds: {{start: 0, count: {jobs}}}\n"
    )


def write_dataset(workspace: Path, jobs: int) -> Path:
    """dataset.yaml (`jobs` seeds), scenes/walk.yaml and profiles/small.yaml under `workspace`; its path."""
    for relative, text in (("profiles/small.yaml", PROFILE), ("scenes/walk.yaml", SCENE)):
        (workspace / relative).parent.mkdir(parents=True, exist_ok=True)
        (workspace / relative).write_text(text, encoding="utf-8")
    dataset = workspace / "dataset.yaml"
    dataset.write_text(dataset_text(jobs), encoding="utf-8")
    return dataset


# --- comparing output trees ---------------------------------------------------------------------------


def job_file_hashes(out: Path) -> dict[str, str]:
    """sha256 (hex) of every file in every job directory of a batch's `out`, by path relative to `out`.

    The dataset-level files (dataset.json with its wall times and executor, DATASET.md, the card with its
    command line) say how the batch ran, so they are left out; the jobs' files are what must not differ."""
    hashes = {}
    for job_dir in sorted(p for p in out.iterdir() if p.is_dir() and p.name != CARD_PLOTS_DIR):
        for path in sorted(job_dir.rglob("*")):
            if path.is_file():
                hashes[path.relative_to(out).as_posix()] = hashlib.sha256(path.read_bytes()).hexdigest()
    return hashes


def tree_digest(hashes: Mapping[str, str]) -> str:
    """One sha256 over a tree's files: each path and its file's sha256, in path order (a renamed or moved
    file changes it as a changed byte does)."""
    digest = hashlib.sha256()
    for path in sorted(hashes):
        digest.update(f"{path}\0{hashes[path]}\n".encode())
    return digest.hexdigest()


def differing_files(a: Mapping[str, str], b: Mapping[str, str]) -> list[str]:
    """The paths whose bytes differ between two trees, or that only one of them has, sorted."""
    return sorted(path for path in a.keys() | b.keys() if a.get(path) != b.get(path))


# --- command lines ------------------------------------------------------------------------------------


def executable(name: str) -> str:
    """The console script `name` (ray, camgen) of this Python's environment, else the one on PATH."""
    beside = Path(sys.executable).parent / name
    found = str(beside) if beside.is_file() else shutil.which(name)
    if found is None:
        raise FileNotFoundError(f"no `{name}` command beside {sys.executable} or on PATH")
    return found


def head_command(ray: str, *, port: int, cpus: int, temp_dir: Path, dashboard_port: int) -> list[str]:
    """README's `ray start --head`, in the foreground (--block), with this bench's own temporary directory
    and ports (another Ray on the machine may hold the dashboard's default, 8265)."""
    return [
        ray, "start", "--head", f"--port={port}", f"--num-cpus={cpus}", "--include-dashboard=false",
        f"--dashboard-port={dashboard_port}", f"--temp-dir={temp_dir}", "--disable-usage-stats", "--block",
    ]  # fmt: skip


def node_command(ray: str, *, address: str, cpus: int) -> list[str]:
    """README's `ray start --address=HEAD:PORT`: another node joins the head's cluster."""
    return [ray, "start", f"--address={address}", f"--num-cpus={cpus}", "--disable-usage-stats", "--block"]


def batch_command(
    camgen: str, dataset: Path, out: Path, *, frames: int, address: str | None = None, workers: int | None = None
) -> list[str]:
    """`camgen batch` on the cluster at `address`, or on the local pool with `workers` processes."""
    words = [camgen, "batch", str(dataset), "-o", str(out), "--frames", str(frames), "--retries", "0"]
    if address is not None:
        return [*words, "--executor", "ray", "--address", address]
    if workers is None:
        raise ValueError("batch_command needs an address (Ray) or a number of workers (the local pool)")
    return [*words, "--workers", str(workers)]


def free_ports(count: int) -> list[int]:
    """`count` distinct TCP ports nothing listened on a moment ago."""
    sockets = [socket.socket() for _ in range(count)]
    try:
        for s in sockets:
            s.bind(("127.0.0.1", 0))
        return [s.getsockname()[1] for s in sockets]
    finally:
        for s in sockets:
            s.close()


def process_group_members(pgid: int) -> list[int]:
    """The ids of the live processes (not zombies) in process group `pgid`, read from /proc (Linux)."""
    members = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat.read_text(encoding="utf-8", errors="replace")
        except OSError:  # the process ended meanwhile
            continue
        state, _ppid, pgrp = text[text.rindex(")") + 2 :].split()[:3]  # after "pid (comm) "
        if int(pgrp) == pgid and state not in ("Z", "X"):
            members.append(int(stat.parent.name))
    return members


# --- the cluster --------------------------------------------------------------------------------------


class LocalCluster:
    """A Ray cluster of `nodes` nodes × `cpus` CPUs on this machine, started with `ray start --block` under
    `workspace` and stopped (each process group by its id) on `stop` or on leaving a `with` block."""

    def __init__(self, workspace: Path, *, nodes: int = NODES, cpus: int = NODE_CPUS) -> None:
        if nodes < 1 or cpus < 1:
            raise ValueError(f"a cluster needs ≥ 1 node of ≥ 1 CPU, got {nodes} × {cpus}")
        self.workspace, self.nodes, self.cpus = workspace, nodes, cpus
        self.temp_dir = workspace / "ray"
        self.port, self._dashboard_port = free_ports(2)
        self.address = f"127.0.0.1:{self.port}"
        token = workspace / "auth_token"
        token.write_text(secrets.token_hex(32), encoding="utf-8")
        token.chmod(0o600)
        env = {k: v for k, v in os.environ.items() if k not in ("RAY_ADDRESS", "RAY_AUTH_TOKEN")}
        self.env = {**env, "RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN_PATH": str(token), "RAY_USAGE_STATS_ENABLED": "0"}
        """The environment of every command that talks to this cluster (its nodes and camgen batch)."""
        self._processes: list[tuple[subprocess.Popen, Path]] = []
        self.pids: list[int] = []
        """Each `ray start` process's id, which is also its process group's."""

    def __enter__(self) -> LocalCluster:
        try:
            self.start()
        except BaseException:
            self.stop()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self.stop()

    def start(self) -> None:
        ray = executable("ray")
        commands = [
            head_command(
                ray,
                port=self.port,
                cpus=self.cpus,
                temp_dir=self.temp_dir,
                dashboard_port=self._dashboard_port,
            ),
            *[node_command(ray, address=self.address, cpus=self.cpus) for _ in range(self.nodes - 1)],
        ]
        for i, command in enumerate(commands):
            log = self.workspace / f"ray_start_{i}.log"
            with open(log, "wb") as sink:
                process = subprocess.Popen(
                    command, stdout=sink, stderr=subprocess.STDOUT, env=self.env, start_new_session=True
                )
            self._processes.append((process, log))
            self.pids.append(process.pid)
            self._wait_ready(process, log)

    def _wait_ready(self, process: subprocess.Popen, log: Path) -> None:
        deadline = time.monotonic() + START_TIMEOUT_S
        while READY_LINE not in log.read_text(encoding="utf-8", errors="replace"):
            if process.poll() is not None or time.monotonic() > deadline:
                tail = log.read_text(encoding="utf-8", errors="replace")[-2000:]
                state = f"exited with {process.returncode}" if process.returncode is not None else "timed out"
                raise RuntimeError(f"`{' '.join(process.args)}` {state} before its node ran:\n{tail}")
            time.sleep(0.2)

    def stop(self) -> None:
        """SIGTERM to each `ray start` (the nodes that joined first, the head last), which stops the processes
        it started; then SIGKILL to anything left in its process group."""
        while self._processes:
            process, _ = self._processes.pop()
            if process.poll() is None:
                process.send_signal(signal.SIGTERM)
                try:
                    process.wait(STOP_TIMEOUT_S)
                except subprocess.TimeoutExpired:
                    pass
            try:
                os.killpg(process.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            process.wait()
            deadline = time.monotonic() + KILL_SETTLE_S
            while process_group_members(process.pid) and time.monotonic() < deadline:
                time.sleep(0.05)

    def nodes_that_ran_workers(self) -> int:
        """How many of the cluster's nodes started a worker process (read from Ray's worker logs, which
        name each worker's node); 0 if the logs say nothing of it."""
        nodes = set()
        for log in (self.temp_dir / "session_latest" / "logs").glob("python-core-worker-*.log"):
            nodes.update(re.findall(r"worker_id=\w+ node_id=(\w+)", log.read_text(encoding="utf-8", errors="replace")))
        return len(nodes)


# --- the case -----------------------------------------------------------------------------------------


@dataclass
class ScaleFacts:
    """Filled in as the case runs."""

    jobs: int = JOBS
    frames: int = FRAMES
    nodes: int = NODES
    batch_s: dict[str, list[float]] = field(default_factory=lambda: {"pool": [], "ray": []})
    """Each `camgen batch` command's wall time, by executor, in the order run."""
    start_s: float = 0.0
    stop_s: float = 0.0
    files: int = 0
    digests: list[tuple[str, str]] = field(default_factory=list)
    """(executor, tree digest) of each run, in the order run."""
    differing: list[str] = field(default_factory=list)
    """Paths that differ from the first pool run's tree, over every run."""
    verified: list[bool] = field(default_factory=list)
    """`camgen verify`'s verdict on each run."""
    worker_nodes: int = 0
    cluster_pids: list[int] = field(default_factory=list)
    """The cluster's `ray start` process ids (and process groups), to check that none outlives it."""
    load_1min: float = 0.0

    @property
    def same_bytes(self) -> bool:
        return bool(self.digests) and len({digest for _, digest in self.digests}) == 1 and not self.differing


def run_scale(facts: ScaleFacts, *, order: tuple[str, ...] = ORDER) -> None:
    """Start the cluster, run the dataset on it and on the pool in `order`, compare and verify every run's
    files, stop the cluster (also when something fails), and remove the files."""
    camgen = executable("camgen")
    workspace = Path(tempfile.mkdtemp(prefix="camgen-scale-"))
    try:
        dataset = write_dataset(workspace, facts.jobs)
        reference: dict[str, str] | None = None
        started = time.perf_counter()
        with LocalCluster(workspace, nodes=facts.nodes) as cluster:
            facts.start_s = time.perf_counter() - started
            facts.cluster_pids = list(cluster.pids)
            for i, executor in enumerate(order):
                out = workspace / f"out_{i}_{executor}"
                address, workers = (cluster.address, None) if executor == "ray" else (None, POOL_WORKERS)
                command = batch_command(camgen, dataset, out, frames=facts.frames, address=address, workers=workers)
                began = time.perf_counter()
                done = subprocess.run(
                    command, env=cluster.env, capture_output=True, text=True, timeout=BATCH_TIMEOUT_S, check=False
                )
                facts.batch_s[executor].append(time.perf_counter() - began)
                if done.returncode != 0:
                    raise RuntimeError(f"`{' '.join(command)}` exited with {done.returncode}:\n{done.stderr[-2000:]}")
                hashes = job_file_hashes(out)
                reference = hashes if reference is None else reference
                facts.files = len(hashes)
                facts.digests.append((executor, tree_digest(hashes)))
                facts.differing = sorted(set(facts.differing) | set(differing_files(reference, hashes)))
                verify = subprocess.run([camgen, "verify", str(out)], capture_output=True, check=False)
                facts.verified.append(verify.returncode == 0)
                shutil.rmtree(out)
            facts.worker_nodes = cluster.nodes_that_ran_workers()
            stopping = time.perf_counter()
        facts.stop_s = time.perf_counter() - stopping
        facts.load_1min = os.getloadavg()[0]
    finally:
        shutil.rmtree(workspace, ignore_errors=True)


def scale_cases(facts: ScaleFacts) -> list[Case]:
    name = f"{facts.jobs} jobs × {facts.frames} frames 160×120: pool and Ray cluster, {len(ORDER)} runs (ABBA)"
    return [Case(name=name, run=lambda: run_scale(facts), repeats=1, warmup=0)]
