"""Configuration: YAML → frozen pydantic models, with located, readable errors."""

from camgen.config.dataset import Dataset
from camgen.config.loader import (
    LoadedProfile,
    LoadedScene,
    check_cameras,
    find_profile,
    load_dataset,
    load_profile,
    load_scene,
)
from camgen.config.profile import Profile
from camgen.config.scene import Scene

__all__ = [
    "Dataset",
    "LoadedProfile",
    "LoadedScene",
    "Profile",
    "Scene",
    "check_cameras",
    "find_profile",
    "load_dataset",
    "load_profile",
    "load_scene",
]
