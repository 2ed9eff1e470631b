"""One camera's preview: its frames with the annotations drawn on them, written as a WebM video, a contact
sheet PNG and, when asked, one self-contained HTML page.

Files (in the chosen directory, named ``<job>-<camera>``)::

    <job>-<camera>.webm          every frame annotated (VP9, `camgen.io.video.webm_vp9_writer`)
    <job>-<camera>.contact.png   up to CONTACT_SHEET_TILES frames spread evenly over the sequence
    <job>-<camera>.html          the page (`camgen.preview.page`), the video embedded in it

Each appears under its name only when complete. Frames wider than `max_width_px` are scaled down before
drawing, so lines and text stay sharp. Track tails are the ground truth: each object's ground point
(the centre of its 3-D box's base) over the last `TAIL_S` seconds, projected through the current frame's
camera (camera.jsonl), so a tail stays on the ground while a PTZ camera moves; without camera states or
3-D boxes, the box's bottom centre in the image.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from pycocotools import mask as mask_utils

from camgen.errors import ConfigError
from camgen.io.files import write_text_atomic
from camgen.io.frames import write_frame
from camgen.io.video import webm_vp9_writer
from camgen.optics.projection import project_points
from camgen.preview.draw import DrawnObject, annotate_frame, camera_state_lines, contact_sheet
from camgen.preview.page import preview_page
from camgen.preview.source import RenderedSequence, read_card

MAX_WIDTH_PX = 1280
"""Default width limit of the preview, px."""
TAIL_S = 2.0
"""Length of a track's tail, s of its past."""
CONTACT_SHEET_TILES = 12
"""Most frames on the contact sheet (`camgen.preview.draw.contact_sheet` lays them out 4 to a row)."""


@dataclass(frozen=True)
class PreviewFiles:
    video: Path
    contact_sheet: Path
    html: Path | None
    frames: int


def preview_stem(sequence: RenderedSequence) -> str:
    return f"{sequence.output.job_directory.name}-{sequence.output.name}"


def write_preview(
    sequence: RenderedSequence,
    directory: Path,
    *,
    html: bool = False,
    max_width_px: int = MAX_WIDTH_PX,
    on_frame: Callable[[], None] | None = None,
) -> PreviewFiles:
    """Draw every frame of `sequence` and write the preview's files into `directory` (see the module)."""
    stem = preview_stem(sequence)
    width_px, height_px = _preview_size(sequence.width_px, sequence.height_px, max_width_px)
    scale_xy = (width_px / sequence.width_px, height_px / sequence.height_px)
    count = len(sequence.frame_indices)
    sheet_positions = set(np.unique(np.round(np.linspace(0, count - 1, min(count, CONTACT_SHEET_TILES))).astype(int)))
    tail_frames = max(2, round(TAIL_S * sequence.fps))
    history: dict[int, deque] = {}
    tiles, captions = [], []
    video_path = directory / f"{stem}.webm"
    written = 0
    with webm_vp9_writer(video_path, width_px=width_px, height_px=height_px, fps=sequence.fps) as write:
        for position, (frame_index, image) in enumerate(
            zip(sequence.frame_indices, sequence.frames_rgb8(), strict=False)
        ):
            if image.shape[:2] != (sequence.height_px, sequence.width_px):
                raise ConfigError(
                    f"{sequence.output.directory}: frame {frame_index} is {image.shape[1]}×{image.shape[0]} px, "
                    f"but coco.json says {sequence.width_px}×{sequence.height_px}; render it again"
                )
            if (width_px, height_px) != (sequence.width_px, sequence.height_px):
                image = cv2.resize(image, (width_px, height_px), interpolation=cv2.INTER_AREA)
            annotations = sequence.annotations.get(frame_index, [])
            state = sequence.states.get(frame_index, {})
            for annotation in annotations:
                track = history.setdefault(int(annotation["track_id"]), deque())
                track.append((frame_index, *_ground_point(annotation)))
            tails = _tails_px(history, frame_index - tail_frames, state, scale_xy)
            objects = [_drawn(annotation, sequence, scale_xy, (height_px, width_px)) for annotation in annotations]
            annotated = annotate_frame(image, objects, tails_px=tails, panel_lines=camera_state_lines(state))
            write(annotated)
            written += 1
            if position in sheet_positions:
                tiles.append(annotated)
                time = state.get("time_s", frame_index / sequence.fps)
                captions.append(f"frame {frame_index}  {time:.2f} s")
            if on_frame is not None:
                on_frame()
        if written == 0:
            raise ConfigError(f"{sequence.output.directory}: its video holds no frames; render it again")
    sheet_path = directory / f"{stem}.contact.png"
    write_frame(sheet_path, contact_sheet(tiles, captions), format="png")
    html_path = None
    if html:
        html_path = directory / f"{stem}.html"
        card = read_card(sequence.output)
        page = preview_page(
            title=f"{sequence.output.job_directory.name} / {sequence.output.name}",
            facts=_facts(sequence, written),
            video_webm=video_path.read_bytes(),
            states=[sequence.states[k] for k in sequence.frame_indices if k in sequence.states],
            card_markdown=card,
            card_directory=None if sequence.output.card_path is None else sequence.output.card_path.parent,
        )
        write_text_atomic(html_path, page)
    return PreviewFiles(video=video_path, contact_sheet=sheet_path, html=html_path, frames=written)


def _preview_size(width_px: int, height_px: int, max_width_px: int) -> tuple[int, int]:
    """The drawn frame size: at most `max_width_px` wide, the aspect kept, both even (VP9's 4:2:0)."""
    scale = min(1.0, max_width_px / width_px)
    return max(2, round(width_px * scale) // 2 * 2), max(2, round(height_px * scale) // 2 * 2)


def _ground_point(annotation: dict) -> tuple[np.ndarray | None, np.ndarray]:
    """The object's ground point: the base centre of its 3-D box, m (None without one), and the bottom
    centre of its box, px."""
    box = annotation.get("bbox_3d_world_m")
    world = np.mean(np.asarray(box, dtype=np.float64)[:4], axis=0) if box is not None and len(box) == 8 else None
    x, y, w, h = annotation["bbox"]
    return world, np.array([x + (w - 1) / 2, y + h - 1], dtype=np.float64)


def _tails_px(history: dict[int, deque], oldest_frame: int, state: dict, scale_xy) -> dict[int, np.ndarray]:
    """Each track's points after `oldest_frame` in the drawn frame's pixels (older ones are dropped):
    projected through the frame's camera where the state and every 3-D point are there, else the boxes'
    bottom centres."""
    camera = all(key in state for key in ("K_px", "distortion", "T_world_from_cam"))
    tails = {}
    for track_id, points in history.items():
        while points and points[0][0] <= oldest_frame:
            points.popleft()
        if len(points) < 2:
            continue
        if camera and all(world is not None for _, world, _ in points):
            xy, _ = project_points(
                np.array([world for _, world, _ in points]),
                np.asarray(state["T_world_from_cam"]),
                np.asarray(state["K_px"]),
                state["distortion"],
            )
        else:
            xy = np.array([image for _, _, image in points])
        tails[track_id] = xy * np.asarray(scale_xy)
    return tails


def _drawn(annotation: dict, sequence: RenderedSequence, scale_xy, size_hw: tuple[int, int]) -> DrawnObject:
    sx, sy = scale_xy
    x, y, w, h = annotation["bbox"]
    category = sequence.categories.get(annotation.get("category_id"), {})
    label = f"{annotation['track_id']} {category.get('name', '?')}"
    visibility = annotation.get("visibility")
    if isinstance(visibility, int | float) and round(100 * visibility) < 100:
        label += f" {100 * visibility:.0f}% visible"
    mask = None
    segmentation = annotation.get("segmentation")
    if isinstance(segmentation, dict) and "counts" in segmentation:
        mask = mask_utils.decode(segmentation)
        if mask.shape != size_hw:
            mask = cv2.resize(mask, (size_hw[1], size_hw[0]), interpolation=cv2.INTER_NEAREST)
        mask = mask.astype(bool)
    keypoints = annotation.get("keypoints")
    if keypoints:
        points = np.asarray(keypoints, dtype=np.float64).reshape(-1, 3) * (sx, sy, 1)
        keypoints = tuple(points.ravel())
    return DrawnObject(
        track_id=int(annotation["track_id"]),
        label=label,
        bbox_xywh=(x * sx, y * sy, w * sx, h * sy),
        mask=mask,
        keypoints=keypoints or None,
        skeleton=tuple(tuple(pair) for pair in category.get("skeleton", ())),
    )


def _facts(sequence: RenderedSequence, frames: int) -> list[tuple[str, str]]:
    classes: dict[str, int] = {}
    for track in sequence.tracks.values():
        name = sequence.categories.get(track.get("category_id"), {}).get("name", "?")
        classes[name] = classes.get(name, 0) + 1
    return [
        ("directory", str(sequence.output.directory)),
        ("frames", f"{frames} at {sequence.fps:g} fps, {sequence.width_px}×{sequence.height_px} px"),
        ("tracks", ", ".join(f"{n} {name}" for name, n in sorted(classes.items())) or "none"),
        ("video", "embedded in this page (WebM VP9, base64); also written beside it as .webm"),
    ]
