"""Run a compiled Job: render each camera's planned passes, frame by frame, and write its outputs.

Per frame: the ideal pinhole passes (radiance, depth, instance ids; `camgen.render.sequence`), the camera
model (`camgen.plan.camera_pipeline`: lens, sensor with auto-exposure, ISP, a virtual PTZ's crop), then
what the camera's stages ask for: the video in the profile's codec (``video.mp4``), frames (the 8-bit
stream as PNG/TIFF, or the linear radiance as EXR), raw DNG, depth (16-bit PNG or EXR), the
scene-referred radiance (`camgen.io.radiance`), forward optical flow and scene flow (`camgen.plan.flow`),
annotations (`camgen.plan.annotations`: MOTChallenge with its img1 images and optional public
detections, COCO, YOLO, Market-1501 re-ID crops) and the per-frame camera states (``camera.jsonl``).

Each camera's folder is written as ``CAMERA.partial`` and renamed when the camera is complete (removed
on any exception), so a render stopped part-way leaves no per-frame files; job.json and manifest.json
are written last, so a job directory holding them holds a finished render. `IMPLEMENTED_STAGES` are the
stages run here; `unimplemented_stages` names any other stage a job plans (a job compiled by another
camgen version), so that callers can say it is skipped.
"""

from __future__ import annotations

import contextlib
import json
import shutil
import time
from collections.abc import Callable, Collection, Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from camgen.annotate.detection import detect_people, hog_detector
from camgen.io.annotations import IMAGE_SUFFIXES, LineSpool, SequenceAnnotations, write_reid_crops
from camgen.io.dng import SRGB_FROM_XYZ, write_dng
from camgen.io.files import atomic_path, write_text_atomic
from camgen.io.flow import write_flo, write_scene_flow
from camgen.io.frames import write_depth, write_frame
from camgen.io.manifest import write_manifest
from camgen.io.radiance import RadianceWriter
from camgen.isp.eptz import crop_and_scale
from camgen.job import CameraJob, Job
from camgen.optics.remap import LensMapCache
from camgen.plan.annotations import Annotator
from camgen.plan.camera_pipeline import CameraPipeline, cuts_reid_crops, frame_rng
from camgen.plan.flow import FlowField
from camgen.plan.lens_stages import LensStages
from camgen.plan.timing import StageClock, stage_sums
from camgen.render.renderer import Passes, Renderer
from camgen.render.scene_graph import build_scene_graph, instance_table
from camgen.render.sequence import CameraRenderer

RAW_SUFFIX = {"png16": ".png", "tiff16": ".tif", "exr": ".exr"}
"""File suffix of each raw mosaic format (`outputs.raw`)."""
PARTIAL_SUFFIX = ".partial"
"""A camera's folder is written under its name with this suffix and renamed when complete."""
NOISE_THREADS = 2
"""Threads for the sensor's row bands and the tone lookup (the machines here have 2 cores)."""

IMPLEMENTED_STAGES = frozenset(
    {
        "render",
        "optics.motion_blur",
        "optics.depth_of_field",
        "optics.axial_ca",
        "optics.diffraction",
        "optics.remap",
        "optics.vignetting",
        "sensor.exposure",
        "sensor.noise",
        "sensor.adc",
        "isp.demosaic",
        "isp.white_balance",
        "isp.ccm",
        "isp.denoise",
        "isp.contrast_stretch",
        "isp.tone",
        "isp.sharpen",
        "isp.eptz",
        "io.video",
        "io.camera_metadata",
        "annotate",
        "io.raw_dng",
        "io.raw",
        "io.frames",
        "io.depth",
        "io.radiance",
        "io.flow",
        "io.scene_flow",
    }
)


@dataclass
class CameraResult:
    name: str
    directory: Path
    frames: int = 0
    files: list[Path] = field(default_factory=list)
    total_s: float = 0.0
    stage_frames: list[dict[str, float]] = field(default_factory=list)
    """Wall time per stage of each frame rendered, s (`camgen.plan.timing.StageClock`). The first
    frame carries the one-off costs: the scene upload, lens maps, auto-exposure's convergence."""
    frame_wall_s: list[float] = field(default_factory=list)
    """Wall time of each frame, s (the first from the camera's setup on)."""
    finish_s: dict[str, float] = field(default_factory=dict)
    """Wall time per stage after the last frame: flushing the video encoder, writing annotations."""

    @property
    def render_s(self) -> float:
        """Time spent drawing and reading back passes (motion-blur sub-frames included), s."""
        return stage_sums(self.stage_frames).get("render", 0.0)


def job_directory_name(job: Job) -> str:
    """`<scene>-<first 8 hex digits of the job hash>`: readable, and distinct for distinct jobs."""
    return f"{job.scene_name}-{job.job_id[:8]}"


def unimplemented_stages(camera: CameraJob) -> list[str]:
    return [stage.name for stage in camera.stages if stage.name not in IMPLEMENTED_STAGES]


def rendered_record(cameras: Iterable[str], frames: Iterable[int] | None) -> dict:
    """What a manifest records as `rendered`: the cameras, and the frame indices ("all" for None)."""
    return {"cameras": list(cameras), "frames": "all" if frames is None else list(frames)}


def execute(
    job: Job,
    out_dir: str | Path,
    *,
    renderer: Renderer,
    frames: Iterable[int] | None = None,
    cameras: Iterable[str] | None = None,
    resolve_path: Callable[[str], Path] | None = None,
    save_passes: bool = False,
    on_frame: Callable[[str, int], None] | None = None,
) -> list[CameraResult]:
    """Render `job` into ``out_dir/<scene>-<hash>/<camera>/`` and return what was written.

    frames: frame indices to render (default: all). Auto-exposure runs from the first frame rendered,
    so a subset starts from the profile's exposure, not where a full render would be. save_passes:
    also write each frame's passes, through the lens into the output frame, as
    ``passes/<frame>.npz`` (radiance_cd_m2, depth_m, instance_id) and its raw DN.
    on_frame(camera, index) is called after each frame (for progress).
    """
    job_dir = Path(out_dir) / job_directory_name(job)
    indices = list(range(job.frame_count) if frames is None else frames)
    wanted = None if cameras is None else set(cameras)
    # A render starts clean: no job.json or manifest.json until it completes, and no files left in a
    # camera's directory by an earlier render of it (fewer frames, other outputs, a killed run).
    for stale in ("manifest.json", "job.json"):
        (job_dir / stale).unlink(missing_ok=True)
    for camera in job.cameras:
        for directory in (job_dir / camera.name, job_dir / f"{camera.name}{PARTIAL_SUFFIX}"):
            if (wanted is None or camera.name in wanted) and directory.is_dir():
                shutil.rmtree(directory)
    results = []
    maps = LensMapCache()  # cameras with the same lens and zoom share their maps
    try:
        with ThreadPoolExecutor(NOISE_THREADS) as executor:
            for camera_index, camera in enumerate(job.cameras):
                if wanted is not None and camera.name not in wanted:
                    continue
                # A camera's files (per-frame images included) are written under a temporary name and the
                # folder is renamed when the camera is complete; a render stopped part-way leaves none.
                partial = job_dir / f"{camera.name}{PARTIAL_SUFFIX}"
                context = _Context(job, camera_index, partial, renderer, maps, executor)
                result = _execute_camera(context, indices, resolve_path, save_passes, on_frame)
                final = job_dir / camera.name
                partial.replace(final)
                result.directory = final
                result.files = [final / path.relative_to(partial) for path in result.files]
                results.append(result)
        # Written last: a job directory with job.json in it holds a finished render, of the cameras and
        # frames the manifest's `rendered` names (all of them unless --camera/--frames chose fewer).
        write_text_atomic(job_dir / "job.json", job.to_json())
        rendered = rendered_record([r.name for r in results], indices if frames is not None else None)
        write_manifest(job, job_dir, rendered=rendered)  # after everything, job.json included
    except BaseException:
        # Stopped anywhere before the manifest (an error, Ctrl-C, a batch worker's SIGTERM, even between
        # job.json and the manifest): nothing this render wrote stays, finished cameras included, so a job
        # directory without a manifest holds no file of it.
        discard_unfinished(job, job_dir, wanted)
        raise
    return results


def discard_unfinished(job: Job, job_dir: Path, cameras: Collection[str] | None = None) -> bool:
    """Delete what an unfinished render of `job` left in `job_dir` (its cameras' folders, finished or
    ``.partial``, and job.json), unless the job's manifest is there (a finished render). cameras: only these
    cameras' folders (None: every camera of the job). The job directory goes too once it is empty. Returns
    whether anything was deleted. Used when a render stops part-way, by `execute` itself, and by a batch whose
    worker was killed before it could (`camgen.batch.run`)."""
    job_dir = Path(job_dir)
    if not job_dir.is_dir() or (job_dir / "manifest.json").exists():
        return False
    deleted = False
    for camera in job.cameras:
        if cameras is not None and camera.name not in cameras:
            continue
        for directory in (job_dir / camera.name, job_dir / f"{camera.name}{PARTIAL_SUFFIX}"):
            if directory.is_dir():
                shutil.rmtree(directory, ignore_errors=True)
                deleted = True
    job_json = job_dir / "job.json"
    if job_json.exists():
        job_json.unlink(missing_ok=True)
        deleted = True
    with contextlib.suppress(OSError):
        job_dir.rmdir()  # only if empty
    return deleted


@dataclass
class _Context:
    job: Job
    camera_index: int
    directory: Path
    renderer: Renderer
    maps: LensMapCache
    executor: ThreadPoolExecutor


def _execute_camera(context: _Context, indices, resolve_path, save_passes, on_frame) -> CameraResult:
    job, directory = context.job, context.directory
    camera = job.cameras[context.camera_index]
    result = CameraResult(camera.name, directory)
    started = time.perf_counter()
    clock = StageClock()
    stages = {stage.name: stage for stage in camera.stages}
    pipeline = (
        CameraPipeline(job, camera, maps=context.maps, executor=context.executor, clock=clock)
        if "radiance" in camera.render.passes
        else None
    )
    lens = pipeline.lens if pipeline is not None else LensStages(camera, context.maps)
    video = None
    # Per-frame lines (camera.jsonl, the annotations) go to files under the camera's folder as they come,
    # not into memory: a long sequence renders in flat memory (issue 23). Deleted when the camera ends.
    spool_dir = directory / ".spool"
    metadata = LineSpool(spool_dir / "camera.lines")
    camera_renderer = CameraRenderer(context.renderer, build_scene_graph(job.scene, resolve_path), camera)
    annotator = sequence = detector = None
    formats = ()
    if "annotate" in stages:
        annotator = Annotator(camera_renderer, lens)
        width_px, height_px = camera.output_size_px or (camera.width_px, camera.height_px)
        frames_format = stages["io.frames"].params["format"] if "io.frames" in stages else None
        params = stages["annotate"].params
        formats = params["formats"]
        if "detections" in params:
            detector = hog_detector()
            if detector is None:
                raise RuntimeError(
                    "outputs.mot_detections needs OpenCV's HOG people detector, which this OpenCV build "
                    "lacks; install opencv-contrib-python-headless"
                )
        sequence = SequenceAnnotations(
            name=camera.name,
            fps=job.fps,
            width_px=width_px,
            height_px=height_px,
            frame_count=max(indices) + 1 if indices else 0,
            frame_suffix=None if frames_format is None else FRAME_SUFFIX[frames_format],
            image_suffix=IMAGE_SUFFIXES[params.get("images", "jpg")],
            detections=detector is not None,
            spool_dir=spool_dir,
        )
        graph = camera_renderer.graph
        actor_nodes = zip(graph.actors, graph.actor_nodes, strict=True)
        track_ids = {actor.name: graph.instance_ids[node] for actor, node in actor_nodes}
        for index, (actor, node) in enumerate(zip(graph.actors, graph.actor_nodes, strict=True)):
            rig = graph.rig(index)
            attributes = None if rig is None or rig.model is None else rig.model.appearance.attributes()
            sequence.describe(
                graph.instance_ids[node],
                name=actor.name,
                cls=actor.cls,
                attributes=attributes,
                rides=None if actor.rides is None else track_ids[actor.rides],
            )
    radiance_files = (
        RadianceWriter(directory / "radiance", stages["io.radiance"].params["format"])
        if "io.radiance" in stages
        else None
    )
    flow_field = FlowField(camera_renderer, lens) if {"io.flow", "io.scene_flow"} & stages.keys() else None
    converge = (
        pipeline is not None and camera.exposure_mode == "auto" and job.settings.auto_exposure_start == "converged"
    )
    try:
        for index in indices:
            state = camera.states[index] if pipeline is None else pipeline.state_for(index)
            with clock("render"):
                # A frame drawn to meter the view is drawn sharp: its exposure is the profile's guess.
                frame = camera_renderer.frame(index, state, sharp=converge)
            if converge:
                # Start as a camera that has watched this view for a while, not from the profile's guess.
                converge = False
                pipeline.converge_exposure(state, frame.passes)
                settled = pipeline.state_for(index)
                if camera_renderer.redraws_settled(state, settled):
                    with clock("render"):
                        frame = camera_renderer.frame(index, settled)  # the blur spans the settled exposure
                state = settled
            captured = None
            if pipeline is not None:
                rng = frame_rng(job.seed, context.camera_index, frame.index)
                captured = pipeline.process(state, frame.passes, rng=rng)
            rgb8 = None if captured is None else captured.rgb8
            if rgb8 is not None and state.window_px is not None:
                with clock("isp.eptz"):
                    rgb8 = crop_and_scale(rgb8, state.window_px, camera.output_size_px)
            if rgb8 is not None and "io.video" in stages:
                with clock("io.video"):
                    if video is None:
                        from camgen.io.video import VideoWriter  # PyAV only where a video is written

                        width_px, height_px = camera.output_size_px or (camera.width_px, camera.height_px)
                        video = VideoWriter(
                            directory / "video.mp4",
                            width_px=width_px,
                            height_px=height_px,
                            fps=job.fps,
                            codec=camera.profile.codec,
                            preset=camera.profile.codec.preset,
                        )
                    video.write(rgb8)
            with clock("optics.passes"):
                stream = _stream_passes(camera, stages, state, frame.passes, lens, save_passes)
            with clock("io.files"):
                _write_files(context, stages, state, frame, captured, rgb8, stream, result)
            if radiance_files is not None:
                with clock("io.radiance"):
                    scene_radiance = lens.scene_radiance(state, frame.passes.radiance)
                    if state.window_px is not None:
                        scene_radiance = crop_and_scale(scene_radiance, state.window_px, camera.output_size_px)
                    result.files.append(radiance_files.write(f"{frame.index:06d}", scene_radiance))
            if annotator is not None:
                window = state.window_px

                def to_stream(image, window=window):
                    return (
                        image if window is None else crop_and_scale(image, window, camera.output_size_px, nearest=True)
                    )

                with clock("annotate"):
                    annotated = annotator.annotate(state, stream, post=None if window is None else to_stream)
                    sequence.add(annotated)
                    if cuts_reid_crops(stages) and rgb8 is not None:
                        result.files += write_reid_crops(
                            directory, annotated, rgb8, camera_number=context.camera_index + 1
                        )
                if rgb8 is not None:
                    with clock("io.annotation_images"):
                        if "mot" in formats:
                            result.files.append(sequence.write_mot_image(directory, frame.index, rgb8))
                        if "yolo" in formats:
                            result.files += sequence.write_yolo_frame(directory, annotated, rgb8)
                    if detector is not None:
                        with clock("annotate.detect"):
                            sequence.add_detections(frame.index, detect_people(detector, rgb8[..., ::-1]))
            if flow_field is not None and frame.index + 1 < job.frame_count:
                with clock("io.flow"):  # after the annotations: it moves the actors to the next frame
                    flow_px, displacement_m = flow_field.flow(state, camera.states[frame.index + 1], stream)
                    if "io.flow" in stages:
                        result.files.append(directory / "flow" / f"{frame.index:06d}.flo")
                        write_flo(result.files[-1], flow_px)
                    if "io.scene_flow" in stages:
                        result.files.append(directory / "scene_flow" / f"{frame.index:06d}.exr")
                        write_scene_flow(result.files[-1], displacement_m)
            if "io.camera_metadata" in stages:
                record = state.model_dump(mode="json")
                output_K = record.pop("output_K_px")
                if state.window_px is not None:  # K_px describes the stream; the sensor's is kept beside it
                    record["sensor_K_px"] = record["K_px"]
                    record["K_px"] = output_K
                if captured is not None:
                    record["metered_level_frac"] = captured.metered_level_frac
                    if captured.white_balance_rgb is not None:
                        record["white_balance_rgb"] = captured.white_balance_rgb
                metadata.append(json.dumps(record, separators=(",", ":")))
            if save_passes:
                if result.frames == 0:
                    table = [vars(instance) for instance in instance_table(job.scene)]
                    write_text_atomic(directory / "passes" / "instances.json", json.dumps(table, indent=1))
                raw = None if captured is None else captured.raw_dn
                with clock("io.passes"):
                    _save_passes(directory / "passes" / f"{frame.index:06d}.npz", stream, raw, result)
            result.frames += 1
            clock.end_frame()
            if on_frame is not None:
                on_frame(camera.name, frame.index)
        if video is not None:
            with clock("io.video"):
                video.close()
            result.files.append(directory / "video.mp4")
        if radiance_files is not None and result.frames:
            result.files.append(radiance_files.close())
        if len(metadata):
            result.files.append(metadata.write(directory / "camera.jsonl"))
        if sequence is not None:
            with clock("annotate"):
                if "mot" in formats:
                    result.files += sequence.write_mot(directory)
                if "coco" in formats:
                    result.files.append(sequence.write_coco(directory / "coco.json"))
                if "yolo" in formats:
                    result.files.append(sequence.write_yolo_data(directory))
        clock.end_frame()
        result.stage_frames, result.finish_s = clock.frames[:-1], clock.frames[-1]
        result.frame_wall_s = clock.frame_wall_s[:-1]
    except BaseException:
        if video is not None:
            video.abort()
        raise
    finally:
        camera_renderer.close()
        metadata.close()
        if sequence is not None:
            sequence.close()
        if spool_dir.is_dir():
            spool_dir.rmdir()
    result.total_s = time.perf_counter() - started
    return result


FRAME_SUFFIX = {"png": ".png", "tiff": ".tiff", "exr": ".exr"}
DEPTH_SUFFIX = {"png16": ".png", "exr": ".exr"}


def _stream_passes(camera: CameraJob, stages, state, rendered: Passes, lens: LensStages, save_passes: bool) -> Passes:
    """The frame's passes through the lens and onto the stream (a virtual PTZ's crop), once, holding
    only those that the saved passes, the EXR frames, the depth files, the annotations or the flow use."""
    radiance = save_passes or ("io.frames" in stages and stages["io.frames"].params["format"] == "exr")
    flow = "io.flow" in stages or "io.scene_flow" in stages
    depth = save_passes or "io.depth" in stages or radiance or flow  # the blur stages read depth too
    ids = save_passes or "annotate" in stages or flow
    if not (radiance or depth or ids):
        return Passes()
    through = lens.apply(
        state,
        Passes(
            radiance=rendered.radiance if radiance else None,
            depth_m=rendered.depth_m if depth else None,
            instance_id=rendered.instance_id if ids else None,
        ),
    )
    return through if state.window_px is None else _eptz_passes(through, state.window_px, camera.output_size_px)


def _write_files(context: _Context, stages, state, frame, captured, rgb8, stream: Passes, result: CameraResult) -> None:
    """The optional per-frame files: raw DNG, frames (8-bit stream or linear EXR radiance), depth.
    `stream`: the frame's passes through the lens, on the stream (`_stream_passes`)."""
    camera = context.job.cameras[context.camera_index]
    directory, name = context.directory, f"{frame.index:06d}"
    if "io.raw_dng" in stages and captured is not None:
        sensor = camera.profile.sensor
        qe = sensor.quantum_efficiency
        mono = sensor.cfa == "mono"
        gains = captured.white_balance_rgb
        path = directory / "raw" / f"{name}.dng"
        write_dng(
            path,
            captured.raw_dn,
            cfa=sensor.cfa,
            black_level_dn=sensor.black_level_dn,
            white_level_dn=sensor.white_level_dn,
            bit_depth=sensor.bit_depth,
            color_matrix_xyz_to_camera=None if mono else np.diag([qe.r, qe.g, qe.b]) @ SRGB_FROM_XYZ,
            as_shot_neutral_rgb=None if mono or gains is None else tuple(min(gains) / g for g in gains),
            camera_name=camera.profile_name,
            exposure_time_s=state.exposure_time_s,
            f_number=state.f_number,
            temperature_c=sensor.temperature_c,
        )
        result.files.append(path)
    if "io.raw" in stages and captured is not None:
        kind = stages["io.raw"].params["format"]
        sensor = camera.profile.sensor
        if result.frames == 0:  # what a reader needs to interpret the samples, once per camera
            meta = directory / "raw" / "raw.json"
            write_text_atomic(
                meta,
                json.dumps(
                    {
                        "cfa": sensor.cfa,
                        "black_level_dn": sensor.black_level_dn,
                        "white_level_dn": sensor.white_level_dn,
                        "bit_depth": sensor.bit_depth,
                        "unit": "DN as the ADC delivered them, black level included",
                    },
                    indent=1,
                ),
            )
            result.files.append(meta)
        path = directory / "raw" / f"{name}{RAW_SUFFIX[kind]}"
        raw = np.ascontiguousarray(captured.raw_dn)
        if kind == "exr":
            write_frame(path, raw.astype(np.float32), format="exr")
        else:
            write_frame(path, raw.astype(np.uint16), format="png" if kind == "png16" else "tiff")
        result.files.append(path)
    if "io.frames" in stages:
        kind = stages["io.frames"].params["format"]
        path = directory / "frames" / f"{name}{FRAME_SUFFIX[kind]}"
        if kind == "exr":  # linear: the scene radiance through the lens, cd/m², before the sensor
            write_frame(path, np.ascontiguousarray(stream.radiance, dtype=np.float32), format="exr")
        elif rgb8 is not None:
            write_frame(path, rgb8, format=kind)
        result.files.append(path)
    if "io.depth" in stages:
        kind = stages["io.depth"].params["format"]
        path = directory / "depth" / f"{name}{DEPTH_SUFFIX[kind]}"
        write_depth(path, stream.depth_m, format=kind)
        result.files.append(path)


def _eptz_passes(passes, window, output_size_px):
    """The stream's crop of output-size passes: radiance averaged, depth and ids by nearest pixel."""
    return type(passes)(
        radiance=None if passes.radiance is None else crop_and_scale(passes.radiance, window, output_size_px),
        depth_m=None
        if passes.depth_m is None
        else crop_and_scale(passes.depth_m, window, output_size_px, nearest=True),
        instance_id=None
        if passes.instance_id is None
        else crop_and_scale(passes.instance_id, window, output_size_px, nearest=True),
    )


def _save_passes(path: Path, passes, raw_dn, result: CameraResult) -> None:
    arrays = {
        key: value
        for key, value in (
            ("radiance_cd_m2", passes.radiance),
            ("depth_m", passes.depth_m),
            ("instance_id", passes.instance_id),
            ("raw_dn", raw_dn),
        )
        if value is not None
    }
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez_compressed(handle, **arrays)
    result.files.append(path)
