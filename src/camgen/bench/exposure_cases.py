"""Exposure of the example cameras (issue 20: "exposure of the examples checked so that no example camera films
a silhouette by accident"). Frame 0 of every camera of every example scene is delivered through the full camera
model with its auto-exposure converged on the view (`camgen.sim`, which meters frame 0 as a camera that has
watched the view for a while; read out binned to at most `READOUT_WIDTH_PX` wide), with its ground truth. Each
person and vehicle at least `MIN_HEIGHT_PX` tall and `MIN_VISIBILITY` visible is measured by the median luma (BT.601
Y′ of the delivered 8-bit frame) of the middle of its box (`core_box`: half its width, the middle 60 % of its
height) and of its surroundings (`ring_boxes`: the box grown by half its size on each side, less the box itself:
the ground or wall it stands against), and so is the frame.

A silhouette (`is_silhouette`): an object whose surroundings' median luma is under `SILHOUETTE_LUMA` while the
frame's 90th percentile is over `BRIGHT_LUMA`: the exposure set by a bright sky or facade, the street where the
object stands left dark. An object's own luma is reported but not judged: a person in dark clothes on a well
exposed pavement is dark by nature (a navy coat reflects ~5 %), not a silhouette. Night scenes are dark all over and
are not silhouettes by this test."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from camgen.bench.harness import Case
from camgen.world.night import luma_bt601

READOUT_WIDTH_PX = 640
MIN_HEIGHT_PX = 24
"""At the readout size: about 96 px at 2560 wide, the realism sections' smallest counted person at full size."""
MIN_VISIBILITY = 0.7
SILHOUETTE_LUMA = 40.0
"""Y′ code value (of 255) under which an object reads as a silhouette: about 2 % of the white level in linear
light through a 2.2 gamma, where a face or a number plate shows no detail."""
BRIGHT_LUMA = 200.0
"""Y′ code value over which the frame's 90th percentile counts as a bright background (a sky, a lit facade)."""
CLIPPED_LUMA = 250
CRUSHED_LUMA = 5


@dataclass
class CameraExposure:
    scene: str
    camera: str
    condition: str
    exposure_time_s: float
    gain_db: float
    night_mode: bool
    frame_median_luma: float
    frame_p90_luma: float
    clipped_frac: float
    crushed_frac: float
    objects: list[tuple[str, str, float, float]] = field(default_factory=list)
    """(name, class, median luma of its middle, median luma of its surroundings) of each counted person or
    vehicle."""

    @property
    def silhouettes(self) -> list[str]:
        return [name for name, _, _, around in self.objects if is_silhouette(around, self.frame_p90_luma)]


def core_box(box: tuple[float, float, float, float]) -> tuple[int, int, int, int]:
    """The middle of a box (x0, y0, x1, y1; pixel edges): half its width and the middle 60 % of its height."""
    x0, y0, x1, y1 = box
    w, h = x1 - x0, y1 - y0
    return (
        math.floor(x0 + 0.25 * w),
        math.floor(y0 + 0.2 * h),
        math.ceil(x1 - 0.25 * w),
        math.ceil(y1 - 0.2 * h),
    )


def ring_boxes(
    box: tuple[float, float, float, float], width_px: int, height_px: int
) -> list[tuple[int, int, int, int]]:
    """The surroundings of a box (x0, y0, x1, y1; pixel edges) in a `width_px` × `height_px` frame: the box grown by
    half its width and height on each side, clipped to the frame, less the box, as up to four rectangles (above,
    below, left, right)."""
    x0, y0, x1, y1 = (round(v) for v in box)
    dx, dy = max(1, (x1 - x0) // 2), max(1, (y1 - y0) // 2)
    X0, Y0, X1, Y1 = max(0, x0 - dx), max(0, y0 - dy), min(width_px, x1 + dx), min(height_px, y1 + dy)
    parts = [(X0, Y0, X1, y0), (X0, y1, X1, Y1), (X0, y0, x0, y1), (x1, y0, X1, y1)]
    return [(a, b, c, d) for a, b, c, d in parts if c > a and d > b]


def is_silhouette(surroundings_luma: float, frame_p90_luma: float) -> bool:
    return surroundings_luma < SILHOUETTE_LUMA and frame_p90_luma > BRIGHT_LUMA


def readout_px(width_px: int, height_px: int, stream_width_px: int | None = None) -> tuple[int, int]:
    """The binned readout of a sensor: its size over the least whole factor that brings it to READOUT_WIDTH_PX
    wide or less (even sizes), but no less wide than a virtual PTZ's stream (`stream_width_px`), which is a crop of
    the readout."""
    factor = max(1, math.ceil(width_px / READOUT_WIDTH_PX))
    if stream_width_px is not None:
        factor = max(1, min(factor, width_px // stream_width_px))
    return 2 * round(width_px / factor / 2), 2 * round(height_px / factor / 2)


def camera_exposures(repo: Path) -> list[CameraExposure]:
    """Every example camera's frame 0, measured (module docstring)."""
    from camgen.bench.realism import scene_condition
    from camgen.bench.render_cases import _renderer
    from camgen.config import load_scene
    from camgen.sim import Simulation

    rows = []
    renderer = _renderer()
    for path in sorted((repo / "scenes").glob("*.yaml")):
        loaded = load_scene(path)
        condition = scene_condition(loaded.scene)
        for camera in loaded.scene.cameras:
            sensor = loaded.profiles[camera.name].profile.sensor
            stream = camera.eptz.output_size_px[0] if camera.eptz is not None else None
            size = readout_px(sensor.width_px, sensor.height_px, stream)
            with Simulation(
                loaded, ground_truth=True, resolution_px=size, renderer=renderer, cameras=[camera.name]
            ) as sim:
                delivered = sim.reset(0).cameras[camera.name]
            y = luma_bt601(delivered.rgb8)
            row = CameraExposure(
                path.stem,
                camera.name,
                condition,
                delivered.state.exposure_time_s,
                delivered.state.gain_db,
                bool(delivered.state.night_mode),
                float(np.median(y)),
                float(np.percentile(y, 90)),
                float(np.mean(y >= CLIPPED_LUMA)),
                float(np.mean(y <= CRUSHED_LUMA)),
            )
            for obj in delivered.ground_truth.objects:
                box = obj.visible_box
                if box is None or obj.visibility < MIN_VISIBILITY or box[3] - box[1] < MIN_HEIGHT_PX:
                    continue
                x0, y0, x1, y1 = core_box(box)
                core = y[max(0, y0) : y1, max(0, x0) : x1]
                ring = np.concatenate([y[b:d, a:c].ravel() for a, b, c, d in ring_boxes(box, *y.shape[::-1])])
                if core.size and ring.size:
                    row.objects.append((obj.name, obj.cls, float(np.median(core)), float(np.median(ring))))
            rows.append(row)
    return rows


def exposure_cases(repo: Path, rows: list[CameraExposure]) -> list[Case]:
    """One case that measures every example camera once (its time is the whole check's) into `rows`."""

    def run() -> None:
        rows[:] = camera_exposures(repo)

    return [Case("exposure of every example camera, frame 0", run, repeats=1, warmup=0)]


def exposure_table(rows: list[CameraExposure]) -> str:
    lines = [
        "| scene | camera | condition | exposure | median Y′ | p90 Y′ | clipped | crushed | people and vehicles: "
        "median Y′ of each (of its surroundings) | silhouettes |",
        "|---|---|---|---:|---:|---:|---:|---:|---|---|",
    ]
    for r in rows:
        own = sorted(luma for _, _, luma, _ in r.objects)
        around = sorted(luma for _, _, _, luma in r.objects)
        objects = (
            f"{len(own)}: {own[0]:.0f}–{own[-1]:.0f} ({around[0]:.0f}–{around[-1]:.0f})" if own else "none counted"
        )
        mode = " (IR)" if r.night_mode else ""
        lines.append(
            f"| {r.scene} | {r.camera} | {r.condition}{mode} | {r.exposure_time_s * 1e3:.2f} ms, "
            f"{r.gain_db:.1f} dB | {r.frame_median_luma:.0f} | {r.frame_p90_luma:.0f} | {r.clipped_frac:.1%} | "
            f"{r.crushed_frac:.1%} | {objects} | {', '.join(r.silhouettes) or '—'} |"
        )
    return "\n".join(lines)
