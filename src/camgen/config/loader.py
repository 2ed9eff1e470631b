"""Load profiles, scenes and datasets from YAML, resolve references, and check them against each other.

This is the only place that reads configuration files. Everything returned is a frozen model.
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from camgen.config.dataset import Dataset
from camgen.config.placement import cameras_behind_planes, cameras_inside_solids, sky_light_problems, warn_about
from camgen.config.profile import Profile
from camgen.config.scene import Camera, FileMesh, Scene, is_character
from camgen.config.validation import show_value, validate
from camgen.config.yaml_source import YamlDocument, load_yaml, merge_documents
from camgen.errors import ConfigError, Location, Problem
from camgen.io.files import input_file_problem
from camgen.io.gltf import IN_PLACE_SPEED_M_S, clip_ground_speed_m_s, load_character, posed_bounds
from camgen.io.texture_images import TextureFileError, read_texture_images

PROFILE_NAME = re.compile(r"^[A-Za-z0-9_.-]+$")


@dataclass(frozen=True)
class LoadedProfile:
    name: str
    path: Path
    profile: Profile


@dataclass(frozen=True)
class LoadedScene:
    """A validated scene, where it came from, and the profile of each camera (by camera name)."""

    name: str
    path: Path
    scene: Scene
    profiles: dict[str, LoadedProfile]
    file_bounds: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]]
    """Local bounds (low, high corners, m) of every mesh file the scene uses, by its path as written."""
    document: YamlDocument | None = None
    """The scene file as read, to locate problems found after loading (`locate`)."""

    def locate(self, key_path: tuple) -> Location | None:
        """Where `key_path` (or its nearest ancestor) is written in the scene file."""
        return self.document.locate(key_path) if self.document is not None else None

    @property
    def profile_models(self) -> dict[str, Profile]:
        return {camera: loaded.profile for camera, loaded in self.profiles.items()}

    @property
    def profile_names(self) -> dict[str, str]:
        return {camera: loaded.name for camera, loaded in self.profiles.items()}


def default_profile_dirs(referencing_file: Path | None) -> list[Path]:
    """Where a profile *name* is looked up: next to the file, its ``profiles/`` sibling, ``./profiles``;
    only ``./profiles`` for a name given on the command line (`referencing_file` None)."""
    if referencing_file is None:
        return [Path.cwd() / "profiles"]
    here = referencing_file.resolve().parent
    return [here, here / "profiles", here.parent / "profiles", Path.cwd() / "profiles"]


def is_profile_name(reference: str) -> bool:
    """A bare name such as ``ptz_2mp_30x`` (looked up in the profile directories), not a path."""
    return bool(PROFILE_NAME.match(reference)) and not reference.endswith((".yaml", ".yml"))


def find_profile(
    reference: str,
    referencing_file: Path | None,
    profile_dirs: Sequence[Path] = (),
    location: Location | None = None,
    key_path: tuple = (),
) -> Path:
    """Resolve a profile reference: a path (relative to the referencing file; to the working
    directory for None, the command line) or a bare name."""
    if not is_profile_name(reference):
        base = Path.cwd() if referencing_file is None else referencing_file.parent
        candidate = (base / reference).resolve()
        if candidate.is_file():
            return candidate
        state = "is not a file" if candidate.exists() else "does not exist"
        raise ConfigError([Problem(key_path, f"refers to {reference!r}, but {candidate} {state}", location)])
    dirs = [*profile_dirs, *default_profile_dirs(referencing_file)]
    for directory in dirs:
        for suffix in (".yaml", ".yml"):
            candidate = directory / f"{reference}{suffix}"
            if candidate.is_file():
                return candidate.resolve()
    known = sorted({p.stem for d in dirs if d.is_dir() for p in d.glob("*.y*ml")})
    close = difflib.get_close_matches(reference, known, n=1, cutoff=0.6)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    searched = ", ".join(str(d) for d in dict.fromkeys(dirs) if d.is_dir())
    where = (
        f"which is not in {searched}{hint}"
        if searched
        else f"but none of the directories it is looked up in exists ({', '.join(map(str, dict.fromkeys(dirs)))}); "
        f"give the profile's path, or its directory with --profiles or $CAMGEN_PROFILE_PATH"
    )
    raise ConfigError([Problem(key_path, f"names profile {reference!r}, {where}", location)])


def _profile_document(path: Path, profile_dirs: Sequence[Path], chain: tuple[Path, ...]) -> YamlDocument:
    doc = load_yaml(path)
    parent_ref = doc.data.get("extends")
    if parent_ref is None:
        return _without_extends(doc)
    where = doc.locate(("extends",))
    if not isinstance(parent_ref, str) or not parent_ref:
        raise ConfigError(
            [Problem(("extends",), f"must name a profile or a profile file, got {show_value(parent_ref)}", where)]
        )
    parent_path = find_profile(parent_ref, path, profile_dirs, where, ("extends",))
    if parent_path in chain or parent_path == path.resolve():
        cycle = " → ".join(p.name for p in (*chain, path.resolve(), parent_path))
        raise ConfigError([Problem(("extends",), f"makes a cycle: {cycle}", where)])
    parent = _profile_document(parent_path, profile_dirs, (*chain, path.resolve()))
    if {"cameras", "scenes"} & set(parent.data):
        raise ConfigError(
            [Problem(("extends",), f"names {parent_path}, which is a scene or dataset, not a profile", where)]
        )
    return merge_documents(parent, _without_extends(doc))


def _without_extends(doc: YamlDocument) -> YamlDocument:
    return YamlDocument(
        data={k: v for k, v in doc.data.items() if k != "extends"},
        locations={k: v for k, v in doc.locations.items() if k[:1] != ("extends",)},
    )


def load_profile(path: str | Path, profile_dirs: Sequence[Path] = ()) -> LoadedProfile:
    """Load and validate a profile file, applying `extends:` (deep merge, the child wins)."""
    path = Path(path)
    doc = _profile_document(path, profile_dirs, ())
    return LoadedProfile(name=path.stem, path=path.resolve(), profile=validate(Profile, doc))


def load_scene(path: str | Path, profile_dirs: Sequence[Path] = ()) -> LoadedScene:
    """Load a scene, its cameras' profiles and mesh files, and check them against each other."""
    path = Path(path)
    doc = load_yaml(path)
    scene: Scene = validate(Scene, doc)
    problems: list[Problem] = []
    profiles: dict[str, LoadedProfile] = {}
    cache: dict[Path, LoadedProfile] = {}
    for i, camera in enumerate(scene.cameras):
        key = ("cameras", i, "profile")
        try:
            profile_path = find_profile(camera.profile, path, profile_dirs, doc.locate(key), key)
            if profile_path not in cache:
                cache[profile_path] = load_profile(profile_path, profile_dirs)
            profiles[camera.name] = cache[profile_path]
        except ConfigError as exc:
            problems += exc.problems
    file_meshes = [(("environment", "meshes", i, "path"), m) for i, m in enumerate(scene.environment.meshes)]
    file_meshes += [(("actors", i, "shape", "path"), a.shape) for i, a in enumerate(scene.actors)]
    file_bounds = {}
    characters = {i for i, actor in enumerate(scene.actors) if is_character(actor)}
    read: dict[str, object] = {}  # each character file parsed once
    for key, mesh in file_meshes:
        if isinstance(mesh, FileMesh) and mesh.path not in file_bounds:
            try:
                if key[0] == "actors" and key[1] in characters:
                    file_bounds[mesh.path] = _character_bounds(path.parent, mesh.path, read)
                else:
                    file_bounds[mesh.path] = _mesh_file_bounds(path.parent, mesh.path)
            except ConfigError as exc:
                problems.append(Problem(key, exc.problems[0].message, doc.locate(key)))
    for i in sorted(characters):
        if scene.actors[i].shape.path in file_bounds:
            problems += [
                Problem(p.path, p.message, doc.locate(p.path))
                for p in _character_problems(path.parent, scene.actors[i], ("actors", i, "shape", "animation"), read)
            ]
    problems += [Problem(key, message, doc.locate(key)) for key, message in _texture_file_problems(scene, path.parent)]
    if problems:
        raise ConfigError(problems)
    from camgen.motion.trajectory import vehicle_path_problems  # the motion package imports this one's models

    located = [
        Problem(p.path, p.message, doc.locate(p.path))
        for p in [*check_cameras(scene, {k: v.profile for k, v in profiles.items()}), *vehicle_path_problems(scene)]
    ]
    if located:
        raise ConfigError(located)
    warn_about(
        [
            Problem(p.path, p.message, doc.locate(p.path))
            for p in [*cameras_inside_solids(scene), *sky_light_problems(scene)]
        ]
    )
    return LoadedScene(
        name=path.stem, path=path.resolve(), scene=scene, profiles=profiles, file_bounds=file_bounds, document=doc
    )


def _texture_file_problems(scene: Scene, directory: Path) -> list[tuple[tuple, str]]:
    """(key path, message) of each file texture whose images cannot be used (`camgen.io.texture_images`)."""
    surfaces = [(("environment", "meshes", i), mesh) for i, mesh in enumerate(scene.environment.meshes)]
    surfaces += [(("actors", i, "shape"), actor.shape) for i, actor in enumerate(scene.actors)]
    problems = []
    for key, shape in surfaces:
        texture = getattr(getattr(shape, "material", None), "texture", None)
        if getattr(texture, "type", None) != "file":
            continue
        try:
            read_texture_images(directory, texture.base_color_file, texture.normal_file, texture.roughness_file)
        except TextureFileError as exc:
            problems.append(((*key, "material", "texture", exc.key), exc.message))
    return problems


def _mesh_file_bounds(directory: Path, reference: str) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Axis-aligned bounds of a mesh file in its own frame (trimesh reads glTF, OBJ, PLY, STL, …)."""
    import trimesh  # heavy import, only for scenes that use mesh files

    path = _readable(directory, reference, "a mesh file")
    try:
        loaded = trimesh.load(path, force="scene")
    except NotImplementedError as exc:  # trimesh's "file_type 'x' not supported"
        raise ConfigError(f"cannot be read as a mesh ({path}): {exc}; formats read: glTF, OBJ, PLY, STL, OFF") from None
    except OSError as exc:
        raise ConfigError(f"cannot be read as a mesh ({path}): {exc.strerror or exc}") from None
    except Exception as exc:  # a parser's internal error (an index out of bounds, a bad reshape): bad content
        detail = f"{type(exc).__name__}: {exc}"
        raise ConfigError(
            f"cannot be read as a mesh ({path}): the file is truncated or corrupt ({detail}); export it again"
        ) from None
    if loaded.bounds is None or not len(loaded.geometry):
        raise ConfigError(f"holds no geometry ({path}); give a mesh file with triangles")
    low, high = loaded.bounds
    return tuple(map(float, low)), tuple(map(float, high))


def _character_bounds(
    directory: Path, reference: str, read: dict
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Bounds of a glTF character in the actor's axes (x forward, z up), over its rest pose and every
    pose its animations take (`camgen.io.gltf`)."""
    character = _read_character(directory, reference, read)
    low, high = posed_bounds(character, [None, *character.clips])
    return tuple(map(float, low)), tuple(map(float, high))


def _read_character(directory: Path, reference: str, read: dict):
    if reference not in read:
        read[reference] = load_character(_readable(directory, reference, "a glTF 2.0 file"))
    return read[reference]


def _readable(directory: Path, reference: str, kind: str) -> Path:
    """The file a scene refers to, beside it, once it is known to exist and be readable."""
    path = directory / reference
    if not path.exists():
        raise ConfigError(f"refers to {reference!r}, but {path.resolve()} does not exist")
    problem = input_file_problem(path)
    if problem:
        raise ConfigError(f"refers to {reference!r}, but {path.resolve()} {problem}; give {kind}")
    return path


def _character_problems(directory: Path, actor, key: tuple, read: dict) -> list[Problem]:
    """Animation names the file lacks, and a clip that walks in place on a moving actor with no speed."""
    character = _read_character(directory, actor.shape.path, read)
    animation = actor.shape.animation
    problems = []
    for name in ("clip", "idle_clip"):
        wanted = getattr(animation, name) if animation is not None else None
        if wanted is not None and wanted not in [c.name for c in character.clips]:
            known = ", ".join(repr(c.name) for c in character.clips) or "none"
            problems.append(
                Problem((*key, name), f"names {wanted!r}, which {actor.shape.path} lacks (its animations: {known})")
            )
    if problems or (animation is not None and animation.clip_speed_m_s is not None):
        return problems
    walk = character.clip(animation.clip if animation is not None else None)
    moves = actor.random_walk is not None or (actor.path is not None and len(actor.path.waypoints_m) > 1)
    if walk is not None and walk.duration_s > 0 and moves:
        speed = clip_ground_speed_m_s(character, walk, actor.shape.scale)
        if speed < IN_PLACE_SPEED_M_S:
            problems.append(
                Problem(
                    (*key, "clip_speed_m_s"),
                    f"is needed: the animation {walk.name!r} of {actor.shape.path} walks in place (its body travels "
                    f"{speed:.3f} m/s), so one loop's length is unknown; give the walking speed the clip was animated "
                    "for (about 1.3 m/s for an adult's walk, Bohannon 1997)",
                )
            )
    return problems


def load_dataset(path: str | Path, profile_dirs: Sequence[Path] = ()) -> Dataset:
    """Load a dataset spec and check that every scene and profile it names exists (profile names are
    looked up in `profile_dirs`, then beside the dataset, as `find_profile` does)."""
    path = Path(path)
    doc = load_yaml(path)
    dataset: Dataset = validate(Dataset, doc)
    problems = []
    for i, scene in enumerate(dataset.scenes):
        if not (path.parent / scene).is_file():
            key = ("scenes", i)
            problems.append(
                Problem(
                    key, f"refers to {scene!r}, but {(path.parent / scene).resolve()} does not exist", doc.locate(key)
                )
            )
    for i, reference in enumerate(dataset.profiles):
        key = ("profiles", i)
        try:
            find_profile(reference, path, profile_dirs, doc.locate(key), key)
        except ConfigError as exc:
            problems += exc.problems
    if problems:
        raise ConfigError(problems)
    return dataset


def _scripted_program(settings) -> tuple[object, tuple[str, ...]]:
    """The program that names head positions and its key path: a follow's fallback, or the program."""
    program = settings.program
    if getattr(program, "type", None) == "follow":
        return program.fallback, ("program", "fallback")
    return program, ("program",)


def _ptz_positions(ptz) -> list[tuple[tuple, float | None, float | None, float | None]]:
    """(key path below ptz, pan, tilt, zoom) of every head position a camera's settings name."""
    positions: list[tuple[tuple, float | None, float | None, float | None]] = [
        (("pan_deg",), ptz.pan_deg, None, None),
        (("tilt_deg",), None, ptz.tilt_deg, None),
        (("zoom_x",), None, None, ptz.zoom_x),
    ]
    for i, preset in enumerate(ptz.presets):
        positions.append((("presets", i), preset.pan_deg, preset.tilt_deg, preset.zoom_x))
    program, prefix = _scripted_program(ptz)
    kind = getattr(program, "type", None)
    if kind == "scan":
        for j, pan in enumerate(program.pan_range_deg):
            positions.append(((*prefix, "pan_range_deg", j), pan, None, None))
        positions.append(((*prefix, "tilt_deg"), None, program.tilt_deg, None))
        positions.append(((*prefix, "zoom_x"), None, None, program.zoom_x))
    if kind == "keyframes":
        for j, key in enumerate(program.keys):
            positions.append(((*prefix, "keys", j), key.pan_deg, key.tilt_deg, key.zoom_x))
    return positions


@dataclass(frozen=True)
class HeadRanges:
    """Where a camera's (mechanical or virtual) head can point and how fast it may turn."""

    key: str
    """`ptz` or `eptz`: the scene key of the head's settings."""
    pan_deg: tuple[float, float] | None
    """None: endless pan."""
    pan_what: str
    tilt_deg: tuple[float, float]
    tilt_what: str
    zoom_max_x: float
    zoom_what: str
    pan_max_deg_s: float
    tilt_max_deg_s: float


def head_ranges(camera: Camera, profile: Profile) -> HeadRanges | None:
    """The ranges of the camera's PTZ head (profile and camera limits) or of its virtual PTZ (the
    sensor's field of view: the window centre stays on the sensor); None without either."""
    lens = profile.lens
    if camera.ptz is not None and profile.ptz is not None:
        head, ptz = profile.ptz, camera.ptz
        return HeadRanges(
            "ptz",
            None if head.pan_continuous else tuple(head.pan_range_deg),
            "the head's pan range",
            tuple(head.tilt_range_deg),
            "the head's tilt range",
            lens.zoom_max_x,
            f"the lens zooms {lens.focal_length_min_mm:g}–{lens.focal_length_max_mm:g} mm",
            min(head.pan_max_deg_s, ptz.pan_max_deg_s or math.inf),
            min(head.tilt_max_deg_s, ptz.tilt_max_deg_s or math.inf),
        )
    if camera.eptz is not None:
        eptz, sensor = camera.eptz, profile.sensor
        focal_length_mm = camera.focal_length_mm or lens.focal_length_min_mm
        half_pan = math.degrees(math.atan(sensor.width_mm / 2 / focal_length_mm))
        half_tilt = math.degrees(math.atan(sensor.height_mm / 2 / focal_length_mm))
        what = f"the sensor's field of view at {focal_length_mm:g} mm"
        return HeadRanges(
            "eptz",
            (-half_pan, half_pan),
            what,
            (-half_tilt, half_tilt),
            what,
            eptz.zoom_max_x,
            "eptz.zoom_max_x",
            eptz.pan_max_deg_s,
            eptz.tilt_max_deg_s,
        )
    return None


def _check_head_position(path: tuple, pan, tilt, zoom, ranges: HeadRanges) -> list[Problem]:
    """A position must lie within the head's pan and tilt ranges and its zoom range."""
    problems = []
    checks = [("zoom_x", zoom, 1.0, ranges.zoom_max_x, ranges.zoom_what)]
    if ranges.pan_deg is not None:
        checks.append(("pan_deg", pan, *ranges.pan_deg, ranges.pan_what))
    checks.append(("tilt_deg", tilt, *ranges.tilt_deg, ranges.tilt_what))
    for key, value, low, high, what in checks:
        if value is None or low - 1e-9 <= value <= high + 1e-9:
            continue
        where = path if path and path[-1] == key else (*path, key)
        problems.append(Problem(where, f"must lie in [{low:.4g}, {high:.4g}] ({what}), got {value:g}"))
    return problems


def _check_keyframe_speeds(path: tuple, program, ranges: HeadRanges) -> list[Problem]:
    """Consecutive keyframes must not ask for more pan or tilt speed than the head has."""
    problems = []
    for j in range(1, len(program.keys)):
        a, b = program.keys[j - 1], program.keys[j]
        span_s = b.time_s - a.time_s
        # an endless head turns the short way; a limited one cannot cross the ends of its range
        pan_delta = b.pan_deg - a.pan_deg
        if ranges.pan_deg is None:
            pan_delta = ((pan_delta + 180.0) % 360.0) - 180.0
        for axis, delta in (("pan", pan_delta), ("tilt", b.tilt_deg - a.tilt_deg)):
            limit = getattr(ranges, f"{axis}_max_deg_s")
            if abs(delta) / span_s > limit + 1e-9:
                problems.append(
                    Problem(
                        (*path, "keys", j),
                        f"asks for {abs(delta) / span_s:.4g} deg/s of {axis} from keys[{j - 1}] "
                        f"({abs(delta):g}° in {span_s:g} s), more than the {limit:g} deg/s the head may move; "
                        "move the keyframe later",
                    )
                )
    return problems


def _check_head(base: tuple, camera: Camera, profile: Profile) -> list[Problem]:
    """Every position and program of a camera's (mechanical or virtual) head against its ranges."""
    ranges = head_ranges(camera, profile)
    if ranges is None:
        return []
    settings = camera.head
    where = (*base, ranges.key)
    problems = []
    for path, pan, tilt, zoom in _ptz_positions(settings):
        problems += _check_head_position((*where, *path), pan, tilt, zoom, ranges)
    program, prefix = _scripted_program(settings)
    if getattr(program, "type", None) == "scan" and ranges.pan_deg is not None:
        start, end = program.pan_range_deg
        if start == end:
            problems.append(
                Problem(
                    (*where, *prefix, "pan_range_deg"),
                    f"must give two different angles on a head with a limited pan range, got [{start:g}, {end:g}]",
                )
            )
    if getattr(program, "type", None) == "keyframes":
        problems += _check_keyframe_speeds((*where, *prefix), program, ranges)
    return problems


def check_cameras(scene: Scene, profiles: dict[str, Profile]) -> list[Problem]:
    """Checks that need both a camera and its profile, and of where each camera stands; key paths are
    relative to the scene."""
    problems = cameras_behind_planes(scene)
    slowest = min(scene.cameras, key=lambda c: profiles[c.name].sensor.frame_rate_max_hz)
    limit_hz = profiles[slowest.name].sensor.frame_rate_max_hz
    if scene.fps > limit_hz:
        problems.append(
            Problem(
                ("fps",),
                f"must be ≤ {limit_hz:g} Hz, the frame rate limit of the sensor of camera "
                f"{slowest.name!r}, got {scene.fps:g}",
            )
        )
    for i, camera in enumerate(scene.cameras):
        profile = profiles[camera.name]
        lens, head = profile.lens, profile.ptz
        base = ("cameras", i)
        if profile.exposure.mode == "manual" and profile.exposure.exposure_time_s > 1 / scene.fps:
            problems.append(
                Problem(
                    (*base, "profile"),
                    f"sets a manual exposure of {profile.exposure.exposure_time_s:g} s, longer than the frame "
                    f"period 1/fps = {1 / scene.fps:g} s; shorten the exposure or lower fps",
                )
            )
        if camera.metering_region_frac is not None and profile.exposure.mode != "auto":
            problems.append(
                Problem(
                    (*base, "metering_region_frac"),
                    f"is set, but profile {camera.profile!r} exposes manually (exposure.mode: manual), so nothing "
                    "meters; drop it, or use a profile with exposure.mode: auto",
                )
            )
        if camera.ptz is not None and head is None:
            problems.append(
                Problem(
                    (*base, "ptz"),
                    f"is set, but profile {camera.profile!r} has no PTZ head; aim a fixed camera with "
                    "mount.yaw_deg and mount.pitch_deg",
                )
            )
        problems += _check_head(base, camera, profile)
        if camera.eptz is not None:
            sensor, output = profile.sensor, camera.eptz.output_size_px
            if head is not None:
                problems.append(
                    Problem(
                        (*base, "eptz"),
                        f"is for fixed cameras, but profile {camera.profile!r} has a PTZ head; use ptz instead",
                    )
                )
            pixel_format = profile.codec.pixel_format
            if pixel_format != "yuv444p" and (output[0] % 2 or (output[1] % 2 and pixel_format == "yuv420p")):
                problems.append(
                    Problem(
                        (*base, "eptz", "output_size_px"),
                        f"must be even for the profile's {pixel_format} chroma subsampling, got "
                        f"{output[0]}×{output[1]}; use e.g. {output[0] + output[0] % 2}×{output[1] + output[1] % 2}",
                    )
                )
            if output[0] > sensor.width_px or output[1] > sensor.height_px:
                problems.append(
                    Problem(
                        (*base, "eptz", "output_size_px"),
                        f"must fit the {sensor.width_px}×{sensor.height_px} sensor, got {output[0]}×{output[1]}; "
                        "the stream is a crop of the sensor, scaled down",
                    )
                )
        if camera.ptz is not None and head is not None:
            ptz = camera.ptz
            for axis in ("pan", "tilt"):
                limit = getattr(ptz, f"{axis}_max_deg_s")
                head_max = getattr(head, f"{axis}_max_deg_s")
                if limit is not None and limit > head_max:
                    problems.append(
                        Problem(
                            (*base, "ptz", f"{axis}_max_deg_s"),
                            f"must be ≤ the head's maximum {head_max:g} deg/s, got {limit:g}",
                        )
                    )
        if camera.focal_length_mm is not None:
            if head is not None:
                problems.append(
                    Problem(
                        (*base, "focal_length_mm"),
                        "is for varifocal fixed cameras; a PTZ camera zooms with ptz.zoom_x",
                    )
                )
            elif not lens.focal_length_min_mm - 1e-9 <= camera.focal_length_mm <= lens.focal_length_max_mm + 1e-9:
                problems.append(
                    Problem(
                        (*base, "focal_length_mm"),
                        f"must lie in the lens range [{lens.focal_length_min_mm:g}, {lens.focal_length_max_mm:g}] mm, "
                        f"got {camera.focal_length_mm:g}",
                    )
                )
        focus = camera.focus_distance_m
        if focus is not None and focus < lens.min_focus_distance_m:
            problems.append(
                Problem(
                    (*base, "focus_distance_m"),
                    f"must be ≥ the lens' min_focus_distance_m ({lens.min_focus_distance_m:g} m), got {focus:g}",
                )
            )
    return problems
