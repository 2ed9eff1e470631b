"""Run a camera's planned lens stages on its rendered passes (`camgen.optics` wired as the plan says).

Order, and why it differs from the list in DESIGN.md:

1. motion blur — integrated while rendering (sub-frames within the exposure, `camgen.render.sequence`);
2. depth of field, axial CA, diffraction — on the margin-rendered *pinhole* image, before the remap.
   The margin already holds the pixels a blur at the frame border reads; depth is exact there (no
   resampling of depth before it is used); and the image is resampled once, at the end.
3. distortion + lateral CA — one remap into the output frame; depth and ids by nearest pixel;
4. vignetting — a gain per output pixel (it depends on the output position and the chief ray).

Blurring before distorting treats a blur spot as a disc in the pinhole image, which the distortion
then squeezes as it squeezes the scene; for the coefficients surveillance lenses have, the spot's
shape changes by g'(r) ≈ 1 ± 0.2 at the corner, and its size on axis is exact.
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from camgen.job import CameraJob, CameraState
from camgen.optics.depth_of_field import disc_kernel, layered_blur, signed_coc_px
from camgen.optics.diffraction import diffraction_blur
from camgen.optics.intrinsics import corner_radius_normalized
from camgen.optics.remap import LensGeometry, LensMapCache, LensMaps, output_grid_px, remap_image, remap_nearest
from camgen.optics.vignetting import aperture_weight, relative_illumination
from camgen.render.renderer import Passes
from camgen.render.sequence import crop_to_output


class LensStages:
    """The optics stages of one camera; keeps its lens maps and vignetting gain between frames."""

    def __init__(self, camera: CameraJob, cache: LensMapCache | None = None):
        self.camera = camera
        self.stages = {stage.name: stage for stage in camera.stages}
        self.cache = cache or LensMapCache()
        self._gain_key = None
        self._gain = None
        profile = camera.profile
        self.mono = profile.sensor.cfa == "mono"
        ca = profile.lens.chromatic_aberration
        lateral = "optics.remap" in self.stages and self.stages["optics.remap"].params["lateral_ca"]
        self.ca_scales = (ca.lateral_scale_r, 1.0, ca.lateral_scale_b) if lateral and not self.mono else (1.0,)

    def geometry(self, state: CameraState) -> LensGeometry:
        spec = self.camera.render
        return LensGeometry(
            K_px=state.K_px,
            distortion=state.distortion,
            ca_scales=self.ca_scales,
            width_px=self.camera.width_px,
            height_px=self.camera.height_px,
            margin_px=spec.margin_px,
        )

    def blur(self, state: CameraState, passes: Passes) -> np.ndarray | None:
        """The planned blurs (depth of field, axial CA, diffraction) of the render-size radiance."""
        stages, profile = self.stages, self.camera.profile
        pitch_um = profile.sensor.pixel_pitch_um
        radiance = passes.radiance
        if radiance is None:
            return None
        if "optics.depth_of_field" in stages:
            params = stages["optics.depth_of_field"].params
            coc = signed_coc_px(
                passes.depth_m,
                focal_length_mm=state.focal_length_mm,
                f_number=state.f_number,
                focus_distance_m=state.focus_distance_m,
                pixel_pitch_um=pitch_um,
            )
            radiance = layered_blur(radiance, coc, step_px=params["step_px"], step_rel=params["step_rel"])
        if "optics.axial_ca" in stages:
            radiance = radiance.copy()
            for channel, shift_um in enumerate(stages["optics.axial_ca"].params["focus_shift_um"]):
                diameter_px = abs(shift_um) / state.f_number / pitch_um
                if diameter_px > 0:
                    radiance[..., channel] = cv2.filter2D(
                        np.ascontiguousarray(radiance[..., channel]),
                        -1,
                        disc_kernel(diameter_px),
                        borderType=cv2.BORDER_REFLECT,
                    )
        if "optics.diffraction" in stages:
            radiance = diffraction_blur(radiance, f_number=state.f_number, pixel_pitch_um=pitch_um, mono=self.mono)
        return radiance

    def maps(self, state: CameraState) -> LensMaps | None:
        """The lens maps of this state, or None when no lens stage resamples."""
        return self.cache.get(self.geometry(state)) if "optics.remap" in self.stages else None

    def apply(self, state: CameraState, passes: Passes) -> Passes:
        """Render-size passes (output plus margin) → output-size passes through the lens."""
        stages = self.stages
        radiance = self.blur(state, passes)
        out = Passes()
        if "optics.remap" in stages:
            maps = self.cache.get(self.geometry(state))
            undistorted = maps.undistorted_normalized
            if radiance is not None:
                out.radiance = remap_image(radiance, maps, stages["optics.remap"].params["interpolation"])
            if passes.depth_m is not None:
                out.depth_m = remap_nearest(passes.depth_m, maps)
            if passes.instance_id is not None:
                out.instance_id = remap_nearest(passes.instance_id, maps)
        else:
            undistorted = None
            spec = self.camera.render
            out.radiance = None if radiance is None else crop_to_output(radiance, spec)
            out.depth_m = None if passes.depth_m is None else crop_to_output(passes.depth_m, spec)
            out.instance_id = None if passes.instance_id is None else crop_to_output(passes.instance_id, spec)
        if "optics.vignetting" in stages and out.radiance is not None:
            out.radiance = out.radiance * self.vignetting_gain(state, undistorted)[..., None]
        return out

    def source_pixels(self, state: CameraState, window_px: tuple[int, int, int, int]) -> tuple[np.ndarray, np.ndarray]:
        """Rows and columns (each (y1 − y0, x1 − x0) int) of the render pixel that each output pixel of
        `window_px` (x0, y0, x1, y1; x1, y1 exclusive) takes its depth and id from: `apply`'s nearest pixel
        through the lens, or without a lens stage the same pixel shifted by the render's margin."""
        x0, y0, x1, y1 = window_px
        if "optics.remap" in self.stages:
            rows, cols = self.cache.get(self.geometry(state)).nearest_index
            return rows[y0:y1, x0:x1], cols[y0:y1, x0:x1]
        left, top, _, _ = self.camera.render.margin_px
        return np.meshgrid(np.arange(y0, y1) + top, np.arange(x0, x1) + left, indexing="ij")

    def scene_radiance(self, state: CameraState, radiance: np.ndarray) -> np.ndarray:
        """Render-size radiance → the output frame, placed by the lens's distortion alone (the reference
        channel's map for every channel, as depth and ids): no blur, lateral CA or vignetting; the
        scene-referred radiance that `outputs.radiance` writes."""
        if "optics.remap" not in self.stages:
            return crop_to_output(radiance, self.camera.render)
        maps = self.cache.get(self.geometry(state))
        reference = int(np.argmin([abs(scale - 1.0) for scale in self.ca_scales]))
        one = replace(maps, map_x=(maps.map_x[reference],), map_y=(maps.map_y[reference],))
        return remap_image(radiance, one, self.stages["optics.remap"].params["interpolation"])

    def vignetting_gain(self, state: CameraState, undistorted: np.ndarray | None = None) -> np.ndarray | None:
        """Relative illumination of each output pixel, (H, W) float32; None when not planned.

        `undistorted`: the maps' undistorted rays, when the caller has them (else looked up)."""
        if "optics.vignetting" not in self.stages:
            return None
        key = (state.K_px, state.distortion, state.f_number)
        if key != self._gain_key and undistorted is None and "optics.remap" in self.stages:
            undistorted = self.maps(state).undistorted_normalized
        if key != self._gain_key:
            camera, vignetting = self.camera, self.camera.profile.lens.vignetting
            K = np.array(state.K_px)
            grid = output_grid_px(camera.width_px, camera.height_px)
            distorted = np.stack([(grid[..., 0] - K[0, 2]) / K[0, 0], (grid[..., 1] - K[1, 2]) / K[1, 1]], -1)
            gain = relative_illumination(
                distorted if undistorted is None else undistorted,
                distorted,
                corner_radius_normalized=corner_radius_normalized(K, camera.width_px, camera.height_px),
                natural_cos4=vignetting.natural_cos4,
                polynomial=vignetting.optical_polynomial,
                weight=aperture_weight(
                    state.f_number,
                    camera.profile.lens.at_focal_length(state.focal_length_mm)[0],
                    vignetting.full_illumination_f_number,
                ),
            )
            self._gain_key, self._gain = key, gain.astype(np.float32)
        return self._gain
