"""Dataset: which scenes, profiles and seeds to render, as a product or a zip of lists, and what to randomise
per job (`camgen.batch.randomize` draws and applies it)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from camgen.config.base import Model, invalid
from camgen.config.ptz_program import PtzProgram

PositiveFloat = Annotated[float, Field(gt=0)]
NonNegativeFloat = Annotated[float, Field(ge=0)]
Percent = Annotated[float, Field(ge=0, le=100)]


class SeedRange(Model):
    start: Annotated[int, Field(ge=0)] = 0
    count: Annotated[int, Field(ge=1, le=1_000_000)]


class ProfileSpread(Model):
    """Unit-to-unit variation, % rms: each value is multiplied by (1 + N(0, pct/100)), clipped to stay valid."""

    read_noise_e: Percent = 0.0
    prnu_pct: Percent = 0.0
    dsnu_e: Percent = 0.0
    dark_current_e_per_s: Percent = 0.0
    focus_distance_m: Percent = 0.0
    """Of the focus the camera or its profile sets; a lens focused at its hyperfocal distance is left alone."""


class Randomize(Model):
    """What varies between real deployments, drawn per job from the dataset's `seed` and the job's name.

    Every knob left at its default changes nothing."""

    light_scale_range: tuple[PositiveFloat, PositiveFloat] | None = None
    """[min, max] factor on every light (illuminance_lux, intensity_cd) and the sky's luminance, drawn
    log-uniformly: time of day and light level. A sun or ambient light stops at the schema's 200 000 lux."""
    mount_position_jitter_m: Annotated[float, Field(ge=0, le=100)] = 0.0
    """Each camera's mount moves by a uniform offset in [-d, d] along each world axis, m."""
    mount_angle_jitter_deg: Annotated[float, Field(ge=0, le=180)] = 0.0
    """Each camera's mount yaw, pitch and roll each turn by a uniform offset in [-d, d], degrees (pitch
    stops at ±90°, roll at ±180°)."""
    actor_count_range: tuple[Annotated[int, Field(ge=0)], Annotated[int, Field(ge=0)]] | None = None
    """[min, max] number of the scene's actors to keep (capped by how many it has), a random subset in
    scene order; actors a PTZ follow program targets are always kept."""
    walk_seeds: bool = False
    """Give every actor's random_walk a new seed drawn per job (new paths)."""
    profile_spread_pct: ProfileSpread | None = None
    """Per-camera unit-to-unit variation of the profile; also gives each camera a new serial (its own
    fixed-pattern noise)."""
    ptz_programs: list[PtzProgram] = []
    """Programs to choose from, one drawn uniformly per camera with a (mechanical or virtual) PTZ head;
    empty keeps the scene's. Presets they name must exist in every such camera."""

    @property
    def is_identity(self) -> bool:
        return self == Randomize()

    @model_validator(mode="after")
    def _check(self) -> Randomize:
        for key, unit in (("light_scale_range", ""), ("actor_count_range", " actors")):
            value = getattr(self, key)
            if value is not None and value[0] > value[1]:
                raise invalid(
                    key, f"must be ordered [min, max] with min ≤ max, got [{value[0]:g}, {value[1]:g}]{unit}; swap them"
                )
        return self


class Splits(Model):
    """How `camgen batch` divides the dataset's jobs into train, val and test (`camgen.batch.dataset_files`).

    A job is one sequence (all its cameras go to one split, so one event never appears in two splits). The
    jobs are shuffled by a numpy Generator seeded with `seed` and cut into counts rounded by the largest
    remainder, each split with a ratio above 0 getting at least one job while there are jobs to give."""

    train: Annotated[float, Field(ge=0, le=1)] = 0.7
    """Share of the jobs in the training split."""
    val: Annotated[float, Field(ge=0, le=1)] = 0.15
    """Share of the jobs in the validation split."""
    test: Annotated[float, Field(ge=0, le=1)] = 0.15
    """Share of the jobs in the test split."""
    seed: Annotated[int, Field(ge=0)] | None = None
    """Seed of the shuffle; null: the dataset's `seed`."""

    @property
    def ratios(self) -> dict[str, float]:
        return {"train": self.train, "val": self.val, "test": self.test}

    @model_validator(mode="after")
    def _check(self) -> Splits:
        total = self.train + self.val + self.test
        if abs(total - 1.0) > 1e-6:
            raise invalid(
                "",
                f"train + val + test must be 1, got {self.train:g} + {self.val:g} + {self.test:g} = {total:g}; "
                "scale them to sum to 1",
            )
        return self


class Dataset(Model):
    description: str = ""
    license: str = ""
    """The licence of the rendered data (an SPDX id such as CC-BY-4.0, or its name), for the dataset card and
    the merged COCO file's `licenses`; empty: the card says none was given."""
    scenes: Annotated[list[str], Field(min_length=1)]
    """Scene files, relative to the dataset file."""
    profiles: list[str] = []
    """Profiles that replace every camera's own; empty keeps the scenes' profiles."""
    seeds: list[Annotated[int, Field(ge=0)]] | SeedRange = [0]
    combine: Literal["product", "zip"] = "product"
    """product: every scene × profile × seed; zip: the i-th of each list together."""
    seed: Annotated[int, Field(ge=0)] = 0
    """Root seed of `randomize`: with a job's name it fixes that job's draws (not the scenes' seeds)."""
    randomize: Randomize | None = None
    """Per-job variation of the scenes and profiles; null renders them as written."""
    splits: Splits = Splits()
    """Train/val/test shares of the jobs in the dataset-level COCO files `camgen batch` writes."""

    @property
    def seed_list(self) -> list[int]:
        if isinstance(self.seeds, SeedRange):
            return list(range(self.seeds.start, self.seeds.start + self.seeds.count))
        return list(self.seeds)

    @model_validator(mode="after")
    def _check(self) -> Dataset:
        if self.combine == "zip":
            lengths = {"scenes": len(self.scenes), "seeds": len(self.seed_list)}
            if self.profiles:
                lengths["profiles"] = len(self.profiles)
            if len(set(lengths.values())) > 1:
                text = ", ".join(f"{k}: {v}" for k, v in lengths.items())
                raise invalid("combine", f"zip needs lists of one length, got {text}; or use product")
        return self
