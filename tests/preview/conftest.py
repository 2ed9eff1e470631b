"""One tiny render shared by the preview tests: a 320×240 PTZ camera following a walker past a car, 4 frames,
video and COCO only."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import PTZ_PROFILE, write

# The shared PTZ test profile at half the resolution and twice the pixel pitch (the same sensor area).
PROFILE = (
    PTZ_PROFILE.replace("description: test ptz camera", "description: small ptz camera")
    .replace("width_px: 640", "width_px: 320")
    .replace("height_px: 480", "height_px: 240")
    .replace("pixel_pitch_um: 3.0", "pixel_pitch_um: 6.0")
)

SCENE = """\
duration_s: 1
fps: 10
seed: 1
environment:
  meshes:
    - {type: plane, name: ground, size_m: [20, 20]}
lights:
  - {type: ambient, illuminance_lux: 1000}
actors:
  - {name: walker, class: person, path: {waypoints_m: [[-1, 5], [3, 5]], speed_m_s: 1.4}}
  - {name: car, class: car, path: {waypoints_m: [[4, 8], [-4, 8]], speed_m_s: 3}}
cameras:
  - name: cam
    profile: small_ptz
    mount: {position_m: [0, -5, 3], yaw_deg: 90, pitch_deg: 0}
    ptz: {pan_deg: 0, tilt_deg: -15, zoom_x: 1.0, program: {type: follow, target: walker}}
outputs: {video: true, annotations: [coco]}
"""

FRAMES = 3


@pytest.fixture(scope="session")
def tiny_render(renderer, tmp_path_factory) -> Path:
    """The render's output directory (what `camgen render -o` names): OUT/<job>/cam/."""
    from camgen.config import load_scene
    from camgen.plan import PlanSettings, compile_scene
    from camgen.plan.execute import execute

    directory = tmp_path_factory.mktemp("preview_render")
    write(directory, "profiles/small_ptz.yaml", PROFILE)
    loaded = load_scene(write(directory, "scenes/walk.yaml", SCENE), [directory / "profiles"])
    job = compile_scene(loaded, PlanSettings(supersampling=1))
    out = directory / "out"
    execute(job, out, renderer=renderer, frames=range(FRAMES), resolve_path=loaded.path.parent.joinpath)
    return out
