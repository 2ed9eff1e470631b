"""Procedural vehicles rendered (OpenGL): every body type parked in a row seen from a pole, and a plate
read back from a close view.

- Mask and box agree: for each vehicle wholly in view and unoccluded, the box of its projected mesh and
  the tight box of its pixels in the instance pass agree within 1 px on every side.
- The plate: the annotated quad, used to warp the plate's own image into the frame, matches the
  rendered plate (normalised cross-correlation), and a plate with another text matches far worse; the
  rendered plate's yellow pixels lie inside the annotated plate box and fill most of it.
- Lamps: lit tail lamps add exactly their emission to their pixels and change nothing else.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from camgen.config.profile import Profile
from camgen.config.scene import VEHICLE_BODY_TYPES, Scene
from camgen.io.annotations import SequenceAnnotations
from camgen.motion.trajectory import Route
from camgen.plan import PlanSettings, compile
from camgen.plan.annotations import Annotator
from camgen.plan.lens_stages import LensStages
from camgen.render.scene_graph import build_scene_graph
from camgen.render.sequence import CameraRenderer
from camgen.vehicles import vehicle_rig
from camgen.vehicles.look import TWO_WHEELERS
from camgen.vehicles.plate import plate_image

pytestmark = pytest.mark.opengl

BODIES = [(body, cls) for cls, bodies in VEHICLE_BODY_TYPES.items() for body in bodies if body not in TWO_WHEELERS]
"""The four-wheelers' body types (the two-wheelers, with riders: tests/vehicles/test_two_wheelers.py)."""
ROW_Y_M = 2.0
"""Where every rear axle stands; the vehicles face +y, their rear plates towards the cameras."""
PLATE_TEXT = "CG26 VEH"
PLATE_CAR = "sedan"
PLATE_DISTANCE_M = 2.2


def _profile(focal_length_mm: float) -> Profile:
    return Profile.model_validate(
        {
            "sensor": {
                "width_px": 320,
                "height_px": 240,
                "pixel_pitch_um": 6.0,
                "full_well_e": 10000,
                "conversion_gain_dn_per_e": 0.4,
            },
            "lens": {"focal_length_mm": focal_length_mm, "f_number": 2.0},
        }
    )


def _x(index: int) -> float:
    return (index - (len(BODIES) - 1) / 2) * 4.0


def _scene() -> Scene:
    actors = [
        {
            "name": body,
            "class": cls,
            "vehicle": {"body_type": body, "seed": 20 + i}
            | ({"plate_text": PLATE_TEXT, "colour": "blue"} if body == PLATE_CAR else {}),
            "path": {"waypoints_m": [[_x(i), ROW_Y_M]], "heading_deg": 90},
        }
        for i, (body, cls) in enumerate(BODIES)
    ]
    # The plate camera stands behind the sedan's rear plate, at its height, looking at it.
    index = [body for body, _ in BODIES].index(PLATE_CAR)
    from camgen.config.scene import Actor

    parked = Route(np.array([[_x(index), ROW_Y_M]]), np.zeros(1), 1.0, heading_rad=math.pi / 2)
    rig = vehicle_rig(Actor.model_validate(actors[index]), parked, scene_seed=0, actor_index=index)
    plate = rig.plate_corners_world()["rear"].mean(axis=0)
    return Scene.model_validate(
        {
            "duration_s": 0.1,
            "fps": 10,
            "lights": [
                {"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 250, "elevation_deg": 45},
                {"type": "ambient", "illuminance_lux": 10000},
            ],
            "environment": {
                "sky_luminance_cd_m2": 4000,
                "meshes": [
                    {"type": "plane", "name": "ground", "size_m": [80, 80], "material": {"color_rgb": [0.1] * 3}}
                ],
            },
            "actors": actors,
            "cameras": [
                {
                    "name": "pole",
                    "profile": "wide",
                    "mount": {"position_m": [0, -14, 6], "yaw_deg": 90, "pitch_deg": -14},
                },
                {
                    "name": "plate",
                    "profile": "tele",
                    "mount": {"position_m": [plate[0], plate[1] - PLATE_DISTANCE_M, plate[2]], "yaw_deg": 90},
                },
            ],
            "outputs": {"video": False, "frames": "exr", "annotations": ["coco"], "camera_metadata": False},
        }
    )


@pytest.fixture(scope="module")
def rendered(renderer):
    """camera name → (radiance after the lens (H, W, 3), FrameAnnotations, COCO document) of frame 0."""
    job = compile(_scene(), {"pole": _profile(1.0), "plate": _profile(2.5)}, settings=PlanSettings())
    graph = build_scene_graph(job.scene)
    result = {}
    for camera in job.cameras:
        drawer = CameraRenderer(renderer, graph, camera)
        lens = LensStages(camera)
        try:
            state = camera.states[0]
            passes = lens.apply(state, drawer.frame(0, state).passes)
            frame = Annotator(drawer, lens).annotate(state, passes)
        finally:
            drawer.close()
        sequence = SequenceAnnotations(name=camera.name, fps=job.fps, width_px=320, height_px=240, frame_count=1)
        sequence.add(frame)
        result[camera.name] = passes.radiance, frame, sequence.coco_document()
    return result


def test_every_body_type_is_drawn_and_its_mask_matches_its_projected_box(rendered):
    _, frame, coco = rendered["pole"]
    names = {obj.name for obj in frame.objects if obj.visible_box is not None}
    assert names == {body for body, _ in BODIES}
    compared = 0
    for obj in frame.objects:
        if obj.visibility < 1.0 or obj.truncation > 0:
            continue
        assert np.max(np.abs(np.subtract(obj.amodal_box, obj.visible_box))) <= 1.0, obj.name
        compared += 1
    assert compared >= 4
    # The masks are the vehicles' own pixels: many of them, in their boxes.
    for annotation in coco["annotations"]:
        assert annotation["area"] > 100


def test_the_plate_reads_back_where_it_is_annotated(rendered):
    radiance, frame, coco = rendered["plate"]
    car = next(obj for obj in frame.objects if obj.name == PLATE_CAR)
    plate = next(p for p in car.plates if p["side"] == "rear")
    assert plate["visible"] and plate["text"] == PLATE_TEXT
    assert not next(p for p in car.plates if p["side"] == "front")["visible"] if len(car.plates) > 1 else True
    annotation = next(a for a in coco["annotations"] if a["instance_name"] == PLATE_CAR)
    assert annotation["plates"][0]["text"] == PLATE_TEXT
    grey = radiance @ np.array([0.2126, 0.7152, 0.0722])
    H, W = grey.shape

    def match(text: str) -> float:
        image = plate_image(text, rear=True) @ np.array([0.2126, 0.7152, 0.0722], np.float32)
        h, w = image.shape
        # Pixel-edge corners of the image onto the annotated quad (pixel edges), both moved to OpenCV's
        # pixel centres.
        source = np.float32([[0, 0], [w, 0], [w, h], [0, h]]) - 0.5
        target = np.float32(plate["quad"]) - 0.5
        M = cv2.getPerspectiveTransform(source, target)
        warped = cv2.warpPerspective(image, M, (W, H), flags=cv2.INTER_AREA)
        inside = cv2.warpPerspective(np.ones_like(image), M, (W, H), flags=cv2.INTER_NEAREST) > 0
        inside = cv2.erode(inside.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
        a, b = grey[inside] - grey[inside].mean(), warped[inside] - warped[inside].mean()
        return float(a @ b / np.sqrt((a @ a) * (b @ b)))

    own, other = match(PLATE_TEXT), match("XW71 OKB")
    print(f"plate correlation: own text {own:.3f}, another {other:.3f}")
    assert own > 0.8 and own - other > 0.3
    # The yellow of the plate (green well above blue, unlike the amber lamps' and the red lamps') lies in
    # the annotated box and fills most of it.
    r, g, b = radiance[..., 0], radiance[..., 1], radiance[..., 2]
    yellow = (g > 3 * b) & (g > 0.55 * r) & (r > 0.02 * radiance.max())
    rows, cols = np.nonzero(yellow)
    x, y, w, h = plate["bbox"]
    assert cols.min() >= x - 1 and cols.max() + 1 <= x + w + 1 and rows.min() >= y - 1 and rows.max() + 1 <= y + h + 1
    assert (cols.max() + 1 - cols.min()) * (rows.max() + 1 - rows.min()) > 0.8 * w * h


def test_lit_lamps_add_their_luminance_and_nothing_else(renderer):
    """The same parked sedan seen from behind with its lamps off and on: the difference is the tail
    lamps' emission, exactly (the renderer adds emission as it is), at their pixels and nowhere else."""
    from camgen.render.renderer import View
    from camgen.render.scene_graph import build_scene_graph
    from camgen.vehicles import LAMP_COLOUR_RGB, LAMP_LUMINANCE_CD_M2
    from tests.render.conftest import camera_matrix, look_at, scene_from

    def draw(lights_on: bool) -> np.ndarray:
        scene = scene_from(
            lights=[{"type": "ambient", "illuminance_lux": 1000}],
            actors=[
                {
                    "name": "sedan",
                    "class": "car",
                    "vehicle": {"seed": 3, "body_type": "sedan", "lights_on": lights_on},
                    "path": {"waypoints_m": [[0, 0]]},
                }
            ],
        )
        view = View(camera_matrix(200, 200, 79.5, 59.5), look_at([-6.0, 0.3, 1.2], [0.0, 0.0, 0.7]), 160, 120)
        return renderer.draw(build_scene_graph(scene), view, ("radiance",)).radiance

    added = draw(True) - draw(False)
    expected = LAMP_LUMINANCE_CD_M2["tail"] * np.array(LAMP_COLOUR_RGB["tail"])
    lit = np.any(added != 0, axis=-1)
    assert lit.sum() > 20  # both tail lamps, several pixels each
    np.testing.assert_allclose(added[lit], np.broadcast_to(expected, added[lit].shape), rtol=1e-4)
