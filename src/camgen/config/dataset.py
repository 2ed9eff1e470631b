"""Dataset: which scenes, profiles and seeds to render, as a product or a zip of lists."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from camgen.config.base import Model, invalid


class SeedRange(Model):
    start: Annotated[int, Field(ge=0)] = 0
    count: Annotated[int, Field(ge=1, le=1_000_000)]


class Dataset(Model):
    description: str = ""
    scenes: Annotated[list[str], Field(min_length=1)]
    """Scene files, relative to the dataset file."""
    profiles: list[str] = []
    """Profiles that replace every camera's own; empty keeps the scenes' profiles."""
    seeds: list[Annotated[int, Field(ge=0)]] | SeedRange = [0]
    combine: Literal["product", "zip"] = "product"
    """product: every scene × profile × seed; zip: the i-th of each list together."""

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
