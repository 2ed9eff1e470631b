"""A held camera's annotator draws an actor alone again only when its look changed (`Annotator._alone_kept_or_drawn`):
a car that waits is drawn alone once while it waits, and its counts are what a whole-frame draw through the lens
gives at every frame."""

from __future__ import annotations

import pytest

from camgen.config.scene import Scene
from camgen.plan import PlanSettings, compile
from camgen.plan.annotations import Annotator
from camgen.plan.lens_stages import LensStages
from camgen.render.scene_graph import build_scene_graph
from camgen.render.sequence import CameraRenderer
from tests.render.test_annotation_boxes import profile

pytestmark = pytest.mark.opengl

SCENE = Scene.model_validate(
    {
        "duration_s": 2.0,
        "fps": 5,
        "lights": [{"type": "ambient", "illuminance_lux": 1000}],
        "environment": {"meshes": [{"type": "plane", "name": "ground", "size_m": [60, 60]}]},
        "actors": [
            {"name": "walker", "class": "person", "path": {"waypoints_m": [[3, 3], [-3, 12]], "speed_m_s": 2.0}},
            {
                "name": "car",
                "class": "car",
                "vehicle": {"seed": 7, "body_type": "sedan"},
                "path": {"waypoints_m": [[-4, 9], [6, 9]], "speed_m_s": 4.0, "start_s": 1.0},
            },
        ],
        "cameras": [
            {"name": "cam", "profile": "p", "mount": {"position_m": [0, -2, 3.5], "yaw_deg": 90, "pitch_deg": -18}}
        ],
        "outputs": {"video": False, "annotations": ["coco"]},
    }
)


def test_a_waiting_car_is_drawn_alone_once_and_counted_alike(renderer, monkeypatch):
    job = compile(SCENE, {"cam": profile(-0.2)}, settings=PlanSettings())
    camera = job.cameras[0]
    drawer = CameraRenderer(renderer, build_scene_graph(job.scene), camera)
    lens = LensStages(camera)
    annotator = Annotator(drawer, lens)
    drawn: list[str] = []
    alone = Annotator._alone_in_window

    def counted(self, state, view, node, *args):
        drawn.append(node.name)
        return alone(self, state, view, node, *args)

    monkeypatch.setattr(Annotator, "_alone_in_window", counted)
    waiting = [index for index in range(job.frame_count) if camera.states[index].time_s < 1.0]
    try:
        for index in range(job.frame_count):
            state = camera.states[index]
            frame = drawer.frame(index, state)
            kept = annotator.annotate(state, lens.apply(state, frame.passes))
            whole = annotator.annotate(state, lens.apply(state, frame.passes), post=lambda image: image)
            assert [(o.name, o.unoccluded_pixels, o.visibility) for o in kept.objects] == [
                (o.name, o.unoccluded_pixels, o.visibility) for o in whole.objects
            ]
            assert any(o.name == "car" and o.unoccluded_pixels > 0 for o in kept.objects)
    finally:
        drawer.close()
    car = [name for name in drawn if name.endswith("car")]
    assert len(waiting) >= 3
    assert len(car) == 1 + job.frame_count - len(waiting), drawn  # once while it waits, then at every frame
    assert sum(name.endswith("walker") for name in drawn) == job.frame_count
