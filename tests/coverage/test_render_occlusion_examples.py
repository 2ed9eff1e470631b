"""Which ground points coverage calls visible, against the instance ids rendered through the lens, on the
example scenes (OpenGL).

scenes/intersection_two_cameras.yaml (a 4K box camera at 8 mm and the 2.8 mm bullet, two building
blocks, a signal pole, roads laid 1 cm over the ground) and scenes/parking_lot.yaml (the 30× PTZ dome at
its home view, a building, lamp posts, a kerb), without their actors (coverage plans for the fixed scene),
go through the real camera path: `camgen.plan.compile_scene`, `camgen.render.sequence.render_camera` and
the plan's lens stages, whose remap distorts the instance-id pass by nearest pixel. A ground grid point
(0.5 m cells) in a camera's view, on the ground plane and outside every solid is visible to the render when
the id at its distorted pixel is a ground-level surface (the ground, a road over it, paint on them), hidden when it
is anything else. Issue 22 asks for agreement at ≥ 99 % of these points. Measured: the box camera 100 %
of 3943 (840 hidden), the bullet 99.80 % of 9662 (1294 hidden), the PTZ 99.62 % of 6089 (165 hidden); the
points that differ lie 20–55 m away on the silhouettes of the signal pole, the lamp posts and the kerb,
where a pixel spans more than the 0.5 m cell and its nearest pixel falls on either side.

The profiles' sensors are scaled down 4× (same sensor size, so the same field of view and distortion).
"""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from camgen.config import load_scene
from camgen.config.markings import marking_names
from camgen.coverage.grid import make_grid
from camgen.coverage.network import camera_coverage
from camgen.coverage.occlusion import inside_solids, on_ground, scene_occluders
from camgen.coverage.views import home_view
from camgen.optics.projection import project_points
from camgen.plan import PlanSettings, compile_scene
from camgen.plan.lens_stages import LensStages
from camgen.render.scene_graph import instance_table
from camgen.render.sequence import render_camera
from tests.conftest import REPO, write
from tests.coverage.test_render_density_profiles import scaled_profile

pytestmark = pytest.mark.opengl

SCALE = 4
CELL_M = 0.5
EDGE_M = 1.0
"""The grid stays this far inside the ground plane's outline: 50 m away a pixel spans more than a metre of
grazing ground, and the nearest pixel of a point at the ground's edge falls off it into the sky."""
# (scene, its ground-level surfaces).
SCENES = [
    ("intersection_two_cameras", {"ground", "road_ew", "road_ns"}),
    ("parking_lot", {"asphalt"}),
]


@pytest.fixture(scope="module", params=SCENES, ids=[s[0] for s in SCENES])
def rendered_scene(request, renderer, tmp_path_factory):
    """(the planned job, the ground-level ids, {camera: its instance-id pass through the lens})."""
    name, ground_names = request.param
    directory = tmp_path_factory.mktemp(name)
    scene = yaml.safe_load((REPO / f"scenes/{name}.yaml").read_text(encoding="utf-8"))
    scene.pop("actors", None)
    scene["duration_s"] = 1 / scene["fps"]
    # coco asks for the instance pass, which the plan distorts with the lens (no image is rendered).
    scene["outputs"] = {"video": False, "annotations": ["coco"]}
    for profile in {camera["profile"] for camera in scene["cameras"]}:
        write(directory, f"profiles/{profile}.yaml", scaled_profile(profile, SCALE))
    path = write(directory, f"scenes/{name}.yaml", yaml.safe_dump(scene, sort_keys=False))
    job = compile_scene(load_scene(path), PlanSettings())
    # Road markings lie on the ground (`environment.markings`): a ground-level surface, never an occluder.
    ground_names = ground_names | set(marking_names(job.scene.environment.markings))
    ground_ids = {i.instance_id for i in instance_table(job.scene) if i.name in ground_names}
    ids = {}
    for camera in job.cameras:
        assert "optics.remap" in {stage.name for stage in camera.stages}
        (frame,) = render_camera(renderer, job, camera, frames=[0])
        ids[camera.name] = LensStages(camera).apply(camera.states[frame.index], frame.passes).instance_id
    return job, ground_ids, ids


def test_coverage_agrees_with_the_rendered_instance_ids(rendered_scene):
    job, ground_ids, ids = rendered_scene
    scene = job.scene
    occluders = scene_occluders(scene)
    xs = [mesh.size_m[0] / 2 for mesh in scene.environment.meshes if mesh.name in ("ground", "asphalt")]
    ys = [mesh.size_m[1] / 2 for mesh in scene.environment.meshes if mesh.name in ("ground", "asphalt")]
    grid = make_grid((-xs[0] + EDGE_M, xs[0] - EDGE_M, -ys[0] + EDGE_M, ys[0] - EDGE_M), CELL_M, 0.0)
    points = grid.points_m()
    solid_or_off_ground = inside_solids(points, occluders) | ~on_ground(points, occluders)
    for camera in job.cameras:
        view = home_view(next(c for c in scene.cameras if c.name == camera.name), camera.profile)
        np.testing.assert_allclose(camera.states[0].K_px, view.K_px, rtol=1e-12)
        np.testing.assert_allclose(camera.states[0].T_world_from_cam, view.T_world_from_cam, atol=1e-9)
        coverage = camera_coverage(grid, view, occluders)
        considered = coverage.in_view.ravel() & ~solid_or_off_ground
        uv, _ = project_points(points[considered], view.T_world_from_cam, view.K_px, view.distortion)
        u = np.clip(np.round(uv[:, 0]).astype(int), 0, view.width_px - 1)
        v = np.clip(np.round(uv[:, 1]).astype(int), 0, view.height_px - 1)
        seen_by_render = np.isin(ids[camera.name][v, u], list(ground_ids))
        seen = coverage.visible.ravel()[considered]
        agreement = np.mean(seen == seen_by_render)
        assert considered.sum() > 2000, camera.name
        assert (~seen).sum() > 100, camera.name  # the buildings hide real areas
        assert agreement >= 0.99, (camera.name, agreement)
