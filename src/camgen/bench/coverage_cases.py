"""Coverage cases: `camgen.coverage.report.scene_coverage` (what `camgen coverage` computes before it
writes) on a 100 × 100 m site at a 0.25 m ground grid (160 000 points) with 8 cameras, the size issue 22
sets its goal for (under 10 s on this machine): a ground plane, six buildings and eight lamp posts as
occluders, four 2.8 mm bullets on the corners looking in and four 4K box cameras at 8 mm on the edges'
midpoints looking across. The site is built here (not an example scene) so that the case stays the size
the goal names."""

from __future__ import annotations

import math
from pathlib import Path

from camgen.bench.harness import Case

SITE_M = 100.0
CELL_M = 0.25
REPEATS = 3


def site_scene_and_profiles(repo: Path):
    """(Scene, {camera name: Profile}) of the benchmark site."""
    from camgen.config import load_profile
    from camgen.config.scene import Scene

    half = SITE_M / 2
    buildings = [  # (x, y, width, depth, height), m
        (-25, -25, 20, 12, 9),
        (25, -25, 12, 20, 12),
        (-25, 25, 16, 16, 6),
        (25, 25, 20, 10, 15),
        (0, 30, 10, 6, 4),
        (0, -30, 6, 10, 4),
    ]
    meshes = [{"type": "plane", "name": "ground", "size_m": [SITE_M, SITE_M]}]
    meshes += [
        {"type": "box", "name": f"building_{i}", "size_m": [w, d, h], "position_m": [x, y, h / 2]}
        for i, (x, y, w, d, h) in enumerate(buildings)
    ]
    meshes += [
        {"type": "cylinder", "name": f"lamp_{i}", "radius_m": 0.12, "height_m": 8, "position_m": [x, y, 4]}
        for i, (x, y) in enumerate(
            [(sx * 10, sy * 10) for sx in (-1, 1) for sy in (-1, 1)] + [(-10, 0), (10, 0), (0, -10), (0, 10)]
        )
    ]
    cameras = []
    for i, (sx, sy) in enumerate([(-1, -1), (1, -1), (1, 1), (-1, 1)]):
        x, y = sx * (half - 2), sy * (half - 2)
        cameras.append(
            {
                "name": f"bullet_{i}",
                "profile": "bullet_4mp_2p8mm",
                "mount": {"position_m": [x, y, 6], "yaw_deg": math.degrees(math.atan2(-y, -x)), "pitch_deg": -20},
            }
        )
    for i, (x, y) in enumerate([(0, -half + 1), (half - 1, 0), (0, half - 1), (-half + 1, 0)]):
        cameras.append(
            {
                "name": f"box_{i}",
                "profile": "box_4k_varifocal",
                "focal_length_mm": 8,
                "mount": {"position_m": [x, y, 8], "yaw_deg": math.degrees(math.atan2(-y, -x)), "pitch_deg": -12},
            }
        )
    scene = Scene.model_validate(
        {
            "duration_s": 1,
            "environment": {"meshes": meshes},
            "lights": [{"type": "ambient", "illuminance_lux": 1000}],
            "cameras": cameras,
        }
    )
    models = {
        name: load_profile(repo / "profiles" / f"{name}.yaml").profile
        for name in ("bullet_4mp_2p8mm", "box_4k_varifocal")
    }
    return scene, {camera.name: models[camera.profile] for camera in scene.cameras}


def coverage_cases(repo: Path, facts: dict | None = None) -> list[Case]:
    """The whole computation, then its two parts (the lens model's projection and densities of every
    point for every camera; the occlusion test of the points in view); `facts` receives the grid's
    point count, the camera count, the points in view summed over the cameras and the site's share seen
    at detect or better."""

    from camgen.coverage.density import densities, in_image
    from camgen.coverage.grid import make_grid
    from camgen.coverage.occlusion import scene_occluders, sight_blocked
    from camgen.coverage.report import report, scene_coverage
    from camgen.coverage.views import home_view

    scene, profiles = site_scene_and_profiles(repo)
    half = SITE_M / 2
    points = make_grid((-half, half, -half, half), CELL_M, 0.0).points_m()
    views = [home_view(camera, profiles[camera.name]) for camera in scene.cameras]
    occluders = scene_occluders(scene)
    in_view = [in_image(densities(points, 0.0, view)[0], view.width_px, view.height_px) for view in views]

    def whole() -> None:
        coverage = scene_coverage(scene, profiles, cell_m=CELL_M)
        if facts is not None:
            network = report(coverage, "site")["planes"][0]["network"]
            facts.update(
                points=len(points),
                cameras=len(views),
                points_in_view=int(sum(mask.sum() for mask in in_view)),
                detect_share=network["area_at_least_class"]["detect"]["share"],
            )

    def lens() -> None:
        for view in views:
            densities(points, 0.0, view)

    def occlusion() -> None:
        for view, mask in zip(views, in_view, strict=True):
            sight_blocked(view.centre_m, points[mask], occluders)

    size = f"{SITE_M:g} × {SITE_M:g} m site, {CELL_M:g} m grid, {len(scene.cameras)} cameras"
    return [
        Case(f"camgen coverage: {size}", whole, repeats=REPEATS),
        Case(f"  of which projection and densities ({size})", lens, repeats=REPEATS),
        Case(f"  of which occlusion of the points in view ({size})", occlusion, repeats=REPEATS),
    ]
