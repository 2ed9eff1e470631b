"""A tiny dataset: one small scene, two 160×120 profiles, two seeds; four jobs of a few frames each."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import FIXED_PROFILE, SCENE, write

SMALL_PROFILE = FIXED_PROFILE.replace("width_px: 640", "width_px: 160").replace("height_px: 480", "height_px: 120")
WIDE_PROFILE = SMALL_PROFILE.replace("focal_length_mm: 4.0", "focal_length_mm: 3.0")

DATASET = """\
description: a walker seen through two small cameras, two seeds each
scenes: [scenes/walk.yaml]
profiles: [small, wide]
seeds: [3, 4]
combine: product
"""


def make_dataset(directory: Path, text: str = DATASET) -> Path:
    """tiny.yaml beside profiles/ (fixed, small, wide) and scenes/walk.yaml; returns the dataset's path."""
    write(directory, "profiles/fixed.yaml", SMALL_PROFILE)
    write(directory, "profiles/small.yaml", SMALL_PROFILE)
    write(directory, "profiles/wide.yaml", WIDE_PROFILE)
    write(directory, "scenes/walk.yaml", SCENE)
    return write(directory, "tiny.yaml", text)


@pytest.fixture
def dataset(tmp_path: Path) -> Path:
    return make_dataset(tmp_path)
