"""A dataset file expanded into batch jobs (scene × profile × seed), and each compiled into a Job.

The expansion is deterministic: the same dataset file gives the same jobs in the same order, with the
same names. A job's profile replaces every camera's own and its seed replaces the scene's `seed`, so
distinct (scene, profile, seed) give distinct scenes and hence distinct job hashes.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from camgen.config.loader import find_profile, load_dataset, load_profile, load_scene
from camgen.errors import ConfigError, Problem
from camgen.plan import PlanSettings
from camgen.plan.compile import compile
from camgen.plan.job import Job


@dataclass(frozen=True)
class BatchJob:
    """One entry of a dataset: which scene, with which profile and seed."""

    name: str
    """`<scene>-<profile or "own">-seed<seed>`: stable, and unique within the dataset."""
    dataset_path: Path
    index: int
    """Place of this job in the dataset's expansion, from 0."""
    scene_path: Path
    profile: str | None
    """The profile reference as the dataset writes it (a name or a path), or None: keep the scene's."""
    profile_path: Path | None
    seed: int


def expand(dataset_path: str | Path) -> list[BatchJob]:
    """The jobs of a dataset file, in order: scenes × profiles × seeds (product), or the i-th of each (zip).

    Raises ConfigError, naming the dataset file and the entry, for a missing scene file or an unknown profile.
    """
    dataset_path = Path(dataset_path)
    if not dataset_path.is_file():
        raise ConfigError(f"{dataset_path}: no such dataset file; give the path of a dataset YAML file")
    dataset = load_dataset(dataset_path)
    profile_paths = {ref: find_profile(ref, dataset_path) for ref in dataset.profiles}
    scenes = [dataset_path.parent / scene for scene in dataset.scenes]
    profiles: list[str | None] = list(dataset.profiles) or [None]
    seeds = dataset.seed_list
    if dataset.combine == "zip":
        count = len(scenes)
        entries = [(scenes[i], profiles[i] if dataset.profiles else None, seeds[i]) for i in range(count)]
    else:
        entries = [(scene, profile, seed) for scene in scenes for profile in profiles for seed in seeds]
    jobs = []
    for index, (scene_path, profile, seed) in enumerate(entries):
        label = "own" if profile is None else Path(profile).stem
        jobs.append(
            BatchJob(
                name=f"{scene_path.stem}-{label}-seed{seed}",
                dataset_path=dataset_path,
                index=index,
                scene_path=scene_path,
                profile=profile,
                profile_path=None if profile is None else profile_paths[profile],
                seed=seed,
            )
        )
    names = [job.name for job in jobs]
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise ConfigError(
            f"{dataset_path}: the jobs {', '.join(repeated)} appear more than once; remove the repeated scene, "
            "profile or seed"
        )
    return jobs


def compile_batch_job(batch_job: BatchJob, settings: PlanSettings | None = None) -> Job:
    """Load the job's scene, give every camera the job's profile (if any) and the scene the job's seed, compile.

    Raises ConfigError naming the dataset file and the job when the scene or the combination is invalid.
    """
    try:
        loaded = load_scene(batch_job.scene_path)
        profiles, profile_names = loaded.profile_models, loaded.profile_names
        cameras = loaded.scene.cameras
        if batch_job.profile_path is not None:
            override = load_profile(batch_job.profile_path)
            cameras = [camera.model_copy(update={"profile": override.name}) for camera in cameras]
            profiles = {camera.name: override.profile for camera in cameras}
            profile_names = {camera.name: override.name for camera in cameras}
        scene = loaded.scene.model_copy(update={"cameras": cameras, "seed": batch_job.seed})
        return compile(
            scene,
            profiles,
            scene_name=loaded.name,
            profile_names=profile_names,
            settings=settings,
            file_bounds=loaded.file_bounds,
        )
    except ConfigError as exc:
        where = f"{batch_job.dataset_path}: job {batch_job.name} (entry {batch_job.index})"
        raise ConfigError([Problem((), f"{where}: {problem}", None) for problem in exc.problems]) from None
