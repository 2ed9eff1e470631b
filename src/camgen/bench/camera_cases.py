"""The post-render camera model at 1080p: the fast pipeline against the naive reference, the shot-noise
method by photon level, and float32 against float64.

Input: the parking-lot scene's first frame, rendered once (1× supersampling, its planned margin), at the
exposure auto-exposure settles at. "Core" is what the issue's 50 frames/s target covers: distortion and
lateral CA onto the photosites, vignetting, noise and ADC, white balance, demosaic, CCM, contrast
stretch, tone, 8 bit. "As planned" adds the scene's diffraction blur and the profile's false-colour
suppression, denoise and sharpening (options a profile chooses, as real ISPs offer them).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from functools import cache
from pathlib import Path

import numpy as np
from scipy.stats import norm, poisson

from camgen.bench.harness import Case
from camgen.bench.reference_camera import ReferenceCamera
from camgen.sensor.noise import BANDS, Adc, TemporalNoise, _band_slices, _normal_table, sample_raw, standard_normal

PIXELS_1080P = 1920 * 1080
SHOT_LEVELS_E = (1.0, 3.0, 10.0, 20.0, 50.0, 200.0)
OPTIONAL_STAGES = (
    "optics.diffraction",
    "optics.motion_blur",
    "isp.false_colour",
    "isp.denoise",
    "isp.sharpen",
)
"""Stages a profile or scene adds to the core (every camera runs the core's; these, as each profile asks)."""


def _setup(repo: Path, size: tuple[int, int] = (1920, 1080)):
    """The pipelines and inputs of the cases, for the parking lot's camera with a `size` sensor."""
    return _setup_at(repo, tuple(size))


@cache
def _setup_at(repo: Path, size: tuple[int, int]):
    from camgen.bench.render_cases import _parking_lot, _renderer
    from camgen.plan.camera_pipeline import CameraPipeline
    from camgen.render.scene_graph import build_scene_graph
    from camgen.render.sequence import CameraRenderer

    job, camera, _ = _parking_lot(repo, shadows=True, size=size)
    camera = camera.model_copy(update={"render": camera.render.model_copy(update={"supersampling": 1})})
    core = camera.model_copy(update={"stages": tuple(s for s in camera.stages if s.name not in OPTIONAL_STAGES)})
    executor = ThreadPoolExecutor(2)
    planned = CameraPipeline(job, camera, executor=executor)
    renderer = CameraRenderer(_renderer(), build_scene_graph(job.scene), camera)
    passes = renderer.frame(0).passes
    renderer.close()
    planned.converge_exposure(planned.state_for(0), passes)
    fast = CameraPipeline(job, core, executor=executor)
    fast.setting = planned.setting
    state = fast.state_for(0)
    model = fast.sensor_model
    reference = ReferenceCamera(core.profile, model.pattern, model.dark_e_per_s)
    return planned, fast, reference, state, passes


def camera_cases(repo: Path) -> list[Case]:
    def core() -> None:
        _, fast, _, state, passes = _setup(repo)
        fast.process(state, passes, rng=np.random.default_rng(0))

    def planned() -> None:
        pipeline, _, _, state, passes = _setup(repo)
        pipeline.process(state, passes, rng=np.random.default_rng(0))

    def core_checked() -> float:
        core()
        return _core_error_pct(repo)

    def naive() -> None:
        _, _, reference, *_ = _setup(repo)
        reference.isp(_naive_raw(repo))

    cases = [
        Case(name="camera model 1080p, naive float64 reference", run=naive, repeats=3, setup=lambda: _setup(repo)),
        Case(
            name="camera model 1080p, core (fast path)",
            run=core_checked,
            setup=lambda: _core_error_pct(repo),
            error_unit="% largest mean raw DN difference per CFA channel",
            repeats=15,
            baseline="camera model 1080p, naive float64 reference",
        ),
        Case(
            name="camera model 1080p, as planned (+ diffraction, false colour, denoise, sharpen)",
            run=planned,
            repeats=9,
            baseline="camera model 1080p, core (fast path)",
        ),
    ]
    return cases + _stage_cases(repo) + _shot_noise_cases() + _precision_cases()


def _stage_cases(repo: Path) -> list[Case]:
    """The core's parts, each timed alone on the same frame."""

    def sites() -> None:
        _, fast, _, state, passes = _setup(repo)
        fast.light_at_sites(state, passes)

    def sensor() -> None:
        _, fast, _, state, passes = _setup(repo)
        light = fast.light_at_sites(state, passes)
        fast.sensor_model.capture(
            light,
            exposure_time_s=state.exposure_time_s,
            gain_db=state.gain_db,
            rng=np.random.default_rng(0),
            electrons_per_photon=fast._electrons_per_cd_m2_s(state),
            executor=fast.executor,
        )

    def isp() -> None:
        _setup(repo)[1].isp.process(_raw(repo))

    return [
        Case(name="core part: lens onto the photosites (split + one remap)", run=sites),
        Case(
            name="core part: lens + sensor (noise, full well, ADC)",
            run=sensor,
            baseline="core part: lens onto the photosites (split + one remap)",
        ),
        Case(name="core part: ISP (WB, demosaic, CCM, stretch, tone)", run=isp),
    ]


def _naive_raw(repo: Path) -> np.ndarray:
    """The naive reference's raw frame of the same state and input (not cached: it is timed)."""
    _, fast, reference, state, passes = _setup(repo)
    light = reference.light_at_sites(
        passes.radiance, fast.lens.maps(state), fast.camera.render.margin_px, fast.lens.vignetting_gain(state)
    )
    return reference.raw(
        light,
        f_number=state.f_number,
        exposure_time_s=state.exposure_time_s,
        gain_db=state.gain_db,
        rng=np.random.default_rng(0),
    )


@cache
def _core_error_pct(repo: Path) -> float:
    """The fast path's raw frame against the naive reference's (independent draws): the largest
    relative difference of the mean black-subtracted DN over a CFA channel, in %."""
    _, fast, _, _, _ = _setup(repo)
    sensor = fast.camera.profile.sensor
    ours = _raw(repo).astype(np.float64) - sensor.black_level_dn
    reference = _naive_raw(repo).astype(np.float64) - sensor.black_level_dn
    index = fast.channel_index if fast.channel_index is not None else np.zeros(ours.shape, np.int8)
    return max(float(100 * abs(ours[index == c].mean() / reference[index == c].mean() - 1)) for c in np.unique(index))


@cache
def _raw(repo: Path) -> np.ndarray:
    _, fast, _, state, passes = _setup(repo)
    return fast.process(state, passes, rng=np.random.default_rng(0)).raw_dn


def _rounded_gaussian_tv(level_e: float) -> float:
    """Total-variation distance between Poisson(λ) and N(λ, λ) rounded to integers (clipped at 0)."""
    k = np.arange(0, int(level_e + 12 * np.sqrt(level_e) + 20))
    gaussian = norm.cdf(k + 0.5, level_e, np.sqrt(level_e)) - norm.cdf(k - 0.5, level_e, np.sqrt(level_e))
    gaussian[0] += norm.cdf(-0.5, level_e, np.sqrt(level_e))
    return 0.5 * float(np.abs(gaussian - poisson.pmf(k, level_e)).sum())


def _shot_noise_cases() -> list[Case]:
    """Exact Poisson against the Gaussian approximation on a 1080p frame of one level; the error is
    the total-variation distance of the (rounded) Gaussian from the Poisson law."""
    cases = []
    for level in SHOT_LEVELS_E:
        mean = np.full(PIXELS_1080P, level, np.float32)
        exact = f"shot noise λ = {level:g} e⁻, exact Poisson (numpy)"
        cases.append(Case(name=exact, run=lambda m=mean: _discard(np.random.default_rng(0).poisson(m)), repeats=3))

        def gaussian(m=mean) -> float:
            z = standard_normal(m.shape, rng=np.random.default_rng(0))
            _discard(m + np.sqrt(m) * z)
            return _rounded_gaussian_tv(float(m[0]))

        cases.append(
            Case(
                name=f"shot noise λ = {level:g} e⁻, Gaussian (table normals)",
                run=gaussian,
                repeats=3,
                baseline=exact,
                error_unit="TV distance",
            )
        )
    return cases


def _precision_cases() -> list[Case]:
    """The fused sensor chain in float32 against the same draws in float64: the error is the fraction
    of 12-bit DN that come out different."""
    rng = np.random.default_rng(3)
    rate = rng.uniform(5.0, 9000.0, (1080, 1920)).astype(np.float32)
    noise = TemporalNoise(read_noise_e=2.5, gaussian_above_e=0.0)
    adc = Adc(gain_dn_per_e=0.35, black_level_dn=240.0, bit_depth=12)
    table64 = _normal_table().astype(np.float64)

    def float32() -> np.ndarray:
        return sample_raw(
            rate,
            per_unit=1.0,
            exposure_time_s=1.0,
            dark_e_per_s=0.0,
            offset_e=None,
            noise=noise,
            adc=adc,
            rng=np.random.default_rng(0),
        )

    fast = cache(float32)  # the float64 case compares with it, without timing it again

    def float64() -> float:
        # The same standard normals, band by band, in float64.
        streams = np.random.default_rng(0).spawn(BANDS + 1)
        z = np.concatenate(
            [
                table64[np.frombuffer(stream.bytes(2 * (rows.stop - rows.start) * 1920), "<u2")].reshape(-1, 1920)
                for rows, stream in zip(_band_slices(1080), streams, strict=False)
            ]
        )
        mean = rate.astype(np.float64)
        electrons = mean + np.sqrt(mean + 2.5**2) * z
        dn = np.clip(np.floor(electrons * 0.35 + 240.5), 0, 4095).astype(np.uint16)
        return float(np.mean(dn != fast()))

    return [
        Case(name="sensor chain 1080p, float32 (fast path)", run=lambda: _discard(float32()), repeats=5),
        Case(
            name="sensor chain 1080p, float64, same draws",
            run=float64,
            repeats=3,
            setup=fast,
            baseline="sensor chain 1080p, float32 (fast path)",
            error_unit="of DN differ",
        ),
    ]


def _discard(_result) -> None:
    """Cases time the work, not its result."""
