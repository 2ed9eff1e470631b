"""Bench variants of the example scenes: one camera, another output size, more actors or cameras.

Each returns a new `LoadedScene` validated as a user's file would be, so what is timed is what
`camgen render` would run.
"""

from __future__ import annotations

import dataclasses

from camgen.config.loader import LoadedProfile, LoadedScene
from camgen.config.profile import Profile
from camgen.config.scene import Scene


def one_camera(loaded: LoadedScene, camera: str) -> LoadedScene:
    """The scene with only `camera`."""
    scene = loaded.scene.model_copy(update={"cameras": [c for c in loaded.scene.cameras if c.name == camera]})
    return dataclasses.replace(loaded, scene=scene, profiles={camera: loaded.profiles[camera]})


def resized_profile(profile: Profile, width_px: int, height_px: int) -> Profile:
    """The profile's sensor with `width_px` × `height_px` sites over the same sensor width (square
    pitch scaled), so a lens keeps its horizontal field of view; noise figures per site unchanged."""
    data = profile.model_dump()
    sensor = data["sensor"]
    scale = sensor["width_px"] / width_px
    sensor["pixel_pitch_um"] *= scale
    if sensor.get("pixel_pitch_y_um") is not None:
        sensor["pixel_pitch_y_um"] *= sensor["height_px"] / height_px
    sensor["principal_point_offset_px"] = tuple(x / scale for x in sensor["principal_point_offset_px"])
    sensor["width_px"], sensor["height_px"] = width_px, height_px
    return Profile.model_validate(data)


def at_output_size(loaded: LoadedScene, width_px: int, height_px: int) -> LoadedScene:
    """Every camera's stream at `width_px` × `height_px`: a virtual PTZ's output size, otherwise the
    sensor's (`resized_profile`)."""
    cameras, profiles = [], dict(loaded.profiles)
    for camera in loaded.scene.cameras:
        if camera.eptz is not None:
            eptz = camera.eptz.model_copy(update={"output_size_px": (width_px, height_px)})
            camera = camera.model_copy(update={"eptz": eptz})
        else:
            old = loaded.profiles[camera.name]
            profiles[camera.name] = LoadedProfile(old.name, old.path, resized_profile(old.profile, width_px, height_px))
        cameras.append(camera)
    scene = Scene.model_validate(
        {**loaded.scene.model_dump(by_alias=True), "cameras": [c.model_dump(by_alias=True) for c in cameras]}
    )
    return dataclasses.replace(loaded, scene=scene, profiles=profiles)
