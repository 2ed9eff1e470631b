"""The dataset-level files of a batch: the merged COCO file loads and scores itself perfectly, ids are unique,
splits keep each sequence whole and follow the seed, and the card names what was rendered and counts it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval

from camgen.batch.dataset_files import (
    CARD_NAME,
    DEFAULT_RATIOS,
    MERGED_NAME,
    SPLITS,
    JobRecord,
    dataset_statistics,
    split_counts,
    split_jobs,
    write_dataset_files,
)
from camgen.batch.run import BatchSummary, JobOutcome
from camgen.cli.main import main
from camgen.config.dataset import Splits
from camgen.plan.execute import job_directory_name
from tests.batch.conftest import make_dataset
from tests.conftest import write

CATEGORIES = [{"id": 1, "name": "person"}, {"id": 3, "name": "car"}]  # COCO 2017's ids, as camgen writes them


def camera_coco(*, frames: int, tracks: dict[int, str], shift_px: float, categories=CATEGORIES) -> dict:
    """A per-camera coco.json as camgen writes one: one video, a box per track and frame (track t at
    x = 40·t + shift, taller for people), frames/NNNNNN.png, a TAO-style track record per actor (and one for
    an actor the camera never sees)."""
    ids = {category["name"]: category["id"] for category in categories}
    images = [
        {"id": f + 1, "video_id": 1, "frame_index": f, "width": 320, "height": 240, "file_name": f"frames/{f:06d}.png"}
        for f in range(frames)
    ]
    annotations = []
    for f in range(frames):
        for track, cls in tracks.items():
            w, h = (12.0, 40.0 + 5 * track) if cls == "person" else (50.0, 30.0)
            annotations.append(
                {
                    "id": len(annotations) + 1,
                    "image_id": f + 1,
                    "video_id": 1,
                    "category_id": ids[cls],
                    "track_id": track,
                    "bbox": [40.0 * track + shift_px + f, 100.0, w, h],
                    "area": w * h,
                    "iscrowd": 0,
                    "visibility": 0.25 * track,
                    "truncation": 0.0,
                }
            )
    return {
        "info": {},
        "videos": [{"id": 1, "name": "cam", "width": 320, "height": 240}],
        "images": images,
        "annotations": annotations,
        "categories": categories,
        "tracks": [
            {"id": t, "video_id": 1, "category_id": ids[c], "name": f"actor_{t}"}
            for t, c in {**tracks, 9: "car"}.items()  # actor 9 is never seen in this camera
        ],
    }


def write_job(out: Path, directory: str, cameras: dict[str, dict], fps: float = 10.0) -> None:
    """A finished job's directory: manifest.json (the parts the dataset files read) and each camera's coco.json."""
    manifest = {
        "files": {},
        "fps": fps,
        "rendered": {"cameras": list(cameras), "frames": [0]},
        "cameras": [
            {"name": name, "profile_name": "small", "profile": {"description": "a small test camera"}}
            for name in cameras
        ],
    }
    write(out, f"{directory}/manifest.json", json.dumps(manifest))
    for name, coco in cameras.items():
        write(out, f"{directory}/{name}/coco.json", json.dumps(coco))


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory) -> tuple[Path, list[JobRecord]]:
    """Five jobs of two cameras (the second job's files list the categories in another order), a sixth that
    failed; the dataset files written from them."""
    out = tmp_path_factory.mktemp("synthetic") / "out"
    jobs = []
    for j in range(5):
        tracks = {1: "person", 2: "person", 3: "car"} if j % 2 == 0 else {1: "car", 2: "person"}
        categories = CATEGORIES[::-1] if j == 1 else CATEGORIES
        cameras = {
            camera: camera_coco(frames=3, tracks=tracks, shift_px=10.0 * c, categories=categories)
            for c, camera in enumerate(("north", "south"))
        }
        write_job(out, f"job{j}-0000000{j}", cameras)
        jobs.append(JobRecord(f"job{j}", f"job{j}-0000000{j}", "done" if j else "skipped"))
    jobs.append(JobRecord("job5", None, "failed", error="ConfigError: no such mesh"))
    write_dataset_files(
        out, jobs, dataset="tiny", description="five small jobs", split_seed=7, command="camgen batch x"
    )
    return out, jobs


def test_the_merged_file_loads_with_unique_ids_and_scores_itself_perfectly(synthetic):
    out, _ = synthetic
    merged = json.loads((out / MERGED_NAME).read_text())
    for key in ("images", "annotations", "videos", "tracks"):
        ids = [record["id"] for record in merged[key]]
        assert len(ids) == len(set(ids)) and min(ids) == 1, key
    assert len(merged["videos"]) == 10 and len(merged["images"]) == 30 and len(merged["annotations"]) == 78
    assert merged["categories"] == CATEGORIES  # as the per-camera files have them
    assert merged["images"][3]["file_name"] == "job0-00000000/south/frames/000000.png"  # relative to coco.json
    assert {video["name"] for video in merged["videos"]} >= {"job0-00000000/north", "job4-00000004/south"}
    gt = COCO(str(out / MERGED_NAME))
    detections = gt.loadRes([{**a, "score": 1.0} for a in gt.dataset["annotations"]])
    evaluation = COCOeval(gt, detections, "bbox")
    evaluation.params.areaRng = [[0, 1e10]] * 4  # every box counts in every area range
    evaluation.evaluate()
    evaluation.accumulate()
    evaluation.summarize()
    assert evaluation.stats[0] == pytest.approx(1.0) and evaluation.stats[1] == pytest.approx(1.0)


def test_categories_follow_names_and_identities_are_shared_by_a_jobs_cameras(synthetic):
    out, _ = synthetic
    merged = json.loads((out / MERGED_NAME).read_text())
    names = {category["id"]: category["name"] for category in merged["categories"]}
    videos = {video["id"]: video for video in merged["videos"]}
    tracks = {track["id"]: track for track in merged["tracks"]}
    identities: dict[tuple[str, str], set[int]] = {}
    for annotation in merged["annotations"]:
        video = videos[annotation["video_id"]]
        track = tracks[annotation["track_id"]]
        assert track["video_id"] == annotation["video_id"]  # a track lives in one stream (TAO)
        assert track["identity_id"] == annotation["identity_id"]
        assert names[annotation["category_id"]] == ("car" if annotation["bbox"][2] == 50.0 else "person")
        identities.setdefault((video["job"], annotation["identity_id"]), set()).add(video["camera"])
    assert all(cameras == {"north", "south"} for cameras in identities.values())
    assert len(identities) == 3 + 2 + 3 + 2 + 3  # one per actor and job, over both cameras
    assert len(tracks) == 2 * len(identities)  # one per actor seen and camera; actor 9, never seen, has none
    assert len({job for job, _ in identities}) == 5 and len(set(i for _, i in identities)) == len(identities)


@pytest.mark.parametrize(
    ("count", "expected"),
    [(0, (0, 0, 0)), (1, (1, 0, 0)), (2, (1, 1, 0)), (3, (1, 1, 1)), (4, (2, 1, 1)), (10, (7, 2, 1)), (20, (14, 3, 3))],
)
def test_split_counts_round_by_the_largest_remainder_with_one_per_split(count, expected):
    assert tuple(split_counts(count, {"train": 0.7, "val": 0.15, "test": 0.15}).values()) == expected


def test_split_counts_leave_a_zero_share_empty():
    assert split_counts(5, {"train": 0.8, "val": 0.2, "test": 0.0}) == {"train": 4, "val": 1, "test": 0}
    assert split_counts(30, {"train": 0.7, "val": 0.15, "test": 0.15}) == {"train": 21, "val": 5, "test": 4}


def test_splits_are_disjoint_cover_every_job_and_follow_the_seed():
    assert Splits().ratios == DEFAULT_RATIOS  # the dataset file's default is the documented one
    jobs = [f"job{i}" for i in range(40)]
    first = split_jobs(jobs, rng=np.random.default_rng(2026))
    assert sorted(job for name in SPLITS for job in first[name]) == sorted(jobs)
    assert [len(first[name]) for name in SPLITS] == [28, 6, 6]
    assert first == split_jobs(jobs, rng=np.random.default_rng(2026))
    assert first != split_jobs(jobs, rng=np.random.default_rng(2027))


def test_split_files_keep_each_job_whole_and_together_make_the_merged_file(synthetic):
    out, jobs = synthetic
    merged = json.loads((out / MERGED_NAME).read_text())
    recorded = json.loads((out / "splits.json").read_text())
    assert recorded["seed"] == 7
    assert sorted(entry["job"] for part in recorded["splits"].values() for entry in part) == [job.name for job in jobs]
    images, video_jobs = [], {}
    for name in SPLITS:
        part = json.loads((out / f"coco_{name}.json").read_text())
        jobs_here = {entry["job"] for entry in recorded["splits"][name]}
        assert {video["job"] for video in part["videos"]} <= jobs_here
        assert all(video["split"] == name for video in part["videos"])
        for video in part["videos"]:
            assert video_jobs.setdefault(video["job"], name) == name  # both cameras of a job in one split
        images += [image["id"] for image in part["images"]]
        assert part["categories"] == merged["categories"]
    assert sorted(images) == [image["id"] for image in merged["images"]]


def test_the_card_names_every_camera_counts_the_classes_and_the_missing_job(synthetic):
    out, _ = synthetic
    card = (out / CARD_NAME).read_text()
    merged = json.loads((out / MERGED_NAME).read_text())
    stats = dataset_statistics(merged)
    for video in merged["videos"]:
        assert f"| {video['job']} | {video['camera']} | small | 320×240 | 10 | 3 | 0.30 s |" in card
    for name, boxes in (("person", 48), ("car", 30)):
        count = sum(a["category_id"] == {"person": 1, "car": 3}[name] for a in merged["annotations"])
        assert count == boxes == stats.boxes[name]
        assert f"| {name} | {boxes} | {stats.tracks[name]} | {stats.identities[name]} |" in card
    assert "| job5 | failed: ConfigError: no such mesh |" in card
    assert "**5 of 6 jobs**" in card and "camgen batch x" in card and "CC0" in card
    for plot in ("classes", "box_heights", "occlusion"):
        assert f"](card/{plot}.png)" in card
        assert (out / "card" / f"{plot}.png").read_bytes().startswith(b"\x89PNG")


def test_the_batch_command_writes_them_with_the_dataset_files_shares_seed_and_licence(tmp_path, monkeypatch):
    dataset = make_dataset(
        tmp_path,
        "description: four jobs\nscenes: [scenes/walk.yaml]\nprofiles: [small, wide]\nseeds: [3, 4]\nseed: 5\n"
        "license: CC-BY-4.0\nsplits: {train: 0.5, val: 0.5, test: 0.0}\n",
    )

    def render(jobs, out_dir, **options) -> BatchSummary:
        """In place of the renders: each job's files as a render leaves them, the last job failed."""
        outcomes = []
        for batch, job in jobs[:-1]:
            directory = Path(out_dir) / job_directory_name(job)
            write_job(
                directory.parent, directory.name, {"cam": camera_coco(frames=3, tracks={1: "person"}, shift_px=0)}
            )
            outcomes.append(JobOutcome(batch, job.job_id, directory, "done", frames=3))
        batch, job = jobs[-1]
        outcomes.append(JobOutcome(batch, job.job_id, None, "failed", error="RuntimeError: out of memory"))
        return BatchSummary(outcomes, 1.0, None)

    monkeypatch.setattr("camgen.batch.run.run_batch", render)
    out = tmp_path / "out"
    assert main(["batch", str(dataset), "-o", str(out), "--workers", "1", "--frames", "3"]) == 1
    recorded = json.loads((out / "splits.json").read_text())
    assert recorded["seed"] == 5 and recorded["ratios"] == {"train": 0.5, "val": 0.5, "test": 0.0}
    assert [len(recorded["splits"][name]) for name in SPLITS] == [2, 2, 0]
    merged = json.loads((out / MERGED_NAME).read_text())
    assert len(merged["videos"]) == 3 and merged["licenses"][0]["name"] == "CC-BY-4.0"
    card = (out / CARD_NAME).read_text()
    assert "| walk-wide-seed4 | failed: RuntimeError: out of memory |" in card
    assert f"camgen batch {dataset} -o {out} --workers 1 --retries 1 --frames 3" in card
    assert "**CC-BY-4.0**" in card and "four jobs" in card
