"""The post-render camera model of one camera: lens → sensor → ISP, frame by frame, as the plan says.

Per frame:

1. the planned blurs of the pinhole radiance (`LensStages.blur`);
2. distortion, lateral CA and the CFA in one resampling straight onto the photosites
   (`camgen.optics.remap.remap_mosaic`): each site reads only its own colour channel;
3. photons per site from the camera equation, times QE, PRNU and vignetting in one cached per-site
   factor; the exposure time and gain come from auto-exposure (or the manual setting);
4. noise and the ADC (`camgen.sensor.capture`) → raw DN;
5. auto-exposure meters the raw frame and sets the next frame's exposure;
6. the ISP (`camgen.isp.pipeline`) → 8-bit RGB, when video or frames are asked for.

The pipeline keeps what changes slowly (lens maps, the per-site factor, the sensor's fixed patterns,
the auto-exposure and contrast-stretch state); everything random comes from the frame's `rng`.
"""

from __future__ import annotations

from concurrent.futures import Executor
from dataclasses import dataclass

import cv2
import numpy as np

from camgen.io.annotations import ANNOTATIONS_OF_DELIVERED_FRAMES
from camgen.isp.pipeline import CameraIsp
from camgen.job import CameraJob, CameraState, Job
from camgen.optics.remap import (
    STACKED_ROWS_MAX,
    LensMapCache,
    MosaicMap,
    mosaic_map,
    remap_image,
    remap_mosaic,
    stack_channels,
)
from camgen.plan.lens_stages import LensStages
from camgen.plan.timing import StageClock
from camgen.render.renderer import Passes
from camgen.render.sequence import crop_to_output
from camgen.sensor.auto_exposure import (
    ExposureLimits,
    ExposureSetting,
    metered_level_frac,
    metering_window,
    next_exposure,
    settled_exposure,
)
from camgen.sensor.capture import SensorModel
from camgen.sensor.cfa import cfa_channel_index, mosaic
from camgen.sensor.exposure import photons_per_cd_m2_s
from camgen.world.night import monochrome


def frame_rng(seed: int, camera_index: int, frame_index: int) -> np.random.Generator:
    """The generator of one frame of one camera: independent of which other frames are rendered."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(camera_index, frame_index)))


def exposure_limits(camera: CameraJob, fps: float) -> ExposureLimits:
    """What the camera can set: its exposure range (at most one frame interval) and analog gain."""
    exposure, sensor = camera.profile.exposure, camera.profile.sensor
    longest = min(exposure.exposure_time_max_s, 1.0 / fps)
    return ExposureLimits(
        exposure_time_min_s=min(exposure.exposure_time_min_s, longest),
        exposure_time_max_s=longest,
        gain_max_db=sensor.analog_gain_max_db,
    )


@dataclass
class CapturedFrame:
    raw_dn: np.ndarray
    """(H, W) uint16 raw mosaic (or mono image)."""
    rgb8: np.ndarray | None
    """(H, W, 3) uint8 ISP output; None when no processed output is planned."""
    state: CameraState
    """The camera state of this frame, with the exposure time and gain actually used."""
    metered_level_frac: float
    white_balance_rgb: tuple[float, float, float] | None = None
    """The ISP's white-balance gains (R, G, B) for this frame; None without ISP or for mono."""


class CameraPipeline:
    """Lens, sensor and ISP of one camera of a job (see the module docstring)."""

    def __init__(
        self,
        job: Job,
        camera: CameraJob,
        *,
        maps: LensMapCache | None = None,
        executor: Executor | None = None,
        clock: StageClock | None = None,
    ):
        self.job, self.camera = job, camera
        self.clock = clock or StageClock()
        """Wall time of each stage (`camgen.plan.timing`); the executor closes each frame."""
        self.stages = {stage.name: stage for stage in camera.stages}
        self.lens = LensStages(camera, maps)
        self.executor = executor
        profile = camera.profile
        sensor = profile.sensor
        self.mono = sensor.cfa == "mono"
        terms = frozenset(self.stages["sensor.noise"].params["terms"])
        self.sensor_model = SensorModel.build(
            sensor, camera.serial, terms=terms, gaussian_above_e=job.settings.gaussian_above_e
        )
        self.channel_index = None if self.mono else cfa_channel_index(sensor.cfa, sensor.height_px, sensor.width_px)
        qe = sensor.quantum_efficiency
        self._mono_weights = np.array([[qe.r, qe.g, qe.b]], np.float32)
        self.limits = exposure_limits(camera, job.fps)
        first = camera.states[0]
        self.setting = ExposureSetting(
            exposure_time_s=min(
                max(first.exposure_time_s, self.limits.exposure_time_min_s), self.limits.exposure_time_max_s
            ),
            gain_db=first.gain_db,
        )
        isp_steps = {name for name in self.stages if name.startswith("isp.")}
        self.isp = (
            CameraIsp(profile.isp, sensor, frame_interval_s=1.0 / job.fps, steps=isp_steps, executor=executor)
            if "io.video" in self.stages or "io.frames" in self.stages or annotates_delivered_frames(self.stages)
            else None
        )
        self._mosaic_maps: dict = {}
        self._site_factor_key = None
        self._site_factor = None
        self._stacked = None

    def carried_state(self) -> dict:
        """What the frames so far leave for the next, JSON-ready and exact (floats as their repr): the
        exposure auto-exposure set for the next frame and the ISP's adapting state
        (`CameraIsp.carried_state`). The rest of the pipeline is settings and caches, and each frame's
        noise comes from its own generator (`frame_rng`), so a pipeline given this state by
        `restore_state` renders the following frames as the one that rendered those frames would."""
        return {
            "exposure_time_s": float(self.setting.exposure_time_s),
            "gain_db": float(self.setting.gain_db),
            "isp": None if self.isp is None else self.isp.carried_state(),
        }

    def restore_state(self, state: dict) -> None:
        """Continue from a `carried_state` (see there)."""
        self.setting = ExposureSetting(float(state["exposure_time_s"]), float(state["gain_db"]))
        if (state["isp"] is None) != (self.isp is None):
            raise ValueError("the carried state is of a pipeline with a different ISP")
        if self.isp is not None:
            self.isp.restore_state(state["isp"])

    def state_for(self, index: int) -> CameraState:
        """The state of frame `index` with the exposure the camera will use for it."""
        return self.camera.states[index].model_copy(
            update={"exposure_time_s": self.setting.exposure_time_s, "gain_db": self.setting.gain_db}
        )

    def _mosaic_map(self, state: CameraState) -> MosaicMap:
        geometry = self.lens.geometry(state)
        if geometry not in self._mosaic_maps:
            spec = self.camera.render
            if len(self._mosaic_maps) >= 8:
                self._mosaic_maps.pop(next(iter(self._mosaic_maps)))
            self._mosaic_maps[geometry] = mosaic_map(
                self.lens.maps(state),
                self.channel_index,
                width_px=self.camera.width_px,
                height_px=self.camera.height_px,
                margin_px=spec.margin_px,
                render_height_px=spec.height_px,
            )
        return self._mosaic_maps[geometry]

    def _electrons_per_cd_m2_s(self, state: CameraState) -> np.ndarray | float:
        """Per-site factor from scene radiance to electrons per second: camera equation × QE × PRNU
        × relative illumination (cached while the lens state holds)."""
        key = (state.K_px, state.distortion, state.f_number)
        if key != self._site_factor_key:
            sensor = self.camera.profile.sensor
            factor = photons_per_cd_m2_s(sensor.pixel_pitch_um * sensor.pitch_y_um, state.f_number)
            per_site = self.sensor_model.electrons_per_photon
            vignetting = self.lens.vignetting_gain(state)
            if vignetting is not None:
                per_site = vignetting * per_site
            if isinstance(per_site, np.ndarray):
                per_site = (per_site * np.float32(factor)).astype(np.float32)
            else:
                per_site = float(per_site) * factor
            self._site_factor_key, self._site_factor = key, per_site
        return self._site_factor

    def light_at_sites(self, state: CameraState, passes: Passes) -> np.ndarray:
        """(H, W) float32 radiance each photosite receives through the lens (mono: QE-weighted)."""
        with self.clock("optics.blur"):
            radiance = self.lens.blur(state, passes)
        with self.clock("optics.remap"):
            return self._resample_onto_sites(state, radiance)

    def _resample_onto_sites(self, state: CameraState, radiance: np.ndarray) -> np.ndarray:
        interpolation = (
            self.stages["optics.remap"].params["interpolation"] if "optics.remap" in self.stages else "linear"
        )
        rows = radiance.shape[0] * (1 if self.mono else 3)
        if rows > STACKED_ROWS_MAX:
            # Too tall to stack for one remap (above ~10 000 rows): resample each channel, then sample.
            maps = self.lens.maps(state)
            rgb = (
                crop_to_output(radiance, self.camera.render)
                if maps is None
                else remap_image(radiance, maps, interpolation)
            )
            return rgb @ self._mono_weights[0] if self.mono else mosaic(rgb, self.camera.profile.sensor.cfa)
        if self.mono:
            stacked = cv2.transform(radiance, self._mono_weights)
        else:
            self._stacked = stacked = stack_channels(radiance, self._stacked)
        return remap_mosaic(stacked, self._mosaic_map(state), interpolation)

    def converge_exposure(self, state: CameraState, passes: Passes, iterations: int = 30) -> None:
        """Set the exposure auto-exposure settles at for this view, as if the camera had watched it
        for a while: the metered level of the noise-free expected raw frame reaches the target.

        The level is linear in the exposure product until sites saturate, so a few multiplicative
        corrections without the speed limit converge; `iterations` bounds them. The window is the
        metering's (`metering_window`).
        """
        sensor, auto = self.camera.profile.sensor, self.camera.profile.exposure.auto
        window = metering_window(self.camera.height_px, self.camera.width_px, auto.metering_region_frac)
        light = self.light_at_sites(state, passes)[window]
        per_site = self._electrons_per_cd_m2_s(state)
        rate_e_per_s = light * (per_site[window] if isinstance(per_site, np.ndarray) else per_site)
        dark = self.sensor_model.dark_e_per_s
        rate_e_per_s = rate_e_per_s + (dark[window] if isinstance(dark, np.ndarray) else dark)
        self.setting = settled_exposure(
            rate_e_per_s,
            self.setting,
            sensor=sensor,
            target_frac=auto.target_level_frac,
            limits=self.limits,
            iterations=iterations,
        )

    def process(self, state: CameraState, passes: Passes, *, rng: np.random.Generator) -> CapturedFrame:
        """One frame's raw and ISP output, and the exposure set for the next frame."""
        light = self.light_at_sites(state, passes)
        with self.clock("sensor"):
            raw = self.sensor_model.capture(
                light,
                exposure_time_s=state.exposure_time_s,
                gain_db=state.gain_db,
                rng=rng,
                electrons_per_photon=self._electrons_per_cd_m2_s(state),
                executor=self.executor,
            )
        with self.clock("sensor.auto_exposure"):
            level = self._meter_and_adapt(state, raw)
        with self.clock("isp"):
            rgb8 = None if self.isp is None else self.isp.process(raw, state.gain_db, grey_out=state.night_mode)
            if rgb8 is not None and state.night_mode:  # the camera sends grey in night mode
                rgb8 = monochrome(rgb8)
        white_balance = None if self.isp is None or self.mono else tuple(self.isp.white_balance_gains.tolist())
        return CapturedFrame(
            raw_dn=raw, rgb8=rgb8, state=state, metered_level_frac=level, white_balance_rgb=white_balance
        )

    def _meter_and_adapt(self, state: CameraState, raw: np.ndarray) -> float:
        """Meter the raw frame; with auto-exposure, set the next frame's exposure. Returns the level."""
        sensor, exposure = self.camera.profile.sensor, self.camera.profile.exposure
        auto = exposure.auto
        level = metered_level_frac(
            raw,
            black_level_dn=sensor.black_level_dn,
            white_level_dn=sensor.white_level_dn,
            region_frac=auto.metering_region_frac,
        )
        if exposure.mode == "auto":
            self.setting = next_exposure(
                ExposureSetting(state.exposure_time_s, state.gain_db),
                level,
                target_frac=auto.target_level_frac,
                speed_up_ev_per_s=auto.speed_up_ev_per_s,
                speed_down_ev_per_s=auto.speed_down_ev_per_s,
                frame_interval_s=1.0 / self.job.fps,
                limits=self.limits,
            )
        return level


def annotates_delivered_frames(stages) -> bool:
    """Whether the annotations write or cut from the delivered 8-bit frames (MOT, YOLO, re-ID)."""
    annotate = stages.get("annotate")
    return annotate is not None and bool(set(ANNOTATIONS_OF_DELIVERED_FRAMES) & set(annotate.params["formats"]))


def cuts_reid_crops(stages) -> bool:
    """Whether the annotations cut re-identification crops out of the delivered frames."""
    annotate = stages.get("annotate")
    return annotate is not None and "reid" in annotate.params.get("formats", ())
