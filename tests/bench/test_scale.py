"""The scale section's pure parts: output trees hashed and compared, the cluster's and the batch's command lines
as Ray's and camgen's own parsers read them, the section's skip without Ray; and (slow) the whole path on a
two-job dataset: a real `ray start` cluster writes the pool's bytes and leaves no process behind."""

from __future__ import annotations

import hashlib
import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

from camgen.bench import scale_cases
from camgen.bench.report import Plots
from camgen.bench.scale_cases import (
    LocalCluster,
    ScaleFacts,
    batch_command,
    differing_files,
    free_ports,
    head_command,
    job_file_hashes,
    node_command,
    run_scale,
    tree_digest,
)
from camgen.bench.sections import sections
from camgen.cli.main import build_parser

needs_ray = pytest.mark.skipif(importlib.util.find_spec("ray") is None, reason="needs camgen[ray]")
REPO = Path(__file__).resolve().parents[2]


def _batch_out(out: Path) -> Path:
    """A batch's output: two jobs' files, and the dataset-level files that say how it ran."""
    files = {
        "walk-aaaa/manifest.json": b'{"job": "a"}',
        "walk-aaaa/cam/video.mp4": b"\x00\x01video a",
        "walk-aaaa/cam/camera.jsonl": b'{"frame": 0}\n',
        "walk-bbbb/manifest.json": b'{"job": "b"}',
        "walk-bbbb/cam/video.mp4": b"\x00\x01video b",
        "dataset.json": b'{"executor": "local", "seconds": 1.0}',
        "DATASET_CARD.md": b"camgen batch ... --workers 2",
        "card/classes.png": b"\x89PNG",
    }
    for relative, data in files.items():
        (out / relative).parent.mkdir(parents=True, exist_ok=True)
        (out / relative).write_bytes(data)
    return out


def test_the_jobs_files_are_hashed_and_the_dataset_level_files_left_out(tmp_path):
    out = _batch_out(tmp_path / "out")
    hashes = job_file_hashes(out)
    assert sorted(hashes) == [
        "walk-aaaa/cam/camera.jsonl",
        "walk-aaaa/cam/video.mp4",
        "walk-aaaa/manifest.json",
        "walk-bbbb/cam/video.mp4",
        "walk-bbbb/manifest.json",
    ]
    assert hashes["walk-aaaa/cam/video.mp4"] == hashlib.sha256(b"\x00\x01video a").hexdigest()


def test_a_changed_byte_a_renamed_file_or_a_missing_file_changes_the_digest(tmp_path):
    a = job_file_hashes(_batch_out(tmp_path / "a"))
    b_out = _batch_out(tmp_path / "b")
    (b_out / "dataset.json").write_bytes(b'{"executor": "ray", "seconds": 2.0}')  # how it ran: not compared
    (b_out / "card" / "classes.png").write_bytes(b"other plot")
    b = job_file_hashes(b_out)
    assert tree_digest(a) == tree_digest(b) and differing_files(a, b) == []
    assert tree_digest(dict(reversed(list(a.items())))) == tree_digest(a)  # the order of the mapping is not

    video = b_out / "walk-bbbb" / "cam" / "video.mp4"
    video.write_bytes(b"\x00\x01video B")
    changed = job_file_hashes(b_out)
    assert tree_digest(changed) != tree_digest(a)
    assert differing_files(a, changed) == ["walk-bbbb/cam/video.mp4"]

    video.write_bytes(b"\x00\x01video b")
    video.rename(video.with_name("video2.mp4"))  # the same bytes under another name
    renamed = job_file_hashes(b_out)
    assert tree_digest(renamed) != tree_digest(a)
    assert differing_files(a, renamed) == ["walk-bbbb/cam/video.mp4", "walk-bbbb/cam/video2.mp4"]

    (b_out / "walk-bbbb" / "cam" / "video2.mp4").unlink()
    assert differing_files(a, job_file_hashes(b_out)) == ["walk-bbbb/cam/video.mp4"]


def test_same_bytes_needs_runs_one_digest_and_no_differing_file():
    assert not ScaleFacts().same_bytes
    assert ScaleFacts(digests=[("pool", "ab"), ("ray", "ab")]).same_bytes
    assert not ScaleFacts(digests=[("pool", "ab"), ("ray", "cd")]).same_bytes
    assert not ScaleFacts(digests=[("pool", "ab"), ("ray", "ab")], differing=["x/video.mp4"]).same_bytes


def test_the_batch_commands_are_what_camgen_batch_reads(tmp_path):
    ray_args = build_parser().parse_args(
        batch_command("camgen", tmp_path / "d.yaml", tmp_path / "out", frames=3, address="127.0.0.1:6390")[1:]
    )
    assert (ray_args.executor, ray_args.address, ray_args.frames, ray_args.retries) == ("ray", "127.0.0.1:6390", 3, 0)
    assert ray_args.dataset == tmp_path / "d.yaml" and ray_args.out == tmp_path / "out"
    pool_args = build_parser().parse_args(
        batch_command("camgen", tmp_path / "d.yaml", tmp_path / "out", frames=3, workers=2)[1:]
    )
    assert (pool_args.executor, pool_args.address, pool_args.workers) == ("local", None, 2)
    with pytest.raises(ValueError, match="needs an address"):
        batch_command("camgen", tmp_path / "d.yaml", tmp_path / "out", frames=3)


@needs_ray
def test_the_cluster_commands_are_what_ray_start_reads(tmp_path):
    from ray.scripts.scripts import start

    port, dashboard_port = free_ports(2)
    assert port != dashboard_port
    head = head_command("ray", port=port, cpus=1, temp_dir=tmp_path / "ray", dashboard_port=dashboard_port)
    params = start.make_context("start", head[2:]).params  # unknown or malformed options raise here
    assert params["head"] and params["block"] and params["port"] == port and params["num_cpus"] == 1
    assert params["temp_dir"] == str(tmp_path / "ray") and params["dashboard_port"] == dashboard_port
    assert params["include_dashboard"] is False
    node = start.make_context("start", node_command("ray", address=f"127.0.0.1:{port}", cpus=2)[2:]).params
    assert node["address"] == f"127.0.0.1:{port}" and node["num_cpus"] == 2 and node["block"] and not node["head"]


def test_a_cluster_needs_a_node_and_a_cpu(tmp_path):
    with pytest.raises(ValueError, match="≥ 1 node of ≥ 1 CPU, got 0 × 1"):
        LocalCluster(tmp_path, nodes=0)


def test_without_ray_the_section_is_skipped_with_its_reason(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # what `import ray` meets where it is not installed
    (section,) = [s for s in sections(REPO) if s.key == "scale"]
    assert section.cases() == []
    text = section.body({}, Plots(tmp_path, tmp_path / "BENCHMARKS.md"))
    assert "Skipped in this run: Ray is not installed" in text and "camgen[ray]" in text


def _running(pgid: int) -> bool:
    """Whether a live process of group `pgid` is left: `ps`'s view, independent of the module's /proc reading."""
    listing = subprocess.run(["ps", "-eo", "pgid=,stat="], capture_output=True, text=True, check=True).stdout
    return any(int(g) == pgid and not s.startswith("Z") for g, s in (line.split() for line in listing.splitlines()))


def _fake_ray(tmp_path: Path, body: str) -> Path:
    script = tmp_path / "ray"
    script.write_text(f"#!/bin/sh\n{body}\n", encoding="utf-8")
    script.chmod(0o755)
    return script


def test_the_cluster_is_stopped_with_every_process_of_its_groups_when_the_work_fails(tmp_path, monkeypatch):
    # A stand-in for `ray start --block`: says it runs, leaves a child in its process group (as Ray's daemons
    # are), and waits; SIGTERM ends it but not the child, which the stop's SIGKILL to the group must end.
    fake = _fake_ray(tmp_path, f'echo "{scale_cases.READY_LINE}."; sleep 300 & exec sleep 300')
    monkeypatch.setattr(scale_cases, "executable", lambda name: str(fake))
    with pytest.raises(RuntimeError, match="the batch failed"):
        with LocalCluster(tmp_path, nodes=2) as cluster:
            pids = list(cluster.pids)
            assert len(pids) == 2 and all(_running(pid) for pid in pids)
            raise RuntimeError("the batch failed")
    assert not any(_running(pid) for pid in pids)


def test_a_node_that_fails_to_start_is_reported_and_nothing_is_left(tmp_path, monkeypatch):
    fake = _fake_ray(
        tmp_path, 'case "$*" in *--head*) echo "Ray runtime started."; exec sleep 300;; esac; echo boom; exit 3'
    )
    monkeypatch.setattr(scale_cases, "executable", lambda name: str(fake))
    cluster = LocalCluster(tmp_path, nodes=2)
    with pytest.raises(RuntimeError, match=r"--address=127\.0\.0\.1:\d+ .*exited with 3 before its node ran:\nboom"):
        with cluster:
            pass
    assert len(cluster.pids) == 2 and not any(_running(pid) for pid in cluster.pids)


@needs_ray
@pytest.mark.opengl
@pytest.mark.slow
def test_a_ray_start_cluster_writes_the_pools_bytes_and_stops():
    facts = ScaleFacts(jobs=2, frames=2, nodes=1)
    run_scale(facts, order=("ray", "pool"))
    assert [executor for executor, _ in facts.digests] == ["ray", "pool"]
    assert facts.same_bytes and facts.verified == [True, True]
    assert facts.files >= 2 * 3  # each job: its manifest, the camera's video and camera.jsonl at least
    assert facts.worker_nodes == 1
    assert len(facts.cluster_pids) == 1 and not any(_running(pid) for pid in facts.cluster_pids)
