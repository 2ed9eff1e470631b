"""Ground-area coverage of a camera network over time, from the views a simulation delivers.

Each frame, every delivered camera's view (its state's `K_px`, `distortion` and `T_world_from_cam` at
the delivered size) covers the site's ground cells it sees unhidden at a DORI class (IEC 62676-4:2014,
`camgen.coverage.dori`) at least `min_class`, judged on a standing person as `camgen coverage` judges
it (`camgen.coverage.network.camera_coverage`). The network's coverage of a frame is the area of
cells some camera covers; a PTZ head that turns moves its share. Densities are those of the delivered
frames: a simulation read out at a reduced `resolution_px` has proportionally fewer px/m.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from camgen.config.loader import LoadedScene
from camgen.coverage.dori import class_index
from camgen.coverage.grid import make_grid, site_extent_m
from camgen.coverage.network import camera_coverage
from camgen.coverage.occlusion import inside_solids, on_ground, scene_occluders
from camgen.coverage.views import CameraView
from camgen.sim.simulation import Observations

CELL_M = 1.0
"""Ground cell size, m (`camgen coverage` defaults to finer cells; a frame here costs one pass per camera)."""


def delivered_view(name: str, observation) -> CameraView:
    """A camera's view as it delivered `observation`: a virtual PTZ as its stream (the window's camera
    matrix with the lens's distortion, px/m up to the sensor's own detail, as `camgen.coverage.views.
    eptz_view`)."""
    state = observation.state
    height_px, width_px = observation.rgb8.shape[:2]
    eptz = state.output_K_px is not None
    K = np.array(state.output_K_px if eptz else state.K_px, dtype=np.float64)
    return CameraView(
        name=name,
        K_px=K,
        distortion=np.array(state.distortion, dtype=np.float64),
        T_world_from_cam=np.array(state.T_world_from_cam, dtype=np.float64),
        width_px=width_px,
        height_px=height_px,
        focal_length_mm=state.focal_length_mm,
        detail_scale=min(1.0, state.window_px[2] / width_px) if eptz else 1.0,
    )


@dataclass
class GroundCoverage:
    """Feed it each frame's observations (`add`); it keeps the area covered per frame and over all."""

    loaded: LoadedScene
    cell_m: float = CELL_M
    min_class: str = "detect"
    per_frame_m2: list[float] = field(default_factory=list)
    """Area some camera covered, per frame added, m²."""

    def __post_init__(self) -> None:
        scene = self.loaded.scene
        self.grid = make_grid(site_extent_m(scene, self.loaded.file_bounds), self.cell_m, 0.0)
        self.occluders = tuple(scene_occluders(scene))
        points = self.grid.points_m()
        ground = on_ground(points, self.occluders)
        self.site = (~inside_solids(points, self.occluders) & (True if ground is None else ground)).reshape(
            self.grid.shape
        )
        self.threshold = class_index(self.min_class)
        self.ever = np.zeros(self.grid.shape, bool)

    @property
    def site_m2(self) -> float:
        return float(self.site.sum()) * self.grid.cell_area_m2

    @property
    def union_m2(self) -> float:
        """Area covered at some frame by some camera, m²."""
        return float(self.ever.sum()) * self.grid.cell_area_m2

    def covered(self, observations: Observations) -> np.ndarray:
        """(ny, nx) bool: the site cells some camera covers at this frame."""
        mask = np.zeros(self.grid.shape, bool)
        for name, observation in observations.cameras.items():
            coverage = camera_coverage(self.grid, delivered_view(name, observation), self.occluders)
            mask |= coverage.dori >= self.threshold
        return mask & self.site

    def add(self, observations: Observations) -> float:
        """Record one frame; returns its covered area, m²."""
        mask = self.covered(observations)
        self.ever |= mask
        area = float(mask.sum()) * self.grid.cell_area_m2
        self.per_frame_m2.append(area)
        return area
