"""Drivers behind glass (`camgen.vehicles.cabin`).

- Geometry: the seated driver lies inside the closed shell (winding number), behind the cabin's lining, for cars, a van,
  a truck and a bus; a UK-format plate seats it on the right, another format on the left; its identity
  follows the vehicle's seed; a vehicle that drives has one, a parked one none, and `vehicle.driver`
  overrides both.
- Rendered (OpenGL), a sedan seen close through its windscreen by day: where the driver projects (its
  triangles projected here with OpenCV's camera model, not by the renderer) the frame differs from the
  same frame without a driver, nowhere else; there the tinted glass is darker than clear glass; the
  instance and depth passes (the vehicle's mask) are bit for bit the same with and without the driver,
  and so are the annotated box and mask of a vehicle driving past a pole camera.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

import camgen.vehicles as vehicles
from camgen.config.scene import Actor
from camgen.motion.trajectory import Route
from camgen.vehicles import cabin as cabin_module
from camgen.vehicles import has_driver, vehicle_rig
from camgen.vehicles.body import build_vehicle, shell
from camgen.vehicles.cabin import LINING_INSET_M, drive_side, driver_appearance, driver_part
from camgen.vehicles.look import draw_look

BODIES = {"sedan": "car", "hatchback": "car", "suv": "car", "van": "truck", "box_truck": "truck", "bus": "bus"}


def winding_number(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Generalised winding number of a closed mesh at `points` (Jacobson et al. 2013): the sum of its
    triangles' signed solid angles (Van Oosterom & Strackee 1983) over 4π; 1 inside, 0 outside."""
    out = np.empty(len(points))
    triangles = vertices[faces]
    for start in range(0, len(points), 16):
        r = triangles[None] - points[start : start + 16, None, None, :]  # (P, F, 3, 3)
        a, b, c = r[:, :, 0], r[:, :, 1], r[:, :, 2]
        la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
        dot = lambda u, v: np.einsum("pfi,pfi->pf", u, v)  # noqa: E731
        omega = 2 * np.arctan2(dot(a, np.cross(b, c)), la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb)
        out[start : start + 16] = omega.sum(axis=1) / (4 * np.pi)
    return out


def signed_distance_m(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray, spacing_m: float = 0.03):
    """Signed distance of `points` to a closed, outward-wound mesh (negative inside), to about a centimetre:
    to the nearest centre of the mesh's triangles near the points subdivided to `spacing_m`, signed by that
    triangle's normal, and where that says outside (a fold of the loft can mislead it), by the winding
    number."""
    low, high = points.min(axis=0) - 0.5, points.max(axis=0) + 0.5
    centres = vertices[faces].mean(axis=1)
    near = np.all((centres > low) & (centres < high), axis=1)
    v, f = trimesh.remesh.subdivide_to_size(vertices, faces[near], max_edge=spacing_m)
    mesh = trimesh.Trimesh(v, f, process=False)
    distance, index = cKDTree(mesh.triangles_center).query(points)
    side = np.sign(np.einsum("ij,ij->i", points - mesh.triangles_center[index], mesh.face_normals[index]))
    doubtful = side >= 0
    if doubtful.any():
        side[doubtful] = np.where(winding_number(points[doubtful], vertices, faces) > 0.5, -1.0, 1.0)
    return side * distance


@pytest.mark.parametrize(("body", "seed"), [(body, 1) for body in sorted(BODIES)] + [("sedan", 9), ("sedan", 21)])
def test_the_driver_sits_inside_the_cabin_on_the_right(body, seed):
    """(Sedans 9 and 21: tall drivers whose knees met the front wheel arch before the seat slid back.)"""
    look = draw_look(seed, BODIES[body], pinned={"body_type": body})
    vertices, faces, _, _ = shell(look)
    closed = trimesh.Trimesh(vertices, faces, process=False)
    closed.merge_vertices()
    driver = driver_part(look)
    assert 800 <= len(driver.faces) <= 1300  # a low-detail person
    distance = signed_distance_m(driver.vertices_m, np.asarray(closed.vertices), np.asarray(closed.faces))
    # Inside the shell and behind the lining that lines it (so nothing of it pokes through either).
    assert distance.max() < -LINING_INSET_M, (body, distance.max())
    # Right-hand drive (UK plates): the driver sits on the vehicle's right (−y), in the front half.
    assert drive_side(look) == "right"
    assert driver.vertices_m[:, 1].max() < 0.0
    assert driver.vertices_m[:, 0].mean() > -0.1 * look.length_m
    # The model carries it, rigid with the body, after the lining in the cabin part.
    cabin = {part.name: part for part in build_vehicle(look, driver=True).parts}["cabin"]
    assert np.array_equal(cabin.vertices_m[-len(driver.vertices_m) :], driver.vertices_m)
    assert np.all(cabin.wheel == -1)


def test_another_plate_format_seats_the_driver_on_the_left_and_the_seed_picks_the_driver():
    look = draw_look(1, "car", pinned={"body_type": "sedan", "plate_text": "ABC 123"})
    assert drive_side(look) == "left"
    assert driver_part(look).vertices_m[:, 1].min() > 0.0
    assert driver_appearance(look) == driver_appearance(draw_look(1, "car", pinned={"body_type": "sedan"}))
    drawn = {driver_appearance(draw_look(seed, "car")) for seed in range(6)}
    assert len(drawn) == 6
    assert all(appearance.age_group != "child" and appearance.bag == "none" for appearance in drawn)


def test_a_driving_vehicle_has_a_driver_a_parked_one_none_unless_the_scene_says():
    parked = Route(np.array([[0.0, 0.0]]), np.zeros(1), 1.0)
    driving = Route(np.array([[0.0, 0.0], [30.0, 0.0]]), np.zeros(2), 5.0)
    for driver, expected in ((None, (False, True)), (True, (True, True)), (False, (False, False))):
        actor = Actor.model_validate(
            {"name": "car", "class": "car", "vehicle": {"driver": driver}, "path": {"waypoints_m": [[0, 0]]}}
        )
        assert (has_driver(actor, parked), has_driver(actor, driving)) == expected
    names = {part.name for part in vehicle_rig(actor, driving, scene_seed=0, actor_index=0).model.parts}
    assert "cabin" in names and "body_glass" in names


# ---------------------------------------------------------------------------------------------------------
# Rendered


def _sedan_scene(driver: bool):
    from tests.render.conftest import scene_from

    return scene_from(
        lights=[
            {"type": "sun", "illuminance_lux": 60000, "azimuth_deg": 200, "elevation_deg": 40},
            {"type": "ambient", "illuminance_lux": 15000},
        ],
        environment={
            "sky_luminance_cd_m2": 5000,
            "meshes": [{"type": "plane", "name": "ground", "size_m": [40, 40], "material": {"color_rgb": [0.12] * 3}}],
        },
        actors=[
            {
                "name": "car",
                "class": "car",
                "vehicle": {"seed": 3, "body_type": "sedan", "colour": "white", "driver": driver},
                "path": {"waypoints_m": [[0, 0]]},
            }
        ],
    )


K_PX = np.array([[170.0, 0.0, 79.5], [0.0, 170.0, 59.5], [0.0, 0.0, 1.0]])
"""A 160 × 120 view, about 50° across."""


@pytest.fixture(scope="module")
def windscreen_views(renderer):
    """(driver's projected mask (H, W) bool, {name: Passes}) of the sedan seen through its windscreen:
    "driver", "empty" (no driver), "clear" (a driver behind glass of transmittance 1)."""
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph
    from tests.render.conftest import look_at

    T = look_at([5.0, -1.0, 1.9], [0.3, -0.3, 1.1])
    view = View(K_PX, T, 160, 120)

    placed = {}

    def draw(driver: bool) -> object:
        vehicles._model.cache_clear()
        graph = build_scene_graph(_sedan_scene(driver))
        placed["T_world_from_vehicle"] = graph.vehicles[0].T_world_from_vehicle
        return renderer.draw(graph, view, ("radiance", "depth_m", "instance_id"))

    # Without the seats (`cabin.seats_part`, tests/vehicles/test_seats.py): the driver against the dark lining, as the
    # figures below were measured (a dark seat behind the driver leaves dark clothes less to differ from).
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(cabin_module, "seats_part", lambda look: None)
        passes = {"driver": draw(True), "empty": draw(False)}
        for name in ("WINDSCREEN_T", "FRONT_SIDE_T", "PRIVACY_T"):
            patch.setattr(cabin_module, name, 1.0)
        passes["clear"] = draw(True)
    vehicles._model.cache_clear()
    # The driver's triangles projected with OpenCV.
    look = draw_look(3, "car", pinned={"body_type": "sedan", "colour": "white"})
    driver = driver_part(look)
    T_cam_from_vehicle = np.linalg.inv(T) @ placed["T_world_from_vehicle"]
    rvec, _ = cv2.Rodrigues(T_cam_from_vehicle[:3, :3])
    image, _ = cv2.projectPoints(driver.vertices_m, rvec, T_cam_from_vehicle[:3, 3], K_PX, None)
    mask = np.zeros((120, 160), np.uint8)
    for triangle in image.reshape(-1, 2)[driver.faces]:
        cv2.fillConvexPoly(mask, np.round(triangle * 16).astype(np.int32), 1, lineType=cv2.LINE_8, shift=4)
    return mask.astype(bool), passes


@pytest.mark.opengl
def test_the_driver_shows_through_the_windscreen_and_changes_nothing_else(windscreen_views):
    mask, passes = windscreen_views
    luminance = {k: p.radiance @ np.array([0.2126, 0.7152, 0.0722]) for k, p in passes.items()}
    changed = np.abs(luminance["driver"] - luminance["empty"]) > 0.02 * luminance["empty"]
    grown = cv2.dilate(mask.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    # Nothing outside the driver's projection changes, bit for bit.
    assert np.array_equal(passes["driver"].radiance[~grown], passes["empty"].radiance[~grown])
    # Through the windscreen (the part of its projection not hidden by paint), the driver shows. The A-pillar
    # (`camgen.vehicles.body._screen_pillars`) hides the driver's near shoulder from this front three-quarter
    # view: 372 of 1367 px seen (507 before the pillars).
    seen = mask & changed
    print(f"driver's projection {mask.sum()} px, seen through the glass {seen.sum()} px")
    assert seen.sum() >= 0.25 * mask.sum() and seen.sum() >= 150
    relative = np.abs(luminance["driver"] - luminance["empty"])[seen] / luminance["empty"][seen]
    print(f"change where seen: median {np.median(relative):.3f}, 90th percentile {np.percentile(relative, 90):.3f}")
    assert np.median(relative) > 0.05 and np.percentile(relative, 90) > 0.2
    # Tinted glass (78 % windscreen, 72 % side) passes less of the driver than clear glass: darker,
    # by about the transmittance where the driver's light dominates the reflection.
    ratio = luminance["driver"][seen] / luminance["clear"][seen]
    print(f"tinted / clear over the driver: median {np.median(ratio):.3f}, max {ratio.max():.3f}")
    assert np.mean(ratio < 1.0) > 0.95 and 0.7 < np.median(ratio) < 0.99


@pytest.mark.opengl
def test_the_vehicle_mask_and_depth_are_the_same_with_and_without_the_driver(windscreen_views):
    _, passes = windscreen_views
    car = passes["driver"].instance_id == 1
    assert car.sum() > 2000
    assert np.array_equal(passes["driver"].instance_id, passes["empty"].instance_id)
    assert np.array_equal(passes["driver"].depth_m, passes["empty"].depth_m)


@pytest.mark.opengl
def test_the_annotated_box_and_mask_are_the_same_with_and_without_a_driver(renderer):
    """A car driving past a pole camera, annotated through the whole pipeline (lens, annotator)."""
    from camgen.config.profile import Profile
    from camgen.config.scene import Scene
    from camgen.plan import PlanSettings, compile
    from camgen.plan.annotations import Annotator
    from camgen.plan.lens_stages import LensStages
    from camgen.render.scene_graph import build_scene_graph
    from camgen.render.sequence import CameraRenderer

    profile = Profile.model_validate(
        {
            "sensor": {"width_px": 160, "height_px": 120, "pixel_pitch_um": 6.0, "full_well_e": 10000,
                       "conversion_gain_dn_per_e": 0.4},
            "lens": {"focal_length_mm": 1.2, "f_number": 2.0},
        }
    )  # fmt: skip

    def annotate(driver: bool | None):
        vehicles._model.cache_clear()
        scene = Scene.model_validate(
            {
                "duration_s": 0.1,
                "fps": 10,
                "lights": [
                    {"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 250, "elevation_deg": 45},
                    {"type": "ambient", "illuminance_lux": 10000},
                ],
                "environment": {"sky_luminance_cd_m2": 4000},
                "actors": [
                    {
                        "name": "car",
                        "class": "car",
                        "vehicle": {"seed": 5, "body_type": "hatchback", "driver": driver},
                        "path": {"waypoints_m": [[-6, 0], [20, 0]], "speed_m_s": 8.0},
                    }
                ],
                "cameras": [
                    {
                        "name": "pole",
                        "profile": "p",
                        "mount": {"position_m": [0, -7, 4], "yaw_deg": 100, "pitch_deg": -25},
                    }
                ],
                "outputs": {"video": False, "annotations": ["coco"], "camera_metadata": False},
            }
        )
        job = compile(scene, {"pole": profile}, settings=PlanSettings())
        graph = build_scene_graph(job.scene)
        (camera,) = job.cameras
        drawer = CameraRenderer(renderer, graph, camera)
        try:
            state = camera.states[0]
            lens = LensStages(camera)
            frame = Annotator(drawer, lens).annotate(state, lens.apply(state, drawer.frame(0, state).passes))
        finally:
            drawer.close()
        (car,) = frame.objects
        return car, frame.instance_id, graph.vehicles[0]

    with_driver, ids_with, rig_with = annotate(None)  # it drives: a driver
    without, ids_without, rig_without = annotate(False)
    vehicles._model.cache_clear()
    assert "cabin" in [p.name for p in rig_with.model.parts]
    assert len(rig_with.vertices_m) > len(rig_without.vertices_m) + 500
    for key in ("visible_box", "amodal_box", "unclipped_box", "visible_pixels", "unoccluded_pixels"):
        assert getattr(with_driver, key) == getattr(without, key), key
    assert math.isclose(with_driver.visibility, without.visibility)
    assert np.array_equal(with_driver.box_3d_world_m, without.box_3d_world_m)
    assert np.array_equal(ids_with, ids_without) and (ids_with == 1).sum() > 300
