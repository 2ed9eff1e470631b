"""Amodal boxes through the lens agree with the mask of the fully visible object.

A car-sized box and a walker cross a 640×480 view through a strong barrel lens (k1 = −0.35) and
through a distortion-free one. On every frame where an actor is wholly in view and unoccluded, the box
of its projected mesh (`camgen.annotate.boxes.amodal_box`, through `project_points`) and the tight
box of its pixels in the instance pass after the lens agree within 1 px on every side. Measured worst
side: printed with -s. Each actor's unoccluded draw in its own window (`Annotator._alone_in_window`)
counts what a whole-frame draw through the lens counts.
"""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config.profile import Profile
from camgen.config.scene import Scene
from camgen.plan import PlanSettings, compile
from camgen.plan.annotations import Annotator
from camgen.plan.lens_stages import LensStages
from camgen.render.scene_graph import build_scene_graph
from camgen.render.sequence import CameraRenderer

pytestmark = pytest.mark.opengl


def profile(k1: float) -> Profile:
    return Profile.model_validate(
        {
            "sensor": {
                "width_px": 640,
                "height_px": 480,
                "pixel_pitch_um": 3.0,
                "full_well_e": 10000,
                "conversion_gain_dn_per_e": 0.4,
            },
            "lens": {"focal_length_mm": 2.2, "f_number": 2.0, "distortion": {"k1": k1, "k2": 0.05 if k1 else 0.0}},
        }
    )


SCENE = Scene.model_validate(
    {
        "duration_s": 2.0,
        "fps": 10,
        "lights": [{"type": "ambient", "illuminance_lux": 1000}],
        "environment": {"meshes": [{"type": "plane", "name": "ground", "size_m": [60, 60]}]},
        "actors": [
            {"name": "car", "class": "car", "path": {"waypoints_m": [[-9, 8], [9, 8]], "speed_m_s": 9.0}},
            {"name": "walker", "class": "person", "path": {"waypoints_m": [[3, 3], [-3, 12]], "speed_m_s": 5.0}},
        ],
        "cameras": [
            {"name": "cam", "profile": "p", "mount": {"position_m": [0, -2, 3.5], "yaw_deg": 90, "pitch_deg": -18}}
        ],
        "outputs": {"video": False, "annotations": ["coco"]},  # instance ids only (mot draws img1 frames)
    }
)


@pytest.mark.parametrize("k1", [-0.35, 0.0])
def test_amodal_box_matches_the_mask_of_a_fully_visible_object(renderer, k1):
    job = compile(SCENE, {"cam": profile(k1)}, settings=PlanSettings())
    camera = job.cameras[0]
    assert ("optics.remap" in {s.name for s in camera.stages}) == (k1 != 0)
    drawer = CameraRenderer(renderer, build_scene_graph(job.scene), camera)
    lens = LensStages(camera)
    annotator = Annotator(drawer, lens)
    worst, compared = 0.0, 0
    try:
        for index in range(job.frame_count):
            state = camera.states[index]
            frame = drawer.frame(index, state)
            annotations = annotator.annotate(state, lens.apply(state, frame.passes))
            # Each actor drawn alone in its own window (the default) counts what a whole-frame draw through
            # the lens counts (an identity `post` takes that path), keypoints included.
            whole = annotator.annotate(state, lens.apply(state, frame.passes), post=lambda image: image)
            for obj, reference in zip(annotations.objects, whole.objects, strict=True):
                assert (obj.name, obj.unoccluded_pixels) == (reference.name, reference.unoccluded_pixels)
                assert obj.visibility == reference.visibility
                if reference.keypoints is not None:
                    np.testing.assert_array_equal(obj.keypoints, reference.keypoints)
            for obj in annotations.objects:
                if obj.visibility < 1.0 or obj.truncation > 0 or obj.visible_box is None:
                    continue
                error = np.max(np.abs(np.subtract(obj.amodal_box, obj.visible_box)))
                worst = max(worst, float(error))
                compared += 1
    finally:
        drawer.close()
    print(f"k1 = {k1}: {compared} fully visible object-frames, worst side {worst:.3f} px")
    assert compared >= 10
    assert worst <= 1.0
