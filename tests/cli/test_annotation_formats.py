"""The annotation files of a render load in the field's own tools.

`pycocotools.coco.COCO` loads coco.json and `mask.decode` of every annotation reproduces the
instance pass (saved by --save-passes, after the lens) exactly; `motmetrics.io.loadtxt` parses
gt/gt.txt, and scoring the ground truth against itself gives MOTA = 1.
"""

from __future__ import annotations

import json

import motmetrics
import numpy as np
from pycocotools import mask as mask_utils
from pycocotools.coco import COCO

from camgen.cli.main import main
from tests.conftest import SCENE, write


def render(workspace, frames: int = 6, scene_text: str = SCENE, annotations: str = "mot, coco"):
    scene = write(
        workspace,
        "scenes/walk.yaml",
        scene_text.replace(
            "duration_s: 1",
            f"duration_s: 1\noutputs: {{video: false, raw_dng: false, annotations: [{annotations}]}}",
        ),
    )
    out = workspace / "out"
    assert main(["render", str(scene), "-o", str(out), "--frames", str(frames), "--save-passes"]) == 0
    return next(out.iterdir()) / "cam"


def test_coco_masks_reproduce_the_instance_pass(workspace):
    directory = render(workspace)
    coco = COCO(str(directory / "coco.json"))
    assert coco.getCatIds(catNms=["person"]) and len(coco.getImgIds()) == 6
    checked = 0
    for image_id in coco.getImgIds():
        frame = coco.imgs[image_id]["frame_index"]
        instance = np.load(directory / "passes" / f"{frame:06d}.npz")["instance_id"]
        for annotation in coco.loadAnns(coco.getAnnIds(imgIds=[image_id])):
            decoded = mask_utils.decode(annotation["segmentation"]).astype(bool)
            np.testing.assert_array_equal(decoded, instance == annotation["track_id"])
            x, y, w, h = annotation["bbox"]
            rows, cols = np.nonzero(decoded)
            assert (x, y, x + w, y + h) == (cols.min(), rows.min(), cols.max() + 1, rows.max() + 1)
            assert annotation["area"] == decoded.sum() == coco.annToMask(annotation).sum()
            checked += 1
    assert checked >= 4  # the walker, once it has walked into the view


def iou_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU of every pair of [x, y, w, h] boxes; pairs below 0.5 are not matched (NaN)."""
    ax0, ay0, ax1, ay1 = a[:, 0, None], a[:, 1, None], (a[:, 0] + a[:, 2])[:, None], (a[:, 1] + a[:, 3])[:, None]
    bx0, by0, bx1, by1 = b[:, 0], b[:, 1], b[:, 0] + b[:, 2], b[:, 1] + b[:, 3]
    inter = np.clip(np.minimum(ax1, bx1) - np.maximum(ax0, bx0), 0, None) * np.clip(
        np.minimum(ay1, by1) - np.maximum(ay0, by0), 0, None
    )
    iou = inter / (a[:, 2, None] * a[:, 3, None] + b[:, 2] * b[:, 3] - inter)
    return np.where(iou >= 0.5, iou, np.nan)


def test_mot_ground_truth_parses_and_scores_perfectly_against_itself(workspace):
    directory = render(workspace)
    gt = motmetrics.io.loadtxt(str(directory / "gt" / "gt.txt"), fmt="mot15-2D")
    assert len(gt) >= 4
    # motmetrics 1.4's own IoU helper calls np.asfarray, gone in NumPy 2: the same distance here.
    accumulator = motmetrics.MOTAccumulator(auto_id=True)
    for _, boxes in gt.groupby(level="FrameId"):
        xywh = boxes[["X", "Y", "Width", "Height"]].to_numpy()
        ids = boxes.index.get_level_values("Id")
        accumulator.update(ids, ids, 1.0 - iou_matrix(xywh, xywh))
    summary = motmetrics.metrics.create().compute(accumulator, metrics=["mota", "num_switches"], name="self")
    assert summary["mota"].iloc[0] == 1.0 and summary["num_switches"].iloc[0] == 0
    seqinfo = (directory / "seqinfo.ini").read_text()
    assert "frameRate=10" in seqinfo and "imWidth=640" in seqinfo and "seqLength=6" in seqinfo
    states = [json.loads(line) for line in (directory / "camera.jsonl").read_text().splitlines()]
    assert len(states) == 6


def test_two_renders_of_one_scene_and_seed_are_byte_identical(workspace):
    """Raw frames, annotations, video and metadata: the manifests (file hashes) of two runs agree."""
    first = render(workspace, frames=4).parent
    second_out = workspace / "again"
    scene = workspace / "scenes" / "walk.yaml"
    assert main(["render", str(scene), "-o", str(second_out), "--frames", "4", "--save-passes"]) == 0
    second = next(second_out.iterdir())
    manifest = json.loads((first / "manifest.json").read_text())
    assert any(path.endswith("gt/gt.txt") for path in manifest["files"])
    assert any(path.endswith("coco.json") for path in manifest["files"])
    assert (first / "manifest.json").read_bytes() == (second / "manifest.json").read_bytes()
    assert main(["verify", str(first)]) == 0
    (first / "cam" / "gt" / "gt.txt").write_text("1,1,1,1,1,1,1,1,1\n")
    assert main(["verify", str(first)]) == 1


def test_raw_dng_frames_and_depth_files_match_the_render(workspace):
    """The DNG rawpy reads holds the raw mosaic exactly (pattern, levels), the 16-bit depth PNG the
    depth pass in millimetres, and the EXR frame the radiance through the lens."""
    import cv2
    import OpenImageIO as oiio  # noqa: N813 (the library's usual short name)
    import rawpy

    text = SCENE.replace(
        "duration_s: 1", "duration_s: 1\noutputs: {video: false, raw_dng: true, frames: exr, depth: png16}"
    )
    scene = write(workspace, "scenes/files.yaml", text)
    out = workspace / "out"
    assert main(["render", str(scene), "-o", str(out), "--frames", "2", "--save-passes"]) == 0
    directory = next(out.iterdir()) / "cam"
    passes = np.load(directory / "passes" / "000001.npz")
    with rawpy.imread(str(directory / "raw" / "000001.dng")) as raw:
        np.testing.assert_array_equal(raw.raw_image, passes["raw_dn"])
        assert raw.color_desc == b"RGBG" and raw.raw_pattern.tolist() == [[0, 1], [3, 2]]  # RGGB
        assert raw.black_level_per_channel == [64] * 4 and raw.white_level == 4095
    depth_mm = cv2.imread(str(directory / "depth" / "000001.png"), cv2.IMREAD_UNCHANGED)
    depth_m = passes["depth_m"]
    finite = np.isfinite(depth_m)
    np.testing.assert_array_equal(depth_mm[~finite], 0)
    np.testing.assert_allclose(depth_mm[finite], np.round(depth_m[finite] * 1000), atol=1)
    radiance = oiio.ImageBuf(str(directory / "frames" / "000001.exr")).get_pixels(oiio.FLOAT)
    np.testing.assert_allclose(radiance, passes["radiance_cd_m2"], rtol=1e-6)


def test_a_second_render_into_the_same_directory_leaves_nothing_stale(workspace):
    text = SCENE.replace(
        "duration_s: 1", "duration_s: 1\noutputs: {video: false, frames: png, annotations: [mot, coco]}"
    )
    scene = write(workspace, "scenes/again.yaml", text)
    out = workspace / "out"
    assert main(["render", str(scene), "-o", str(out), "--frames", "5"]) == 0
    assert main(["render", str(scene), "-o", str(out), "--frames", "2"]) == 0
    job_dir = next(out.iterdir())
    assert sorted(p.name for p in (job_dir / "cam" / "frames").iterdir()) == ["000000.png", "000001.png"]
    manifest = json.loads((job_dir / "manifest.json").read_text())
    assert manifest["rendered"] == {"cameras": ["cam"], "frames": [0, 1]}
    coco = json.loads((job_dir / "cam" / "coco.json").read_text())
    assert [image["file_name"] for image in coco["images"]] == ["frames/000000.png", "frames/000001.png"]
    assert all((job_dir / "cam" / image["file_name"]).exists() for image in coco["images"])
    assert main(["verify", str(job_dir)]) == 0


def test_person_keypoints_score_perfectly_in_cocoeval_and_boxes_are_tight(workspace):
    """COCO keypoints load in pycocotools and score AP = 1 against themselves (OKS); the amodal box of an
    unoccluded person inside the image is the tight box of its mask (≤ 1 px), and its visible keypoints
    fall inside that box."""
    from pycocotools.cocoeval import COCOeval

    # The walker seen whole: the camera farther back, the walk across the middle of the view.
    whole_view = (
        SCENE.replace("position_m: [0, -5, 3]", "position_m: [0, -9, 2.5]")
        .replace("pitch_deg: -20", "pitch_deg: -8")
        .replace("waypoints_m: [[-3, 5], [3, 5]]", "waypoints_m: [[-1, 5], [1, 5]]")
    )
    directory = render(workspace, scene_text=whole_view, annotations="mot, coco, reid")
    document = json.loads((directory / "coco.json").read_text())
    person = next(c for c in document["categories"] if c["name"] == "person")
    assert len(person["keypoints"]) == 17 and len(person["skeleton"]) == 19
    track = next(t for t in document["tracks"] if t["name"] == "walker")
    assert {"female", "upper_colour", "lower", "backpack"} <= set(track["attributes"])
    annotations = [a for a in document["annotations"] if a["category_id"] == person["id"]]
    assert annotations and all(len(a["keypoints"]) == 51 for a in annotations)
    whole = [a for a in annotations if a["truncation"] == 0 and a["visibility"] == 1]
    assert whole
    for a in whole:
        np.testing.assert_allclose(a["amodal_bbox"], a["bbox"], atol=1.0)
        keypoints = np.array(a["keypoints"]).reshape(17, 3)
        x, y, w, h = a["bbox"]
        shown = keypoints[keypoints[:, 2] == 2]
        assert len(shown) >= 8 and a["num_keypoints"] == np.count_nonzero(keypoints[:, 2])
        assert np.all((shown[:, 0] >= x) & (shown[:, 0] <= x + w) & (shown[:, 1] >= y) & (shown[:, 1] <= y + h))
    # Seen from its right side (walking along +x, the camera at −y), a person's far-side (left) shoulder
    # and hip are hidden by its own trunk (COCO's v = 1), the near-side ones visible (v = 2).
    names = person["keypoints"]
    for a in whole:
        v = np.array(a["keypoints"]).reshape(17, 3)[:, 2]
        assert v[names.index("right_shoulder")] == 2 and v[names.index("right_hip")] == 2
        assert v[names.index("left_shoulder")] == 1 or v[names.index("left_hip")] == 1
    coco = COCO(str(directory / "coco.json"))
    results = [{**a, "score": 1.0} for a in annotations if a["num_keypoints"] > 0]
    evaluation = COCOeval(coco, coco.loadRes(results), "keypoints")
    evaluation.params.catIds = [person["id"]]
    evaluation.evaluate()
    evaluation.accumulate()
    evaluation.summarize()
    assert evaluation.stats[0] == 1.0

    # The same keypoints beside MOT's gt.txt, frames counted from 1; re-ID crops named as Market-1501's.
    lines = [json.loads(line) for line in (directory / "gt" / "keypoints.jsonl").read_text().splitlines()]
    assert [line["frame"] for line in lines] == [image["id"] for image in document["images"]]
    first = next(a for a in annotations if a["image_id"] == 1)
    np.testing.assert_allclose(np.ravel(lines[0]["people"][0]["keypoints"]), first["keypoints"], atol=1e-3)
    crops = sorted(p.name for p in (directory / "reid").iterdir())
    assert crops == [f"{track['id']:04d}_c1s1_{frame:06d}_00.jpg" for frame in range(1, 7)]
    import cv2

    assert cv2.imread(str(directory / "reid" / crops[0])).shape == (128, 64, 3)
