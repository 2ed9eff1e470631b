"""A camera's label outputs load in the field's own tools as they are.

One tiny render (160×120, 4 frames, the walker straddling the image's left border) writes a MOT17
sequence (img1/, gt/gt.txt, seqinfo.ini, det/det.txt), YOLO labels (images/, labels/, data.yaml) and
coco.json: py-motmetrics reads the MOT ground truth and scores it against itself as perfect, seqinfo.ini
matches the images, each YOLO label is its COCO box normalised, and pycocotools' COCOeval scores the
COCO ground truth against itself at AP 1 for boxes and masks.
"""

from __future__ import annotations

import configparser
import json

import cv2
import motmetrics
import numpy as np
import pytest
import yaml
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval

from camgen.cli.main import main
from camgen.io.annotations import SequenceAnnotations
from tests.cli.test_annotation_formats import iou_matrix
from tests.conftest import FIXED_PROFILE, SCENE, write

FRAMES = 4
WIDTH_PX, HEIGHT_PX = 160, 120
# The test camera at a quarter of its resolution, with pixels four times as large: the same view.
TINY_PROFILE = (
    FIXED_PROFILE.replace("width_px: 640", f"width_px: {WIDTH_PX}")
    .replace("height_px: 480", f"height_px: {HEIGHT_PX}")
    .replace("pixel_pitch_um: 3.0", "pixel_pitch_um: 12.0")
)
OUTPUTS = "{video: false, annotations: [mot, yolo, coco], mot_detections: true}"


def render(directory, outputs: str = OUTPUTS, frames: int = FRAMES):
    write(directory, "profiles/fixed.yaml", TINY_PROFILE)
    scene = SCENE.replace("duration_s: 1", f"duration_s: 1\noutputs: {outputs}").replace(
        "waypoints_m: [[-3, 5], [3, 5]]", "waypoints_m: [[-2.6, 5], [3, 5]]"
    )
    path = write(directory, "scenes/tiny.yaml", scene)
    assert main(["render", str(path), "-o", str(directory / "out"), "--frames", str(frames)]) == 0
    return next((directory / "out").iterdir()) / "cam"


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    """The camera folder of the one render the tests of this module read."""
    return render(tmp_path_factory.mktemp("labels"))


def test_mot_sequence_is_laid_out_as_mot17_and_scores_perfectly_against_itself(sequence):
    info = configparser.ConfigParser()
    info.optionxform = str  # MOT's keys are camel case
    info.read(sequence / "seqinfo.ini")
    seq = info["Sequence"]
    assert list(seq) == ["name", "imDir", "frameRate", "seqLength", "imWidth", "imHeight", "imExt"]
    assert (seq["name"], seq["imDir"], seq["frameRate"], seq["imExt"]) == ("cam", "img1", "10", ".jpg")
    images = sorted((sequence / seq["imDir"]).iterdir())
    assert [p.name for p in images] == [f"{k:06d}{seq['imExt']}" for k in range(1, int(seq["seqLength"]) + 1)]
    assert int(seq["seqLength"]) == FRAMES
    for path in images:
        assert cv2.imread(str(path)).shape == (int(seq["imHeight"]), int(seq["imWidth"]), 3)

    gt = motmetrics.io.loadtxt(str(sequence / "gt" / "gt.txt"), fmt="mot15-2D")
    assert set(gt.index.get_level_values("FrameId")) == set(range(1, FRAMES + 1))
    # motmetrics 1.4's own IoU helper calls np.asfarray, gone in NumPy 2: the same distance, from tests.
    accumulator = motmetrics.MOTAccumulator(auto_id=True)
    for _, boxes in gt.groupby(level="FrameId"):
        xywh = boxes[["X", "Y", "Width", "Height"]].to_numpy()
        ids = boxes.index.get_level_values("Id")
        accumulator.update(ids, ids, 1.0 - iou_matrix(xywh, xywh))
    summary = motmetrics.metrics.create().compute(accumulator, metrics=["mota", "idf1", "num_switches"])
    assert summary["mota"].iloc[0] == 1.0 and summary["idf1"].iloc[0] == 1.0

    # The walker crosses the left border: MOT's box leaves the image, COCO's amodal box is clipped.
    coco = json.loads((sequence / "coco.json").read_text())
    frame_of = {image["id"]: image["frame_index"] for image in coco["images"]}
    walker = [a for a in coco["annotations"] if a["instance_name"] == "walker"]
    assert walker
    for annotation in walker:
        row = gt.loc[(frame_of[annotation["image_id"]] + 1, annotation["track_id"])]
        x, y, w, h = annotation["amodal_bbox"]
        x0, y0 = row["X"], row["Y"]  # motmetrics moved MOT's 1-based bb_left and bb_top to pixel edges
        x1, y1 = x0 + row["Width"], y0 + row["Height"]
        assert x0 < 0 and x == 0
        clipped = [max(x0, 0), max(y0, 0), min(x1, WIDTH_PX), min(y1, HEIGHT_PX)]
        np.testing.assert_allclose(clipped, [x, y, x + w, y + h], atol=1e-3)
        assert row["Visibility"] == pytest.approx(annotation["visibility"] * (1 - annotation["truncation"]), abs=1e-4)

    # Public detections: MOT17's ten columns (frame, -1, box, score, -1, -1, -1), whatever HOG finds here.
    for line in (sequence / "det" / "det.txt").read_text().splitlines():
        fields = line.split(",")
        assert len(fields) == 10 and fields[1] == "-1" and fields[7:] == ["-1"] * 3


def test_det_lines_are_mot17s():
    sequence = SequenceAnnotations(name="s", fps=10, width_px=160, height_px=120, frame_count=1, detections=True)
    sequence.add_detections(0, [(10.0, 20.0, 30.5, 60.0, 1.25)])
    assert list(sequence.detections) == ["1,-1,11.000,21.000,20.500,40.000,1.2500,-1,-1,-1"]


def test_yolo_labels_are_the_coco_boxes_normalised(sequence):
    data = yaml.safe_load((sequence / "data.yaml").read_text())
    assert data["train"] == data["val"] == "images" and "path" not in data
    coco = json.loads((sequence / "coco.json").read_text())
    # YOLO's ids count from 0; coco.json keeps COCO's own ids: the two name the same classes.
    assert sorted(data["names"]) == list(range(len(coco["categories"])))
    assert sorted(data["names"].values()) == sorted(c["name"] for c in coco["categories"])
    category_names = {c["id"]: c["name"] for c in coco["categories"]}
    images = sorted(p.stem for p in (sequence / "images").iterdir())
    assert images == sorted(p.stem for p in (sequence / "labels").iterdir()) == [f"{k:06d}" for k in range(FRAMES)]
    assert cv2.imread(str(sequence / "images" / "000000.jpg")).shape == (HEIGHT_PX, WIDTH_PX, 3)
    checked = 0
    for image in coco["images"]:
        lines = (sequence / "labels" / f"{image['frame_index']:06d}.txt").read_text().splitlines()
        annotations = [a for a in coco["annotations"] if a["image_id"] == image["id"]]
        assert len(lines) == len(annotations)
        for line, annotation in zip(lines, annotations, strict=True):
            class_id, *box = line.split()
            x, y, w, h = annotation["bbox"]
            assert data["names"][int(class_id)] == category_names[annotation["category_id"]]
            expected = [(x + w / 2) / WIDTH_PX, (y + h / 2) / HEIGHT_PX, w / WIDTH_PX, h / HEIGHT_PX]
            np.testing.assert_allclose([float(v) for v in box], expected, atol=5e-7)
            assert all(0 <= float(v) <= 1 for v in box)
            checked += 1
    assert checked >= FRAMES


@pytest.mark.parametrize("kind", ["bbox", "segm"])
def test_coco_ground_truth_scores_ap_1_against_itself(sequence, kind):
    coco = COCO(str(sequence / "coco.json"))
    results = [{**a, "score": 1.0} for a in coco.loadAnns(coco.getAnnIds())]
    evaluation = COCOeval(coco, coco.loadRes(results), kind)
    evaluation.evaluate()
    evaluation.accumulate()
    evaluation.summarize()
    assert evaluation.stats[0] == 1.0  # AP at IoU 0.50:0.95


def test_png_images_on_request(tmp_path):
    directory = render(tmp_path, "{video: false, annotations: [mot, yolo], annotation_images: png}", frames=1)
    assert "imExt=.png" in (directory / "seqinfo.ini").read_text()
    rgb = cv2.imread(str(directory / "img1" / "000001.png"))
    assert rgb.shape == (HEIGHT_PX, WIDTH_PX, 3)
    np.testing.assert_array_equal(cv2.imread(str(directory / "images" / "000000.png")), rgb)
