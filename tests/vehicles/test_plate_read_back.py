"""Licence plates read back from the delivered frames by an OCR, against their annotations (issue 20).

Parked vehicles (cars, a van, a pickup, a motorcycle's two-line plate) seen by ANPR-like cameras (the
plate's characters 20–36 px high, front and rear plates, the camera up to 20° off the plate's axis and
8–15° above it) are rendered through the whole camera model (`camgen.plan.execute`: lens, sensor noise,
ISP, the 8-bit PNG a user gets) with their COCO annotations.

- The text: each line of the annotated plate quad, rectified out of the frame with a margin, is read by
  PP-OCRv4's recogniser (RapidOCR's ONNX models, inside the `rapidocr-onnxruntime` wheel: `make
  setup`), and the read equals the annotated text character for character, as an ANPR syntax check
  writes it (`plate_syntax`: capitals, plate characters only, spaces not compared, and where the UK format
  fixes a digit or a letter, the O/0 pair PP-OCR confuses on this font resolved by position; every other
  character must be read as annotated).
- The box: PP-OCR's text detector, run on the frame around the plate (not rectified), finds the text
  inside the annotated plate box, centred on where the plate's own image puts its characters once mapped
  through the annotated quad, and of about their size (intersection over union).

Without RapidOCR the OCR tests skip, saying so. `tests/vehicles/plate_read_bench.py` measures the
per-character accuracy over many plates, sizes, angles and at night.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import pytest

from camgen.config.profile import Profile
from camgen.config.scene import PLATE_CHARACTERS, Actor, Scene
from camgen.job import Job
from camgen.motion.trajectory import Route
from camgen.plan import PlanSettings, compile
from camgen.vehicles import vehicle_rig
from camgen.vehicles.plate import (
    CHARACTER_SIZE_MM,
    MOTORCYCLE_CHARACTER_SIZE_MM,
    MOTORCYCLE_LINE_GAP_MM,
    MOTORCYCLE_PLATE_SIZE_M,
    PLATE_SIZE_M,
    UK_PLATE_PATTERN,
    motorcycle_plate_image,
    plate_image,
)

SENSOR_SIZE_PX = (320, 240)
PIXEL_PITCH_UM = 3.0
VEHICLE_SPACING_M = 10.0
"""Between the parked vehicles (each camera frames its own one's plate; the others fall outside)."""
READ_HEIGHT_PX = 48
"""Height a rectified line of the plate is resampled to: PP-OCR's recogniser reads lines 48 px high."""


@dataclass(frozen=True)
class PlateView:
    """One camera looking at one plate of one parked vehicle (facing +y)."""

    body_type: str
    side: str
    """"front" or "rear"."""
    character_height_px: float
    """Image height of the plate's characters (79 mm) at the plate's centre, px (sets the focal length)."""
    yaw_deg: float
    """The camera's bearing from the plate's axis, counter-clockwise seen from above, degrees."""
    down_deg: float
    """How far the camera looks down at the plate, degrees."""
    distance_m: float


VIEWS = (
    PlateView("sedan", "rear", 20, 0, 10, 8.0),
    PlateView("hatchback", "rear", 28, 15, 12, 8.0),
    PlateView("suv", "front", 24, -12, 10, 9.0),
    PlateView("estate", "front", 36, 20, 15, 7.0),
    PlateView("van", "rear", 22, -18, 8, 12.0),
    PlateView("pickup", "front", 20, 8, 12, 15.0),
    PlateView("motorcycle", "rear", 24, 10, 12, 8.0),
)
"""ANPR-like views by day (issue 20: characters at least about 20 px high; a slight yaw), one per vehicle."""
NIGHT_VIEWS = (
    PlateView("hatchback", "rear", 24, 10, 10, 9.0),
    PlateView("suv", "front", 24, -12, 10, 9.0),
)
"""Views at 0.05 lx, the cameras in IR night mode: the plates as the near-infrared pass draws them
(`camgen.render.nir`)."""
CASES = [(False, view) for view in VIEWS] + [(True, view) for view in NIGHT_VIEWS]
"""(night, view) of each plate read."""


def _case_id(case: tuple[bool, PlateView]) -> str:
    night, view = case
    return f"{'night' if night else 'day'}-{view.body_type}-{view.side}-{view.character_height_px:g}px"


def _class_of(body_type: str) -> str:
    from camgen.config.scene import VEHICLE_BODY_TYPES

    return next(cls for cls, bodies in VEHICLE_BODY_TYPES.items() if body_type in bodies)


def plate_views_job(
    views: tuple[PlateView, ...] | list[PlateView], *, seed: int = 0, night: bool = False, supersampling: int = 2
) -> Job:
    """A job of one parked vehicle per view (identity seeds `seed`, `seed` + 1, …: each draws its own plate)
    and one camera per view, named ``c<index>``, framing that vehicle's plate as the view says. By day: sun
    and sky; `night`: 0.05 lx of ambient light and the cameras in IR night mode with their illuminators."""
    actors, cameras, profiles = [], [], {}
    for i, view in enumerate(views):
        actor = {
            "name": f"v{i}",
            "class": _class_of(view.body_type),
            "vehicle": {"body_type": view.body_type, "seed": seed + i},
            "path": {"waypoints_m": [[i * VEHICLE_SPACING_M, 0.0]], "heading_deg": 90},
        }
        actors.append(actor)
        parked = Route(np.array([[i * VEHICLE_SPACING_M, 0.0]]), np.zeros(1), 1.0, heading_rad=math.pi / 2)
        rig = vehicle_rig(Actor.model_validate(actor), parked, scene_seed=0, actor_index=i)
        corners = rig.plate_corners_world()[view.side]
        outward = np.cross(corners[3] - corners[0], corners[1] - corners[0])
        bearing = math.atan2(outward[1], outward[0]) + math.radians(view.yaw_deg)
        down = math.radians(view.down_deg)
        position = corners.mean(axis=0) + view.distance_m * np.array(
            [math.cos(bearing) * math.cos(down), math.sin(bearing) * math.cos(down), math.sin(down)]
        )
        name = f"c{i}"
        cameras.append(
            {
                "name": name,
                "profile": name,
                "mount": {
                    "position_m": position.tolist(),
                    "yaw_deg": math.degrees(bearing) + 180.0,
                    "pitch_deg": -view.down_deg,
                },
            }
            | ({"night_mode": True} if night else {})
        )
        focal_length_px = view.character_height_px * view.distance_m / (CHARACTER_SIZE_MM[1] / 1000)
        width_px, height_px = SENSOR_SIZE_PX
        profiles[name] = Profile.model_validate(
            {
                "sensor": {
                    "width_px": width_px,
                    "height_px": height_px,
                    "pixel_pitch_um": PIXEL_PITCH_UM,
                    "full_well_e": 10000,
                    "conversion_gain_dn_per_e": 0.4,
                },
                "lens": {"focal_length_mm": focal_length_px * PIXEL_PITCH_UM / 1000, "f_number": 2.0},
            }
            | ({"night_mode": {}} if night else {})  # the default IR-cut filter and illuminator
        )
    lights = (
        [{"type": "ambient", "illuminance_lux": 0.05}]
        if night
        else [
            {"type": "sun", "illuminance_lux": 50000, "azimuth_deg": 200, "elevation_deg": 40},
            {"type": "ambient", "illuminance_lux": 10000},
        ]
    )
    scene = Scene.model_validate(
        {
            "duration_s": 0.1,
            "fps": 10,
            "lights": lights,
            "environment": {
                "sky_luminance_cd_m2": 0.01 if night else 4000,
                "meshes": [
                    {
                        "type": "plane",
                        "name": "ground",
                        "size_m": [len(views) * VEHICLE_SPACING_M + 60, 80],
                        "position_m": [(len(views) - 1) * VEHICLE_SPACING_M / 2, 0, 0],
                        "material": {"color_rgb": [0.1] * 3},
                    }
                ],
            },
            "actors": actors,
            "cameras": cameras,
            "outputs": {"video": False, "frames": "png", "annotations": ["coco"], "camera_metadata": False},
        }
    )
    return compile(scene, profiles, settings=PlanSettings(supersampling=supersampling))


def delivered_plates(directory: Path) -> tuple[np.ndarray, list[dict]]:
    """The delivered frame 0 (H, W, 3) BGR uint8 of a camera's output folder and its visible plates'
    annotations."""
    frame = cv2.imread(str(directory / "frames" / "000000.png"))
    coco = json.loads((directory / "coco.json").read_text())
    plates = [p for a in coco["annotations"] for p in a.get("plates", []) if p["visible"]]
    return frame, plates


@dataclass(frozen=True)
class PlateLayout:
    """Where a plate's lines of text are, in mm on the plate (x right, y down from its top left corner)."""

    size_mm: tuple[float, float]
    lines_mm: tuple[tuple[float, float], ...]
    """Top and bottom of each line's characters."""
    character_height_mm: float

    @classmethod
    def of(cls, body_type: str) -> PlateLayout:
        """A car's, van's or bus's one-line plate, or a motorcycle's two-line rear plate
        (`camgen.vehicles.plate`)."""
        if body_type == "motorcycle":
            w, h = (1000 * m for m in MOTORCYCLE_PLATE_SIZE_M)
            ch, gap = MOTORCYCLE_CHARACTER_SIZE_MM[1], MOTORCYCLE_LINE_GAP_MM
            top = (h - 2 * ch - gap) / 2
            return cls((w, h), ((top, top + ch), (top + ch + gap, top + 2 * ch + gap)), ch)
        w, h = (1000 * m for m in PLATE_SIZE_M)
        ch = CHARACTER_SIZE_MM[1]
        return cls((w, h), (((h - ch) / 2, (h + ch) / 2),), ch)


def rectified_line(frame: np.ndarray, quad_px: list, layout: PlateLayout, line: int) -> np.ndarray:
    """One line of the plate under the annotated `quad_px` (COCO's pixel-edge coordinates) seen face on:
    the plate's width and the line's characters plus a margin of a fifth of their height above and below
    and at each end (what surrounds the plate, past its edges), resampled to `READ_HEIGHT_PX` for them."""
    w_mm, h_mm = layout.size_mm
    top_mm, bottom_mm = layout.lines_mm[line]
    margin_mm = 0.2 * layout.character_height_mm
    x0, y0, x1, y1 = -margin_mm, top_mm - margin_mm, w_mm + margin_mm, bottom_mm + margin_mm
    px_per_mm = READ_HEIGHT_PX / (y1 - y0)
    plate_mm = np.float32([[0, 0], [w_mm, 0], [w_mm, h_mm], [0, h_mm]])
    target = (plate_mm - [x0, y0]) * px_per_mm - 0.5
    M = cv2.getPerspectiveTransform(np.float32(quad_px) - 0.5, np.float32(target))
    size = (round((x1 - x0) * px_per_mm), READ_HEIGHT_PX)
    return cv2.warpPerspective(frame, M, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


UK_DIGIT_POSITIONS = (2, 3)
"""Where the UK format ("AB12CDE" without its space) has digits; letters everywhere else."""


def plate_syntax(read: str) -> str:
    """An OCR's read of a UK plate as an ANPR syntax check writes it: in capitals (a plate carries no
    lower case; PP-OCR reads a C or K as c or k now and then, whose shapes differ only in size), only the
    characters a plate can carry (the recogniser reads PP-OCR's whole dictionary, and the plate's dark rim
    in the margin can read as a bracket), and a read of the UK format's length takes an O for a 0 in its
    digit positions and a 0 for an O in its letter positions (PP-OCR reads this plate font's plain O as 0
    next to digits, at any size; the font's 0 is slashed, see `camgen.vehicles.plate`). Any other
    character stays as read."""
    read = "".join(c for c in read.upper() if c in PLATE_CHARACTERS)
    if len(read) != 7:
        return read
    return "".join(
        ("0" if c == "O" else c) if i in UK_DIGIT_POSITIONS else ("O" if c == "0" else c) for i, c in enumerate(read)
    )


def text_box_px(plate: dict, body_type: str, side: str) -> np.ndarray:
    """[x0, y0, x1, y1] (pixel edges) of where the plate's characters are in the frame: the bounding box of
    the ink of the plate's own image (`camgen.vehicles.plate`) mapped through the annotated quad."""
    if body_type == "motorcycle":
        image = motorcycle_plate_image(plate["text"])
    else:
        image = plate_image(plate["text"], rear=side == "rear")
    luminance = image.sum(axis=-1)
    rows, cols = np.nonzero(luminance < 0.5 * luminance.max())
    h, w = image.shape[:2]
    M = cv2.getPerspectiveTransform(np.float32([[0, 0], [w, 0], [w, h], [0, h]]), np.float32(plate["quad"]))
    x0, y0, x1, y1 = cols.min(), rows.min(), cols.max() + 1, rows.max() + 1
    ink = np.float32([[[x0, y0], [x1, y0], [x1, y1], [x0, y1]]])
    mapped = cv2.perspectiveTransform(ink, M)[0]
    return np.concatenate([mapped.min(axis=0), mapped.max(axis=0)])


def detected_text_box_px(reader, frame: np.ndarray, plate: dict) -> np.ndarray | None:
    """[x0, y0, x1, y1] (pixel edges) around every text PP-OCR's detector finds in a neighbourhood of the
    annotated box (the box grown by its width sideways and by twice its height up and down), or None."""
    x, y, w, h = plate["bbox"]
    H, W = frame.shape[:2]
    x0, y0 = max(0, math.floor(x - w)), max(0, math.floor(y - 2 * h))
    x1, y1 = min(W, math.ceil(x + 2 * w)), min(H, math.ceil(y + 3 * h))
    found, _ = reader(frame[y0:y1, x0:x1], use_cls=False)
    if not found:
        return None
    corners = np.concatenate([np.float32(box) for box, _, _ in found]) + np.float32([x0, y0])
    # The detector's quads are in pixel-centre coordinates of the crop; COCO's edges are half a pixel on.
    return np.concatenate([corners.min(axis=0), corners.max(axis=0)]) + 0.5


def read_plate(reader, frame: np.ndarray, plate: dict, body_type: str) -> str:
    """PP-OCR's recogniser's read of each line of the annotated plate, rectified, joined by spaces."""
    layout = PlateLayout.of(body_type)
    reads = []
    for line in range(len(layout.lines_mm)):
        read, _ = reader(rectified_line(frame, plate["quad"], layout, line), use_det=False, use_cls=False)
        reads.append(read[0][0] if read else "")
    return " ".join(reads)


def iou(a: np.ndarray, b: np.ndarray) -> float:
    w = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    h = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - w * h
    return float(w * h / union)


@pytest.fixture(scope="module")
def reader():
    """RapidOCR's PP-OCRv4 detector and recogniser, or a skip saying how to install them."""
    ocr = pytest.importorskip(
        "rapidocr_onnxruntime",
        reason="RapidOCR (PP-OCR's ONNX models run by onnxruntime, with pyclipper and shapely) is not installed: "
        "`make setup` installs it (on Python < 3.13, which RapidOCR 1.4.4 requires)",
    )
    return ocr.RapidOCR()


@pytest.fixture(scope="module")
def delivered(reader, renderer, tmp_path_factory):
    """(night, view) → (delivered frame, its one visible plate's annotation), rendered through the camera
    model."""
    from camgen.plan.execute import execute

    root = tmp_path_factory.mktemp("plates")
    out = {}
    for night, views, seed in ((False, VIEWS, 40), (True, NIGHT_VIEWS, 60)):
        results = execute(plate_views_job(views, seed=seed, night=night), root / str(night), renderer=renderer)
        for view, result in zip(views, results, strict=True):
            frame, plates = delivered_plates(result.directory)
            (plate,) = [p for p in plates if p["side"] == view.side]  # the camera's own vehicle's plate
            out[night, view] = frame, plate
    return out


@pytest.mark.parametrize("case", CASES, ids=_case_id)
@pytest.mark.opengl
def test_the_ocr_reads_the_annotated_text_in_the_annotated_quad(reader, delivered, case):
    _, view = case
    frame, plate = delivered[case]
    assert UK_PLATE_PATTERN.match(plate["text"])
    read = read_plate(reader, frame, plate, view.body_type)
    assert plate_syntax(read) == plate["text"].replace(" ", ""), (read, plate["text"])


@pytest.mark.parametrize("case", CASES, ids=_case_id)
@pytest.mark.opengl
def test_the_ocr_finds_the_text_where_the_annotated_box_puts_it(reader, delivered, case):
    _, view = case
    frame, plate = delivered[case]
    found = detected_text_box_px(reader, frame, plate)
    assert found is not None, "no text found around the annotated plate"
    x, y, w, h = plate["bbox"]
    box = np.array([x, y, x + w, y + h])
    # The detector's box, grown by its unclip ratio past the ink, stays inside the plate's box (within 1 px)…
    assert np.all(found[:2] >= box[:2] - 1) and np.all(found[2:] <= box[2:] + 1), (found, box)
    # …and is the box of the plate's characters where the annotated quad puts them: centred on it within a
    # tenth of its height (a quad 1/16 of the plate's width or 1/8 of its height off fails), and of its size
    # (the detector's box is grown past the ink by its unclip ratio: IoU 0.81–0.93 here).
    expected = text_box_px(plate, view.body_type, view.side)
    offset_px = (found[:2] + found[2:]) / 2 - (expected[:2] + expected[2:]) / 2
    assert np.all(np.abs(offset_px) <= 0.1 * (expected[3] - expected[1])), (found, expected)
    assert iou(found, expected) > 0.75, (found, expected)


def test_the_syntax_check_reads_capitals_and_resolves_only_o_and_zero_by_position():
    assert plate_syntax("M074 TR0") == "MO74TRO"
    assert plate_syntax("0S68 NKH") == "OS68NKH"
    assert plate_syntax("AB12 CD8") == "AB12CD8"  # a B read as 8 stays wrong
    assert plate_syntax("AB1 CDE") == "AB1CDE"  # a read of another length is not touched
    assert plate_syntax("[AU52 MVH|") == "AU52MVH"
    assert plate_syntax("Lc09 0Mk") == "LC09OMK"
