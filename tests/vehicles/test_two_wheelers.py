"""Bicycles and motorcycles with riders (`camgen.vehicles.two_wheeler`, `camgen.actors.riding`).

Geometry (no OpenGL): wheels of the cited size that turn by distance / radius, read back from the posed
rim's marker; a crank that turns with the rear wheel through the gearing, its pedals level; a front
wheel whose ground trace turns by the route's steering angle; every size at full lock inside the class
envelope. The rider (several statures, a route with turns and a stop): wrists on the grips and the
balls of the feet on the pedal treads or footpegs within 1 cm every frame, the hips on the saddle, the
knee flexed 30° with the pedal at the bottom. Rendered (one 320 × 240 frame through `execute`): the
two-wheelers and their riders are separate instances with COCO categories bicycle / motorcycle and
person, MOT17 classes 4 / 5 and 2 (person on vehicle), masks and boxes; the riders' visible keypoints
project inside their boxes; the motorcycle's rear plate carries its text, and, seen from behind, the
plate's own two-line image warped onto the annotated quad matches the rendered plate.
"""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest

from camgen.actors import rider_rig
from camgen.actors.skeleton import INDEX
from camgen.config.placement import placement
from camgen.config.profile import Profile
from camgen.config.scene import RIDER_ENVELOPE_M, VEHICLE_ENVELOPE_M, Mount, Scene, actor_shape
from camgen.io.annotations import COCO_CATEGORY_IDS, MOT_CLASSES, MOT_PERSON_ON_VEHICLE
from camgen.motion.trajectory import Route, actor_routes
from camgen.plan import PlanSettings, compile
from camgen.plan.annotations import Annotator
from camgen.plan.execute import execute
from camgen.plan.lens_stages import LensStages
from camgen.plan.visibility import box_corners, local_bounds
from camgen.render.scene_graph import build_scene_graph
from camgen.render.sequence import CameraRenderer
from camgen.vehicles import TwoWheelerRig, vehicle_rigs
from camgen.vehicles.look import BODY_TYPES, draw_look
from camgen.vehicles.plate import motorcycle_plate_image
from camgen.vehicles.two_wheeler import (
    CHAINRING_TEETH,
    COG_TEETH,
    FRONT,
    KNEE_FLEXION_AT_BOTTOM_RAD,
    PEDAL_LEFT,
    PEDAL_RIGHT,
    REAR,
    build_bicycle,
    build_motorcycle,
)

PLATE_TEXT = "MC21 ABC"
TURNING = [[-6.0, 0.0], [4.0, 0.0], [10.0, 6.0], [10.0, 14.0]]
"""A route with a left turn (a bicycle's 2 m and a motorcycle's 2.7 m turning circles fit its corner)."""


def _scene(statures=(1.75, 1.75), waypoints=TURNING, *, camera_y_m: float = -9.0) -> Scene:
    actors = []
    for k, (cls, seed, stature) in enumerate((("bicycle", 3, statures[0]), ("motorcycle", 4, statures[1]))):
        offset = 3.0 * k
        path = {"waypoints_m": [[x, y + offset] for x, y in waypoints], "speed_m_s": 5.0, "pause_s": 0.0}
        vehicle = {"seed": seed, "colour": "red" if k == 0 else "blue"} | ({"plate_text": PLATE_TEXT} if k else {})
        actors.append({"name": cls, "class": cls, "vehicle": vehicle, "path": path})
        rider = {"seed": 40 + k, "stature_m": stature, "age_group": "adult"}
        actors.append({"name": f"{cls}_rider", "class": "person", "rides": cls, "appearance": rider})
    return Scene.model_validate(
        {
            "duration_s": 6.0,
            "fps": 5,
            "lights": [
                {"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 200, "elevation_deg": 45},
                {"type": "ambient", "illuminance_lux": 10000},
            ],
            "environment": {
                "sky_luminance_cd_m2": 4000,
                "meshes": [
                    {"type": "plane", "name": "ground", "size_m": [60, 60], "material": {"color_rgb": [0.2] * 3}}
                ],
            },
            "actors": actors,
            "cameras": [
                {
                    "name": "cam",
                    "profile": "p",
                    "mount": {"position_m": [-2.5, camera_y_m, 2.0], "yaw_deg": 90, "pitch_deg": -6},
                }
            ],
            "outputs": {"video": False, "annotations": ["coco", "mot"], "camera_metadata": False},
        }
    )


def _rigs(scene: Scene):
    """(vehicle rig, rider rig) of the bicycle and of the motorcycle."""
    routes = actor_routes(scene)
    vehicles = vehicle_rigs(scene, routes)
    pairs = []
    for index, actor in enumerate(scene.actors):
        if actor.rides is not None:
            vehicle = vehicles[actor.rides]
            pairs.append((vehicle, rider_rig(actor, vehicle, scene_seed=scene.seed, actor_index=index)))
    return pairs


def _angle_about_y(v: np.ndarray) -> float:
    """The angle of `v` (vehicle frame) about +y, measured as `_rot_y` turns: from +z towards +x."""
    return math.atan2(v[0], v[2])


@pytest.mark.parametrize("body", ["bicycle", "motorcycle"])
def test_wheel_size_is_the_cited_tyre_and_the_dimensions_their_ranges(body):
    look = draw_look(5, body)
    model = build_bicycle(look) if body == "bicycle" else build_motorcycle(look)
    # Every vertex of a wheel bone lies within the wheel's radius of its axle, and the tread reaches it.
    for bone in (FRONT, REAR):
        points = np.concatenate([p.vertices_m[p.wheel == bone] for p in model.parts])
        reach = float(np.hypot(points[:, 0], points[:, 2]).max())
        assert reach == pytest.approx(look.wheel_radius_m, abs=0.002), (bone, reach)
    # ISO 5775 700 × 32C: (622 + 2 × 32) / 2 mm; 120/70 ZR17: (431.8 + 2 × 84) / 2 mm.
    assert look.wheel_radius_m == pytest.approx(0.343 if body == "bicycle" else 0.2999, abs=5e-4)
    dims = BODY_TYPES[body]
    assert dims.wheelbase_m[0] <= look.wheelbase_m <= dims.wheelbase_m[1]
    # Posed at rest: the drawn length, width and height within a few centimetres (a motorcycle's front
    # tyre ends 5 cm short of its spec length's bumper-less front; the rest are its parts' reach).
    rig = TwoWheelerRig(model, Route(np.array([[0.0, 0.0]]), np.zeros(1), 1.0))
    low, high, _ = rig.heading_box()
    size = high - low
    print(f"{body}: posed {np.round(size, 3)} m against drawn {look.length_m:.3f} × {look.width_m:.3f} × "
          f"{look.height_m:.3f} m, {len(rig.vertices_m)} vertices")  # fmt: skip
    assert size[0] == pytest.approx(look.length_m, abs=0.08)
    assert size[1] == pytest.approx(look.width_m, abs=0.02)
    assert size[2] == pytest.approx(look.height_m, abs=0.04)


def test_wheels_turn_by_distance_over_radius_and_the_crank_by_the_gearing():
    scene = _scene(waypoints=[[-6.0, 0.0], [30.0, 0.0]])
    (bike, _), (moto, _) = _rigs(scene)
    for rig in (bike, moto):
        model, R = rig.model, rig.look.wheel_radius_m
        marker = np.array([0.0, 0.0, R])  # the top of the tyre, wheel frame
        T0, bones0 = rig.pose(0.0)
        for time_s in (0.7, 1.9, 3.3):
            T, bones = rig.pose(time_s)
            travelled = float(np.linalg.norm(T[:2, 3] - T0[:2, 3]))  # a straight route: distance is displacement
            for bone in (FRONT, REAR):
                turned = _angle_about_y(bones[bone, :3, :3] @ marker) - _angle_about_y(bones0[bone, :3, :3] @ marker)
                expected = travelled / R
                assert math.remainder(turned - expected, 2 * math.pi) == pytest.approx(0.0, abs=1e-6)
            if model.bottom_bracket_m is None:
                continue
            # The crank, read from where the right pedal is about the bottom bracket, follows the rear wheel.
            crank = [_angle_about_y(b[PEDAL_RIGHT, :3, 3] - model.bottom_bracket_m) for b in (bones0, bones)]
            wheel = travelled / R
            assert math.remainder(crank[1] - crank[0] - wheel * COG_TEETH / CHAINRING_TEETH, 2 * math.pi) == (
                pytest.approx(0.0, abs=1e-6)
            )
            # The pedals stay level and opposite each other.
            for bone in (PEDAL_LEFT, PEDAL_RIGHT):
                assert np.allclose(bones[bone, :3, :3], np.eye(3))
            middle = (bones[PEDAL_LEFT, :3, 3] + bones[PEDAL_RIGHT, :3, 3]) / 2
            assert np.allclose(middle[[0, 2]], model.bottom_bracket_m[[0, 2]], atol=1e-9)
    print(
        f"cadence at 5 m/s: {5.0 / bike.look.wheel_radius_m * COG_TEETH / CHAINRING_TEETH * 60 / (2 * math.pi):.1f} rpm"
    )


def test_the_front_wheel_steers_by_the_routes_angle():
    (bike, _), (moto, _) = _rigs(_scene())
    for rig in (bike, moto):
        steered = 0
        for time_s in np.arange(0.0, 6.0, 0.25):
            _, bones = rig.pose(float(time_s))
            axle = bones[FRONT, :3, :3] @ np.array([0.0, 1.0, 0.0])
            # The wheel plane's trace on the ground is perpendicular to the axle's horizontal part.
            trace = math.atan2(-axle[0], axle[1])
            steer = rig.steer_rad(float(time_s))
            assert trace == pytest.approx(steer, abs=1e-6), (time_s, trace, steer)
            steered += abs(steer) > 0.1
        assert steered >= 2, "the route must turn"


@pytest.mark.parametrize("statures", [(1.55, 1.60), (1.75, 1.80), (1.95, 1.95)])
def test_hands_and_feet_stay_on_the_grips_and_pedals(statures):
    scene = _scene(statures)
    worst = {}
    for vehicle, rider in _rigs(scene):
        body = vehicle.look.body_type
        errors = []
        for time_s in np.arange(0.0, 6.0, 0.2):
            rider.place(float(time_s))
            targets = vehicle.rider_targets(float(time_s))
            R = targets.T_world_from_vehicle[:3, :3]
            J = rider.joints_m
            wrists = J[[INDEX["hand_l"], INDEX["hand_r"]]]
            balls = J[[INDEX["ball_l"], INDEX["ball_r"]]]
            hips = (J[INDEX["thigh_l"]] + J[INDEX["thigh_r"]]) / 2
            # Wrists a hand's width from the grip's axis, the balls of the feet on the treads (their joint
            # a ball's height over the sole), the hips over the seat.
            hand = np.linalg.norm(wrists - targets.grips_m, axis=1)
            assert np.all(hand < 0.07), (body, time_s, hand)
            foot = np.linalg.norm(balls - targets.feet_m - np.array([0, 0, rider.walker.ball_height_m]), axis=1)
            seat = np.linalg.norm(hips - (targets.seat_m + R @ [0, 0, 0.09]))
            grip = np.linalg.norm(wrists - rider.walker._wrist_targets(targets), axis=1)
            errors.append((grip.max(), foot.max(), seat))
            # The feet are under the rider, the pedals' treads under the balls (z up in the world).
            assert np.all(balls[:, 2] > targets.feet_m[:, 2])
        worst[body] = np.max(errors, axis=0)
        print(f"{body}, statures {statures}: worst wrist {worst[body][0] * 1000:.1f} mm, ball of foot "
              f"{worst[body][1] * 1000:.1f} mm, hips {worst[body][2] * 1000:.1f} mm")  # fmt: skip
        assert worst[body][0] < 0.01 and worst[body][1] < 0.01 and worst[body][2] < 1e-6, worst[body]


def test_the_saddle_fits_its_rider_with_the_knee_bent_30_degrees_at_the_bottom():
    for stature in (1.55, 1.95):
        (bike, rider), _ = _rigs(_scene((stature, 1.75)))
        bottom = None
        for time_s in np.linspace(2.0, 3.5, 400):  # at speed: find the right pedal at the bottom of its circle
            _, bones = bike.pose(float(time_s))
            height = bones[PEDAL_RIGHT, 2, 3]
            if bottom is None or height < bottom[1]:
                bottom = (float(time_s), height)
        rider.place(bottom[0])
        J = rider.joints_m
        thigh, shin = J[INDEX["calf_r"]] - J[INDEX["thigh_r"]], J[INDEX["foot_r"]] - J[INDEX["calf_r"]]
        flexion = math.acos(float(thigh @ shin / np.linalg.norm(thigh) / np.linalg.norm(shin)))
        print(f"rider {stature} m: knee flexed {math.degrees(flexion):.1f}° at the bottom")
        assert flexion == pytest.approx(KNEE_FLEXION_AT_BOTTOM_RAD, abs=math.radians(3))


def test_two_wheelers_and_riders_stay_inside_their_envelopes():
    """The largest two-wheelers of each class (longest and widest draw, tallest rider's saddle) at full
    lock, and riders from 1.55 to 1.95 m on them, fit `VEHICLE_ENVELOPE_M` and `RIDER_ENVELOPE_M` in the
    frame of the route's point (the rear axle)."""
    for statures in ((1.55, 1.55), (1.95, 1.95)):
        scene = _scene(statures)
        for (vehicle, rider), actor in zip(_rigs(scene), [a for a in scene.actors if a.rides], strict=True):
            cls = vehicle.look.body_type
            low_v, high_v = VEHICLE_ENVELOPE_M[cls]
            for time_s in np.arange(0.0, 6.0, 0.2):
                vehicle.place(float(time_s))
                rider.place(float(time_s))
                T = vehicle.T_world_from_vehicle
                origin = T[:3, 3] + vehicle.look.rear_axle_x_m * T[:3, 0]
                for vertices, (low, high) in (
                    (vehicle.vertices_m, (low_v, high_v)),
                    (rider.vertices_m, RIDER_ENVELOPE_M),
                ):
                    local = (vertices - origin) @ T[:3, :3]
                    assert np.all(local.min(axis=0) >= low) and np.all(local.max(axis=0) <= high), (cls, time_s)
            shape = actor_shape(actor)
            corners = box_corners(*local_bounds(shape), placement(shape))
            assert np.allclose((corners.min(axis=0), corners.max(axis=0)), RIDER_ENVELOPE_M)


def _profile() -> Profile:
    return Profile.model_validate(
        {
            "sensor": {"width_px": 320, "height_px": 240, "pixel_pitch_um": 3.0, "full_well_e": 10000,
                       "conversion_gain_dn_per_e": 0.4},
            "lens": {"focal_length_mm": 2.4, "f_number": 2.0},
        }
    )  # fmt: skip


@pytest.mark.opengl
def test_riders_and_their_two_wheelers_are_annotated_apart(renderer, tmp_path):
    scene = _scene(waypoints=[[-6.0, 0.0], [30.0, 0.0]])
    job = compile(scene, {"cam": _profile()}, settings=PlanSettings())
    frame = 8  # t = 1.6 s: both in view, side on
    execute(job, tmp_path, renderer=renderer, frames=[frame])
    (directory,) = [p for p in tmp_path.glob("*/cam") if p.is_dir()]
    coco = json.loads((directory / "coco.json").read_text())
    tracks = {t["name"]: t for t in coco["tracks"]}
    category = {c["id"]: c["name"] for c in coco["categories"]}
    for cls in ("bicycle", "motorcycle"):
        assert category[tracks[cls]["category_id"]] == cls
        assert category[tracks[f"{cls}_rider"]["category_id"]] == "person"
        assert tracks[f"{cls}_rider"]["rides_track_id"] == tracks[cls]["id"]
    assert COCO_CATEGORY_IDS["bicycle"] == tracks["bicycle"]["category_id"] == 2  # COCO 2017's id
    assert "plate_text" not in tracks["bicycle"]["attributes"]
    assert tracks["motorcycle"]["attributes"]["plate_text"] == PLATE_TEXT
    annotations = {a["instance_name"]: a for a in coco["annotations"]}
    assert set(annotations) == set(tracks), sorted(annotations)
    for name, annotation in annotations.items():
        assert annotation["area"] > 300 and annotation["segmentation"]["counts"], name
        x, y, w, h = annotation["bbox"]
        print(f"{name}: box {w} × {h} px, {annotation['area']} px")
    for cls in ("bicycle", "motorcycle"):
        rider = annotations[f"{cls}_rider"]
        x, y, w, h = rider["amodal_bbox"]
        keypoints = np.array(rider["keypoints"], dtype=np.float64).reshape(17, 3)
        shown = keypoints[keypoints[:, 2] > 0]
        assert len(shown) >= 10, keypoints
        assert np.all((shown[:, 0] >= x - 0.5) & (shown[:, 0] <= x + w + 0.5)), (cls, shown, rider["amodal_bbox"])
        assert np.all((shown[:, 1] >= y - 0.5) & (shown[:, 1] <= y + h + 0.5)), (cls, shown, rider["amodal_bbox"])
        # The rider sits above its two-wheeler's lower half: its box's top is above the vehicle's.
        assert y < annotations[cls]["amodal_bbox"][1]
    plates = annotations["motorcycle"]["plates"]
    assert [p["text"] for p in plates] == [PLATE_TEXT] and plates[0]["side"] == "rear"
    assert "plates" not in annotations["bicycle"]
    rows = [line.split(",") for line in (directory / "gt" / "gt.txt").read_text().splitlines()]
    mot = {int(row[1]): int(row[7]) for row in rows}
    assert mot[tracks["bicycle"]["id"]] == MOT_CLASSES["bicycle"] == 4
    assert mot[tracks["motorcycle"]["id"]] == MOT_CLASSES["motorcycle"] == 5
    assert mot[tracks["bicycle_rider"]["id"]] == mot[tracks["motorcycle_rider"]["id"]] == MOT_PERSON_ON_VEHICLE == 2


def test_a_motorcycle_lights_its_lamps_and_a_bicycle_its_front_and_rear_lamps():
    (bike, _), (moto, _) = _rigs(_scene())
    surfaces = {part.surface for part in moto.model.parts}
    assert {"head", "tail", "brake", "plates"} <= surfaces
    bike_surfaces = {part.surface for part in bike.model.parts}
    assert not {"head", "tail", "brake", "plates"} & bike_surfaces
    assert {"cycle_head", "cycle_tail"} <= bike_surfaces
    assert not any(bike.lamps(1.0).values())
    moto.lights_on = bike.lights_on = True
    lit = moto.lamps(1.0)
    assert lit["head"] and lit["tail"] and not lit["brake"] and not any(k.startswith("indicator") for k in lit)
    assert bike.lamps(1.0)["cycle_head"] and bike.lamps(1.0)["cycle_tail"]


@pytest.mark.opengl
def test_the_motorcycle_plate_reads_back_where_it_is_annotated(renderer):
    """A camera 1.6 m behind the standing motorcycle: the annotated quad, used to warp the two-line plate's
    own image into the frame, matches the rendered plate (normalised cross-correlation), and another
    text matches far worse."""
    scene = _scene(waypoints=[[-6.0, 0.0], [30.0, 0.0]])
    moto = vehicle_rigs(scene, actor_routes(scene))["motorcycle"]
    plate_centre = moto.plate_corners_world()["rear"].mean(axis=0)
    camera = scene.cameras[0].model_copy(
        update={
            "mount": Mount(position_m=tuple(plate_centre + np.array([-1.6, 0.0, 0.3])), yaw_deg=0.0, pitch_deg=-10.6)
        }
    )
    job = compile(scene.model_copy(update={"cameras": [camera]}), {"cam": _profile()}, settings=PlanSettings())
    (camera,) = job.cameras
    drawer = CameraRenderer(renderer, build_scene_graph(job.scene), camera)
    lens = LensStages(camera)
    try:
        state = camera.states[0]
        passes = lens.apply(state, drawer.frame(0, state).passes)
        frame = Annotator(drawer, lens).annotate(state, passes)
    finally:
        drawer.close()
    (plate,) = next(obj for obj in frame.objects if obj.name == "motorcycle").plates
    assert plate["visible"] and plate["text"] == PLATE_TEXT and plate["side"] == "rear"
    grey = passes.radiance @ np.array([0.2126, 0.7152, 0.0722])
    H, W = grey.shape

    def match(text: str) -> float:
        image = motorcycle_plate_image(text) @ np.array([0.2126, 0.7152, 0.0722], np.float32)
        h, w = image.shape
        source = np.float32([[0, 0], [w, 0], [w, h], [0, h]]) - 0.5  # pixel edges to OpenCV's centres
        M = cv2.getPerspectiveTransform(source, np.float32(plate["quad"]) - 0.5)
        warped = cv2.warpPerspective(image, M, (W, H), flags=cv2.INTER_AREA)
        inside = cv2.warpPerspective(np.ones_like(image), M, (W, H), flags=cv2.INTER_NEAREST) > 0
        inside = cv2.erode(inside.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
        a, b = grey[inside] - grey[inside].mean(), warped[inside] - warped[inside].mean()
        return float(a @ b / np.sqrt((a @ a) * (b @ b)))

    own, other = match(PLATE_TEXT), match("XW71 OKB")
    w, h = plate["bbox"][2:]
    print(f"motorcycle plate {w:.0f} x {h:.0f} px: correlation with its own text {own:.3f}, another {other:.3f}")
    assert own > 0.8 and own - other > 0.3
