"""A camgen scene as a pyrender scene graph, in physical units, with an instance id on every node.

Units (DESIGN.md "camgen.render"): pyrender's lit shader is a Cook–Torrance BRDF whose Lambertian
term is ρ/π; with light intensities in lux (directional) and candela (point, spot) its output is
luminance in cd/m² once gamma and clamping are removed (`camgen.render.renderer`). So:

- sun: a directional light of ``illuminance_lux`` (lux on a surface facing it);
- point and spot: ``intensity_cd`` candela, falling off as 1/d²;
- headlamps: a lit vehicle's low beams, a spot light moving with it whose intensity is the table of
  `camgen.vehicles.headlamps` (`Headlamp`, `add_headlamps`);
- ambient: a uniform sky of illuminance E lux lights a Lambertian surface of reflectance ρ to
  L = ρ·E/π cd/m²; pyrender adds base_colour × ambient_light, so ambient_light = E/π;
- emission: ``emission_cd_m2`` is added as it is (white);
- sky: pixels that hit no geometry get ``sky_luminance_cd_m2`` (the renderer's clear value), or, for a
  CIE sky, the luminance and colour of the sky in their direction (`camgen.world.sky`);
- fog: the renderer blends each radiance pixel towards the horizon sky by Koschmieder's law on its
  distance (`camgen.world.fog`), drawing the depth it needs in the same draw.

Instance ids: actors take 1…A in scene order (so an actor's id is its track id), environment meshes
A+1…A+M, then props, then road markings, then kerbs (so a marking or kerb added to a scene changes no
other id); 0 is the background. Ids are 32-bit, so any realistic number of instances fits.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import timedelta
from functools import lru_cache
from pathlib import Path
from typing import Literal

import numpy as np
import trimesh

from camgen.actors import Crowd, PersonRig, person_rig, rider_rig
from camgen.actors.character import CharacterRig, character_rig
from camgen.config.kerbs import Kerb, kerb_names
from camgen.config.markings import marking_names
from camgen.config.placement import is_level_plane, largest_level_plane, placement
from camgen.config.scene import (
    MAX_LIGHTS,
    Actor,
    AmbientLight,
    BoxMesh,
    CheckerboardMesh,
    CylinderMesh,
    FileMesh,
    LampLight,
    Material,
    PlaneMesh,
    PointLight,
    Scene,
    Site,
    SphereMesh,
    SpotLight,
    SunLight,
    actor_shape,
    is_character,
    is_procedural_person,
    is_procedural_vehicle,
)
from camgen.errors import ConfigError
from camgen.io.gltf import Character, load_character
from camgen.io.ies import read_ies
from camgen.io.texture_images import TextureFileError, read_texture_images
from camgen.motion.pose import T_world_from_cam, rot_z
from camgen.motion.trajectory import Route, actor_routes
from camgen.props import PropModel, placed_props, prop_names
from camgen.props.sway import SWAYING_TYPES, PropSway, bendable, prop_sway, wind_gusts
from camgen.render.gl import pyrender
from camgen.render.mipmaps import MipmappedTexture
from camgen.vehicles import LAMP_COLOUR_RGB, LAMP_LUMINANCE_CD_M2, VehicleRig, plate_texture, vehicle_rigs
from camgen.vehicles.headlamps import (
    BEAM_CONE_DEG,
    BEAM_VISIBLE_FRACTION,
    daylight_horizontal_lux,
    lit_at,
    low_beam_table,
    peak_road_illuminance_lux,
)
from camgen.vehicles.sign import display_luminance_cd_m2
from camgen.world.ies import flux_lm as ies_flux_lm
from camgen.world.ies import grid_intensity_cd, intensity_grid_cd
from camgen.world.kerbs import kerb_geometry
from camgen.world.markings import PAINT_ROUGHNESS, PaintMesh, marking_paint, wet_reflectance
from camgen.world.night import SPOT_FULL_INTENSITY_FRACTION, peak_intensity_cd
from camgen.world.rain import WET_ALBEDO_FACTOR, WET_ROUGHNESS_FACTOR, ground_is_wet
from camgen.world.site import SiteDaylight, daylight_change, site_daylight
from camgen.world.sky import LUMINANCE_WEIGHTS
from camgen.world.textures import (
    TYPICAL_ALBEDO_RGB,
    FileSurfaceMaps,
    encode_normal8,
    encode_srgb8,
    file_surface_maps,
    kerb_surface_maps,
    surface_maps,
)

from OpenGL.GL import GL_REPEAT  # isort: skip — after camgen.render.gl, which selects the EGL platform

CYLINDER_SECTIONS = 48
SPHERE_SUBDIVISIONS = 3


@dataclass(frozen=True)
class Instance:
    instance_id: int
    name: str
    kind: Literal["actor", "environment"]


@dataclass(frozen=True)
class FarGround:
    """The scene's ground continued to the horizon: a level, uniform plane of the ground plane's material
    that the renderer draws where a ray goes down past every mesh (`camgen.render.renderer.
    far_ground_radiance`), so that a camera looking over the edge of the modelled site sees ground, not
    the sky under the horizon.

    It is a backdrop, not geometry: no shadows, no instance id, depth +inf (like the sky). Its material is
    the ground plane's mean: reflectance (a texture's typical albedo: far away, the mipmaps average the
    texture to it), roughness and metalness (a texture's maps' means), wet as the plane is; it is shaded
    per pixel by the renderer's own BRDF (`linear_mesh.frag`: Lambert plus GGX specular with Schlick's
    Fresnel, whose share grows towards grazing view) under the sun lights, plus the ambient term, so it
    meets the plane's far edge without a step in brightness."""

    height_m: float
    reflectance_rgb: tuple[float, float, float]
    roughness: float = 1.0
    metallic: float = 0.0


class OrderedScene(pyrender.Scene):
    """pyrender's Scene, listing its meshes and lights in the order they were added.

    pyrender keeps nodes in sets, which iterate in the order of the nodes' hashes, their memory addresses:
    a different order in every run. The shader sums the lights' contributions in the order pyrender binds
    them (`light_nodes`), so a frame lit by several lights differed in its last bits from run to run (the
    night street's street lamps: 1e-5 of the radiance at 11 % of its pixels, enough to flip an 8-bit code
    now and then), and the same seed must give the same bytes. Lists in insertion order fix it.

    It also keeps what pyrender works out again at each call: each list in order until a node is added or
    removed, and each node's world pose (`get_pose`: pyrender walks the node's path to the root and multiplies
    its matrices) until the node, or a node with children, is set another pose (`set_pose`), or a node is
    added or removed. A draw asks for the same poses tens of thousands of times per frame (sorting, culling,
    the shadow maps and the lit pass each ask for every node's) and the lists for every lit primitive
    (pyrender's lighting). Everything that moves a node goes through `set_pose` (pyrender's own `set_pose`
    stores the matrix it is given; nothing here changes a node's matrix in place)."""

    def __init__(self, *args, **kwargs):
        self._added: dict = {}
        self.node_changes = 0
        """How many times a node was added or removed (`camgen.render.renderer` skips pyrender's context update
        while it holds)."""
        self._orders: dict[str, list] = {}
        """Each ordered list (by property name) since the last node was added or removed."""
        self._poses: dict = {}
        """Each node's world pose asked for since it, or any node with children, was last set another pose."""
        super().__init__(*args, **kwargs)

    def add_node(self, node, parent_node=None):
        self._added.setdefault(node, len(self._added))
        self.node_changes += 1
        self._orders.clear()
        self._poses.clear()
        return super().add_node(node, parent_node)

    def remove_node(self, node):
        self.node_changes += 1
        self._orders.clear()
        self._poses.clear()
        return super().remove_node(node)

    def clear(self):
        self.node_changes += 1
        self._orders.clear()
        self._poses.clear()
        return super().clear()

    def set_pose(self, node, pose):
        super().set_pose(node, pose)
        if node.children:  # its descendants' world poses move with it
            self._poses.clear()
        else:
            self._poses.pop(node, None)

    def get_pose(self, node):
        pose = self._poses.get(node)
        if pose is None:
            pose = self._poses[node] = super().get_pose(node)
        return pose.copy()  # pyrender hands out a new array; a caller may write into it

    def _in_order(self, nodes) -> list:
        return sorted(nodes, key=self._added.__getitem__)

    def _kept_order(self, name: str, nodes) -> list:
        """`_in_order(nodes)` kept under `name` until a node is added or removed; a new list each call."""
        kept = self._orders.get(name)
        if kept is None:
            kept = self._orders[name] = self._in_order(nodes)
        return list(kept)

    @property
    def mesh_nodes(self):
        return self._kept_order("mesh_nodes", self._mesh_nodes)

    @property
    def point_light_nodes(self):
        return self._kept_order("point_light_nodes", self._point_light_nodes)

    @property
    def spot_light_nodes(self):
        return self._kept_order("spot_light_nodes", self._spot_light_nodes)

    @property
    def directional_light_nodes(self):
        return self._kept_order("directional_light_nodes", self._directional_light_nodes)

    @property
    def light_nodes(self):
        return self._kept_order(
            "light_nodes", self._point_light_nodes | self._spot_light_nodes | self._directional_light_nodes
        )


FAR_GROUND_MIN_AREA_M2 = 100.0
"""The smallest level plane taken for the site's ground (10 × 10 m); a smaller one is a prop (a mat, a board)."""


def far_ground(scene: Scene, resolve_path: Callable[[str], Path] | None = None) -> FarGround | None:
    """The largest level plane of the environment, facing up and at least `FAR_GROUND_MIN_AREA_M2`, as the
    ground that continues to the horizon; None when the scene has none or `environment.ground_to_horizon`
    is off. A file texture's files are found with `resolve_path`."""
    if not scene.environment.ground_to_horizon:
        return None
    ground = largest_level_plane(scene.environment.meshes, FAR_GROUND_MIN_AREA_M2)
    if ground is None:
        return None
    material, texture = ground.material, ground.material.texture
    rgb, roughness, metallic = material.color_rgb, material.roughness, material.metallic
    if texture is not None and texture.type == "file":  # the images' means, as `_textured` draws them
        maps = file_texture_maps(material, resolve_path)
        rgb = tuple(maps.reflectance.reshape(-1, 3).mean(axis=0))
        if maps.roughness is not None:
            roughness = float(np.mean(maps.roughness))
    elif texture is not None:  # `_textured` takes roughness and metalness from the texture's maps
        if "color_rgb" not in material.model_fields_set:
            rgb = TYPICAL_ALBEDO_RGB[texture.type]
        maps = surface_maps(texture.type, texture.seed, texture.tile_m)
        roughness, metallic = float(np.mean(maps.roughness)), float(np.mean(maps.metallic))
    if ground_is_wet(scene.environment):
        rgb = tuple(WET_ALBEDO_FACTOR * c for c in rgb)
        roughness *= WET_ROUGHNESS_FACTOR
    return FarGround(float(ground.position_m[2]), tuple(float(c) for c in rgb), roughness, metallic)


@dataclass
class SwayingProp:
    """A tree or bush that sways in the scene's wind (`camgen.props.sway`): its node stays an environment
    node (its instance id), but it is drawn with the actors, never into a kept static background."""

    node: pyrender.Node
    sway: PropSway
    rest_vertices_m: np.ndarray
    """(V, 3) in the prop's frame, at rest."""
    rest_normals: np.ndarray
    placed_at_s: float | None = None
    """The time its vertices were last bent to."""

    def place(self, time_s: float, scene: pyrender.Scene, deformed: set) -> bool:
        """Bend the prop's vertices to `time_s` (nothing when they already are); whether they were bent."""
        if self.placed_at_s == time_s:
            return False
        primitive = self.node.mesh.primitives[0]
        primitive.positions, primitive.normals = self.sway.deformed(self.rest_vertices_m, self.rest_normals, time_s)
        deformed.add(primitive)
        self.node.mesh._bounds = None  # pyrender caches a mesh's bounds, and the scene's until a node moves
        scene.set_pose(self.node, self.node.matrix)
        self.placed_at_s = time_s
        return True


@dataclass
class SceneGraph:
    """A pyrender scene built from a camgen scene; actor nodes are moved with `place_actors`."""

    scene: pyrender.Scene
    actors: list[Actor]
    actor_nodes: list[pyrender.Node]
    environment_nodes: list[pyrender.Node]
    instance_ids: dict[pyrender.Node, int]
    instances: tuple[Instance, ...]
    sky_luminance_cd_m2: float
    shadows: bool
    sky: str = "uniform"
    """"uniform", or a CIE sky type of `camgen.world.sky` (then `sky_luminance_cd_m2` is the zenith's)."""
    sun_direction: np.ndarray | None = None
    """Unit vector towards the (first) sun light, world; None without one."""
    fog_visibility_m: float | None = None
    """Visual range of the scene's fog (`camgen.world.fog`), m; None in clear air."""
    rain_rate_mm_h: float | None = None
    """Rain rate of the scene's rain (`camgen.world.rain`), mm/h; None when dry."""
    rain_seed: int = 0
    """Seed of the rain's drops."""
    far_ground: FarGround | None = None
    """The ground continued beyond the scene's ground plane to the horizon (`far_ground`); None without one."""
    daylight: SiteDaylightTrack | None = None
    """The site's daylight through the sequence, when it changes (`set_daylight`); None: held."""
    actor_local_poses: list[np.ndarray] = field(default_factory=list)
    actor_routes: list[Route] = field(default_factory=list)
    """Each actor's route (its path, or its random walk resolved once), in the order of `actors`."""
    people: list[PersonRig | CharacterRig | None] = field(default_factory=list)
    """Each actor's procedural person or glTF character (its mesh is posed in world coordinates), or None."""
    deformed: set = field(default_factory=set)
    """Primitives whose vertices changed since the renderer last uploaded them."""
    crowd: Crowd = field(default_factory=lambda: Crowd([]))
    """The people, skinned together."""
    vehicles: list[VehicleRig | None] = field(default_factory=list)
    """Each actor's procedural vehicle (its mesh posed in world coordinates), or None."""
    headlamps: list[Headlamp] = field(default_factory=list)
    """The spot lights of the vehicles' low beams (`add_headlamps`), moved and switched with them."""
    prop_nir: dict[int, np.ndarray] = field(default_factory=dict)
    """id() of each prop's or road marking's primitive → its vertices' reflectance at 850 nm (`camgen.render.nir`)."""
    swaying: list[SwayingProp] = field(default_factory=list)
    """The props that sway in the scene's wind (`environment.wind`), moved with the actors; empty when calm."""
    source: tuple[Scene, Callable[[str], Path] | None] | None = None
    """The scene it was built from and its path resolver (a night-mode camera builds its NIR graph
    from them: `camgen.render.nir`)."""
    placed_time_s: float | None = None
    """The time the actors were last placed at and every swaying prop bent to (`place_actors` places them again
    only for another); None when the props are bent to other times (`bend_prop`)."""
    _actors_placed_s: float | None = field(init=False, default=None, repr=False)
    """The time the actors were last placed at."""
    look_versions: list[int] = field(init=False, default_factory=list)
    """Per moving node (in the order of `moving_nodes`), a count that `place_actors` raises whenever it may have
    changed what the node draws (its pose, vertices, normals or lamps), and only then: equal counts at two times
    mean the same look, so a caller may keep what it derived from it (`camgen.render.sequence`: the blur test's
    vertices, the kept frame's looks); unequal counts need not mean another look (a person's, a rider's or a shape's
    count rises at every new time, a parked car's never). Nothing else moves a node of the graph."""

    def __post_init__(self):
        self.look_versions = [0] * (len(self.actor_nodes) + len(self.swaying))

    @property
    def moving_nodes(self) -> list[pyrender.Node]:
        """Every node whose look changes with time: the actors', then the swaying props'."""
        return self.actor_nodes + [prop.node for prop in self.swaying] if self.swaying else self.actor_nodes

    @property
    def still_nodes(self) -> list[pyrender.Node]:
        """The environment nodes that never change (a kept static background holds these only)."""
        if not self.swaying:
            return self.environment_nodes
        swaying = {id(prop.node) for prop in self.swaying}
        return [node for node in self.environment_nodes if id(node) not in swaying]

    def rig(self, index: int) -> PersonRig | CharacterRig | VehicleRig | None:
        """Actor `index`'s procedural person, glTF character or procedural vehicle, or None (a shape)."""
        person = self.people[index] if self.people else None
        return person if person is not None else (self.vehicles[index] if self.vehicles else None)

    def set_daylight(self, time_s: float) -> None:
        """Light the scene as the site's sky does `time_s` after its first frame (sun lights' direction
        and illuminance, the ambient light and the sky); nothing when the daylight is held."""
        if self.daylight is None:
            return
        track = self.daylight
        now = track.at(time_s)
        towards_sun = _towards(now.azimuth_deg, now.elevation_deg)
        for node, illuminance_lux in track.suns:
            node.light.intensity = illuminance_lux * track.ratio(
                now.sun_illuminance_lux, track.start.sun_illuminance_lux
            )
            self.scene.set_pose(node, _look_along(-towards_sun))
        sky_ratio = track.ratio(now.sky_illuminance_lux, track.start.sky_illuminance_lux)
        self.scene.ambient_light = np.full(3, track.ambient_lux * sky_ratio / math.pi)
        self.sky_luminance_cd_m2 = track.sky_luminance_cd_m2 * track.ratio(
            now.zenith_luminance_cd_m2, track.start.zenith_luminance_cd_m2
        )
        self.sun_direction = towards_sun if track.suns else self.sun_direction

    def place_actors(self, time_s: float, *, props: bool = True) -> None:
        """Move every actor to where its route puts it at `time_s` (and pose every person), and bend every
        swaying prop to its shape in the wind then (`props` False: leave the props as they are, as the blur
        test does where it can bound their motion without them); nothing when they stand there already (a
        still frame asks for its frame time four or five times: rectangles, blur groups, draws, the geometric
        pass)."""
        if time_s == self.placed_time_s:
            return
        self.placed_time_s = self._actors_placed_s = time_s
        vehicles = self.vehicles or [None] * len(self.actor_nodes)
        versions = self.look_versions
        for k, (route, node, local, rig, vehicle) in enumerate(
            zip(self.actor_routes, self.actor_nodes, self.actor_local_poses, self.people, vehicles, strict=True)
        ):
            if rig is None and vehicle is None:
                self.scene.set_pose(node, actor_pose(route, time_s) @ local)
                versions[k] += 1
            elif vehicle is not None and vehicle.place(time_s):
                _pose_vehicle_mesh(node, vehicle, self.deformed, sign_luminance_cd_m2(self.scene, vehicle))
                self.scene.set_pose(node, np.eye(4))
                versions[k] += 1
            elif vehicle is not None and self.daylight is not None and vehicle.sign_centre_m is not None:
                _light_display(node, vehicle, sign_luminance_cd_m2(self.scene, vehicle))  # a standing bus at dusk
                versions[k] += 1
        for headlamp in self.headlamps:
            headlamp.place(self.scene, vehicles[headlamp.actor_index], time_s)
        self.crowd.place(time_s)
        for k, (node, rig) in enumerate(zip(self.actor_nodes, self.people, strict=True)):
            if rig is None:
                continue
            versions[k] += 1
            if isinstance(rig, CharacterRig):
                rig.place(time_s)
            for primitive, part in zip(node.mesh.primitives, getattr(rig, "parts", [slice(None)]), strict=True):
                primitive.positions = rig.vertices_m[part]
                primitive.normals = rig.normals[part]
                self.deformed.add(primitive)
            node.mesh._bounds = None  # pyrender caches a mesh's bounds, and the scene's bounds until
            self.scene.set_pose(node, np.eye(4))  # a node moves: the identity pose stands for "moved"
        if props:
            for index in range(len(self.swaying)):
                self.bend_prop(index, time_s)
        self._held_time()

    def bend_prop(self, index: int, time_s: float) -> None:
        """Bend swaying prop `index` (of `swaying`) to its shape at `time_s`, raising its look version when it
        changed; the actors stay where they are."""
        if self.swaying[index].place(time_s, self.scene, self.deformed):
            self.look_versions[len(self.actor_nodes) + index] += 1
            self._held_time()

    def _held_time(self) -> None:
        """`placed_time_s`: the actors' time where every swaying prop is bent to it too, else None."""
        held = all(prop.placed_at_s == self._actors_placed_s for prop in self.swaying)
        self.placed_time_s = self._actors_placed_s if held else None


def instance_table(scene: Scene) -> tuple[Instance, ...]:
    """Every instance id the render assigns: actors 1…A in scene order, then environment meshes, then props,
    then road markings, then kerbs."""
    named = (
        [(actor.name, "actor") for actor in scene.actors]
        + [(m.name, "environment") for m in scene.environment.meshes]
        + [(name, "environment") for name in prop_names(scene.environment)]
        + [(name, "environment") for name in marking_names(scene.environment.markings)]
        + [(name, "environment") for name in kerb_names(scene.environment.kerbs)]
    )
    return tuple(Instance(i, name, kind) for i, (name, kind) in enumerate(named, start=1))


def actor_pose(route: Route, time_s: float) -> np.ndarray:
    """T_world_from_actor at `time_s`: on the ground where its route puts it, x along its heading."""
    xy, heading = route.at(time_s)
    return T_world_from_cam((float(xy[0]), float(xy[1]), 0.0), rot_z(float(heading)))


def _material(material: Material, color_rgb=None) -> pyrender.MetallicRoughnessMaterial:
    rgb = material.color_rgb if color_rgb is None else color_rgb
    return pyrender.MetallicRoughnessMaterial(
        baseColorFactor=(*rgb, 1.0),
        metallicFactor=material.metallic,
        roughnessFactor=material.roughness,
        emissiveFactor=(material.emission_cd_m2,) * 3,
        doubleSided=False,
    )


def _checkerboard(shape: CheckerboardMesh) -> list[tuple[trimesh.Trimesh, tuple[float, float, float]]]:
    """Light and dark quads tiling the board and its margin in one plane (no overlap, no z-fighting)."""
    nx, ny = shape.squares
    size, border = shape.square_size_m, shape.border_width_m
    xs = (np.arange(nx + 1) - nx / 2) * size
    ys = (np.arange(ny + 1) - ny / 2) * size
    quads: dict[bool, list[tuple[float, float, float, float]]] = {True: [], False: []}
    for i in range(nx):
        for j in range(ny):
            quads[(i + j) % 2 == 0].append((xs[i], ys[j], xs[i + 1], ys[j + 1]))
    if border > 0:
        x0, x1, y0, y1 = xs[0] - border, xs[-1] + border, ys[0] - border, ys[-1] + border
        quads[False] += [
            (x0, y0, x1, ys[0]),
            (x0, ys[-1], x1, y1),
            (x0, ys[0], xs[0], ys[-1]),
            (xs[-1], ys[0], x1, ys[-1]),
        ]
    parts = []
    for dark, colour in ((True, shape.dark_color_rgb), (False, shape.material.color_rgb)):
        vertices, faces = [], []
        for k, (a0, b0, a1, b1) in enumerate(quads[dark]):
            vertices += [(a0, b0, 0.0), (a1, b0, 0.0), (a1, b1, 0.0), (a0, b1, 0.0)]
            faces += [(4 * k, 4 * k + 1, 4 * k + 2), (4 * k, 4 * k + 2, 4 * k + 3)]
        parts.append((trimesh.Trimesh(np.array(vertices), np.array(faces), process=False), colour))
    return parts


def _plane(size_m: tuple[float, float]) -> trimesh.Trimesh:
    hx, hy = size_m[0] / 2, size_m[1] / 2
    vertices = np.array([(-hx, -hy, 0.0), (hx, -hy, 0.0), (hx, hy, 0.0), (-hx, hy, 0.0)])
    return trimesh.Trimesh(vertices, np.array([(0, 1, 2), (0, 2, 3)]), process=False)


def _box_faces(size_m) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(positions (24, 3), normals (24, 3), texture coordinates in metres (24, 2), faces (12, 3)) of a
    box centred on the origin: each face its own four vertices, its texture's v along the face's second
    in-plane axis (up the wall on the vertical faces) and u along ± the first, so that (u, v, outward
    normal) is right-handed: no face shows its texture mirrored, and a normal map's +v (the shader's
    bitangent, normal × tangent: `linear_mesh.frag` get_normal) is up the image on every face."""
    half = np.asarray(size_m, dtype=np.float64) / 2
    positions, normals, uvs, faces = [], [], [], []
    # (normal axis, sign, u axis, v axis): v is z on the four walls.
    for axis, sign, u_axis, v_axis in (
        (0, 1, 1, 2),
        (0, -1, 1, 2),
        (1, 1, 0, 2),
        (1, -1, 0, 2),
        (2, 1, 0, 1),
        (2, -1, 0, 1),
    ):
        base = len(positions)
        n = np.zeros(3)
        n[axis] = sign
        u_sign = float(np.cross(np.eye(3)[u_axis], np.eye(3)[v_axis]) @ n)
        for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            p = np.zeros(3)
            p[axis], p[u_axis], p[v_axis] = sign * half[axis], du * half[u_axis], dv * half[v_axis]
            positions.append(p)
            normals.append(n)
            uvs.append((u_sign * p[u_axis] + half[u_axis], p[v_axis] + half[v_axis]))
        # Counter-clockwise seen from outside.
        outward = np.cross(positions[base + 1] - positions[base], positions[base + 2] - positions[base])
        order = [(0, 1, 2), (0, 2, 3)] if outward @ normals[base] > 0 else [(0, 2, 1), (0, 3, 2)]
        faces += [(base + a, base + b, base + c) for a, b, c in order]
    return np.array(positions), np.array(normals), np.array(uvs), np.array(faces)


def _textured(shape, resolve_path: Callable[[str], Path] | None) -> pyrender.Mesh:
    """A plane or a box with its material's texture, procedural (`camgen.world.textures`) or from files
    (`FileTexture`): base colour (sRGB-encoded as glTF stores it), roughness and metallic, and a normal
    map where the texture has one, repeated every tile, mipmapped and filtered trilinearly.

    A normal map holds (u, v, out) components of the surface's frame; the shader's tangent frame is
    ∂position/∂s from screen-space derivatives and normal × tangent (`linear_mesh.frag` get_normal; exact
    on a flat face, where the texture coordinates are an affine function of position), which is (u, v)
    because every face's (u, v, normal) is right-handed (`_box_faces`)."""
    material, texture = shape.material, shape.material.texture
    if isinstance(shape, PlaneMesh):
        plane = _plane(shape.size_m)
        positions, faces = np.asarray(plane.vertices), np.asarray(plane.faces)
        normals = np.tile((0.0, 0.0, 1.0), (len(positions), 1))
        uv_m = positions[:, :2] + np.array(shape.size_m) / 2
    else:
        positions, normals, uv_m, faces = _box_faces(shape.size_m)
    sampler = pyrender.Sampler(wrapS=GL_REPEAT, wrapT=GL_REPEAT)
    metallic_factor = roughness_factor = 1.0
    if texture.type == "file":
        maps = file_texture_maps(material, resolve_path)
        base_linear, roughness, metallic, normal = maps.reflectance, maps.roughness, None, maps.normal
        (tile_w_m, tile_h_m), top_at_v0 = maps.tile_m, False  # an image's row 0 is its top: the tile's +v edge
        if roughness is None:
            roughness_factor = material.roughness
        metallic_factor = material.metallic
    else:
        maps = surface_maps(texture.type, texture.seed, texture.tile_m)
        mean_rgb = material.color_rgb if "color_rgb" in material.model_fields_set else TYPICAL_ALBEDO_RGB[texture.type]
        base_linear = maps.albedo * np.asarray(mean_rgb, dtype=np.float32)
        roughness, metallic, normal = maps.roughness, maps.metallic, maps.normal
        tile_w_m = tile_h_m = maps.tile_m
        top_at_v0 = True  # a procedural tile's row 0 is its v = 0 edge
    pbr = _tiled_material(
        base_linear, roughness, metallic, normal, sampler, metallic_factor, roughness_factor, material.emission_cd_m2
    )
    # pyrender uploads the image flipped, so OpenGL's t = 1 is its row 0.
    t = 1.0 - uv_m[:, 1] / tile_h_m if top_at_v0 else uv_m[:, 1] / tile_h_m
    texcoords = np.column_stack([uv_m[:, 0] / tile_w_m, t])
    primitive = pyrender.Primitive(
        positions=positions, normals=normals, texcoord_0=texcoords, indices=faces, material=pbr
    )
    return pyrender.Mesh(primitives=[primitive])


def _tiled_material(
    base_linear, roughness, metallic, normal, sampler, metallic_factor, roughness_factor, emission_cd_m2
) -> pyrender.MetallicRoughnessMaterial:
    """A material of texture maps repeated every tile: base colour (linear (H, W, 3), stored sRGB-encoded as
    glTF does), roughness and metallic ((H, W) or None) packed as glTF's metallic-roughness texture, a normal map
    ((H, W, 3) unit (u, v, out) or None), each mipmapped and filtered trilinearly."""
    base = encode_srgb8(base_linear)
    metallic_roughness = None
    if roughness is not None:
        # glTF's metallic-roughness texture: roughness in G, metallic in B, each scaled by its factor.
        mr = np.zeros((*roughness.shape, 3), dtype=np.uint8)
        mr[..., 1] = np.round(np.clip(roughness, 0, 1) * 255)
        mr[..., 2] = 255 if metallic is None else np.round(np.clip(metallic, 0, 1) * 255)
        metallic_roughness = MipmappedTexture(srgb=False, source=mr, source_channels="RGB", sampler=sampler)
    return pyrender.MetallicRoughnessMaterial(
        baseColorFactor=(1.0, 1.0, 1.0, 1.0),
        baseColorTexture=MipmappedTexture(srgb=True, source=base, source_channels="RGB", sampler=sampler),
        metallicFactor=metallic_factor,
        roughnessFactor=roughness_factor,
        metallicRoughnessTexture=metallic_roughness,
        normalTexture=(
            None
            if normal is None
            else MipmappedTexture(srgb=False, source=encode_normal8(normal), source_channels="RGB", sampler=sampler)
        ),
        emissiveFactor=(emission_cd_m2,) * 3,
        doubleSided=False,
    )


def file_texture_maps(material: Material, resolve_path: Callable[[str], Path] | None) -> FileSurfaceMaps:
    """The maps of a material's file texture, its colour the material's `color_rgb` when given (else the
    image's own); a ConfigError naming the texture's key and what is wrong with the file."""
    texture = material.texture
    if resolve_path is None:
        raise ConfigError(f"texture file {texture.base_color_file!r} needs the scene's directory to be found")
    files = [
        None if name is None else resolve_path(name)
        for name in (texture.base_color_file, texture.normal_file, texture.roughness_file)
    ]
    stamps = tuple(None if path is None or not path.exists() else path.stat().st_mtime_ns for path in files)
    mean_rgb = tuple(material.color_rgb) if "color_rgb" in material.model_fields_set else None
    return _file_texture_maps(*files, texture.tile_m, mean_rgb, stamps)


@lru_cache(maxsize=8)
def _file_texture_maps(base, normal, roughness, tile_m, mean_rgb, stamps) -> FileSurfaceMaps:
    """`file_texture_maps`, once per set of files (and their modification times) in a process."""
    try:
        images = read_texture_images(Path(), *(None if f is None else str(f) for f in (base, normal, roughness)))
    except TextureFileError as exc:
        raise ConfigError(f"material.texture.{exc.key} {exc.message}") from None
    return file_surface_maps(
        images.base_color, tile_m, normal_packed=images.normal, roughness=images.roughness, mean_rgb=mean_rgb
    )


def build_mesh(shape, resolve_path: Callable[[str], Path] | None = None) -> pyrender.Mesh:
    """A pyrender mesh in the shape's own frame (its placement goes on the node)."""
    if isinstance(shape, PlaneMesh | BoxMesh) and shape.material.texture is not None:
        return _textured(shape, resolve_path)
    material = _material(shape.material)
    if isinstance(shape, BoxMesh):
        return pyrender.Mesh.from_trimesh(trimesh.creation.box(extents=shape.size_m), material=material, smooth=False)
    if isinstance(shape, CylinderMesh):
        cylinder = trimesh.creation.cylinder(radius=shape.radius_m, height=shape.height_m, sections=CYLINDER_SECTIONS)
        return pyrender.Mesh.from_trimesh(cylinder, material=material, smooth=False)
    if isinstance(shape, SphereMesh):
        sphere = trimesh.creation.icosphere(subdivisions=SPHERE_SUBDIVISIONS, radius=shape.radius_m)
        return pyrender.Mesh.from_trimesh(sphere, material=material, smooth=True)
    if isinstance(shape, PlaneMesh):
        return pyrender.Mesh.from_trimesh(_plane(shape.size_m), material=material, smooth=False)
    if isinstance(shape, CheckerboardMesh):
        primitives = []
        for part, colour in _checkerboard(shape):
            mesh = pyrender.Mesh.from_trimesh(part, material=_material(shape.material, colour), smooth=False)
            primitives += mesh.primitives
        return pyrender.Mesh(primitives=primitives)
    if isinstance(shape, FileMesh):
        if resolve_path is None:
            raise ConfigError(f"mesh file {shape.path!r} needs the scene's directory to be found")
        loaded = trimesh.load(resolve_path(shape.path), force="mesh")
        if len(getattr(loaded, "faces", ())) == 0:
            raise ConfigError(f"mesh file {shape.path!r} holds no triangles (a point cloud?); give a mesh with faces")
        loaded.apply_scale(shape.scale)
        # The file's own materials stand unless the scene sets one.
        override = material if "material" in shape.model_fields_set else None
        mesh = pyrender.Mesh.from_trimesh(loaded, material=override, smooth=False)
        for primitive in mesh.primitives:
            # Surfaces are opaque: depth and ids name the first surface hit, and the static background
            # stays exact. (pyrender marks every material it converts from trimesh as blended.)
            primitive.material.alphaMode = "OPAQUE"
        return mesh
    raise TypeError(f"unknown shape {type(shape).__name__}")


def prop_mesh(model: PropModel) -> pyrender.Mesh:
    """A procedural prop (`camgen.props`) as one primitive with per-vertex albedo (COLOR_0) and the prop's
    roughness and metalness, in its own frame: one draw per prop (the renderer's per-draw cost dominates)."""
    vertices, normals, faces, colours, _ = model.arrays()
    primitive = pyrender.Primitive(
        positions=vertices,
        normals=normals,
        color_0=colours,
        indices=faces,
        material=pyrender.MetallicRoughnessMaterial(
            baseColorFactor=(1.0, 1.0, 1.0, 1.0),
            metallicFactor=model.metallic,
            roughnessFactor=model.roughness,
            doubleSided=False,
        ),
    )
    return pyrender.Mesh(primitives=[primitive])


PERSON_ROUGHNESS = 0.75
"""Skin, hair and most fabric are rough dielectrics (glTF roughness 0.6–0.9)."""


def person_mesh(rig: PersonRig) -> pyrender.Mesh:
    """A procedural person as one primitive with per-vertex albedo (COLOR_0), its vertices posed in
    world coordinates (the node's pose stays the identity); `SceneGraph.place_actors` updates them."""
    model = rig.model
    primitive = pyrender.Primitive(
        positions=rig.vertices_m,
        normals=rig.normals,
        color_0=model.colours,
        indices=model.faces,
        material=pyrender.MetallicRoughnessMaterial(
            baseColorFactor=(1.0, 1.0, 1.0, 1.0),
            metallicFactor=0.0,
            roughnessFactor=PERSON_ROUGHNESS,
            doubleSided=True,
        ),
    )
    return pyrender.Mesh(primitives=[primitive])


class ClearcoatMaterial(pyrender.MetallicRoughnessMaterial):
    """A glTF metallic-roughness material under a smooth clear coat (a car's paint: a pigmented base coat
    under 35–50 µm of clear lacquer). The shader (`linear_mesh.frag`, its CLEARCOATED_MATERIAL path) adds the
    coat's mirror reflection of the sky and the ground, Schlick's Fresnel factor of the view angle times the
    environment along the reflected ray, and takes that share off the base's ambient (diffuse) light, as
    glTF's KHR_materials_clearcoat layers a coat of IOR 1.5 (F0 = 0.04) over the base. Other materials
    (people, the ground, props) keep their diffuse-only ambient term."""

    clearcoat = True


class PaintMaterial(pyrender.MetallicRoughnessMaterial):
    """Road paint (`camgen.world.markings`): drawn and shadowed like the ground it lies on, but left out of
    the shadow maps (`camgen.render.renderer`): a plate a few millimetres over the road would only shade the
    road along its own edges (acne and a dark rim), while the road already casts the ground's shadow."""

    casts_shadow = False


def paint_mesh_node(paint: PaintMesh, *, wet: bool) -> pyrender.Mesh:
    """A marking's worn paint as one primitive with per-vertex reflectance (COLOR_0), facing up; wet: its
    reflectance darkened under a water film (`camgen.world.markings.wet_reflectance`) and its roughness
    × `camgen.world.rain.WET_ROUGHNESS_FACTOR`, as the wet ground's."""
    colours = wet_reflectance(paint.colours) if wet else paint.colours
    primitive = pyrender.Primitive(
        positions=paint.vertices_m,
        normals=np.tile(np.array([0.0, 0.0, 1.0], dtype=np.float32), (len(paint.vertices_m), 1)),
        color_0=np.asarray(colours, dtype=np.float32),
        indices=paint.faces,
        material=PaintMaterial(
            baseColorFactor=(1.0, 1.0, 1.0, 1.0),
            metallicFactor=0.0,
            roughnessFactor=PAINT_ROUGHNESS * (WET_ROUGHNESS_FACTOR if wet else 1.0),
            doubleSided=False,
        ),
    )
    return pyrender.Mesh(primitives=[primitive])


def kerb_mesh_node(kerb: Kerb) -> pyrender.Mesh:
    """A kerb (`camgen.world.kerbs`) as one textured primitive in world coordinates: precast concrete of the
    kerb's colour (weathered concrete's by default) with its units' joints (`camgen.world.textures.
    kerb_surface_maps`). Dry in the rain, as walls are (`wet_ground` wets level planes only)."""
    mesh = kerb_geometry(kerb)
    maps = kerb_surface_maps(kerb.seed, kerb.unit_length_m, kerb.joint_m)
    rgb = TYPICAL_ALBEDO_RGB["concrete"] if kerb.color_rgb is None else kerb.color_rgb
    sampler = pyrender.Sampler(wrapS=GL_REPEAT, wrapT=GL_REPEAT)
    material = _tiled_material(
        maps.albedo * np.asarray(rgb, dtype=np.float32),
        maps.roughness,
        maps.metallic,
        maps.normal,
        sampler,
        metallic_factor=1.0,
        roughness_factor=1.0,
        emission_cd_m2=0.0,
    )
    # A procedural tile's row 0 is its v = 0 edge, and pyrender uploads the image flipped (`_textured`).
    texcoords = np.column_stack([mesh.uv_m[:, 0] / maps.tile_m, 1.0 - mesh.uv_m[:, 1] / maps.tile_m])
    primitive = pyrender.Primitive(
        positions=mesh.vertices_m, normals=mesh.normals, texcoord_0=texcoords, indices=mesh.faces, material=material
    )
    return pyrender.Mesh(primitives=[primitive])


class ShadeMaterial(pyrender.MetallicRoughnessMaterial):
    """The shaded ground under a vehicle (`camgen.vehicles.body.ground_shade`): drawn with the vehicle, written
    into the instance pass as background (id 0, `camgen.render.renderer`), since it is the road, not the
    vehicle."""

    unlabelled = True


GLASS_RGB = (0.005, 0.0055, 0.006)
"""Glass's own diffuse share as an albedo (a faint tint and road film; clean float glass scatters well under 1 %):
a near-black base, glossy (roughness 0.05). Its look is its mirror reflection, added by the shader (its
TRANSMISSIVE_MATERIAL path): Schlick's Fresnel factor of the view angle (4 % at normal incidence) times the sky or
the lit ground along the reflected ray, as the paint's clear coat mirrors them, and the sun's specular highlight;
the transmitted cabin shows through (`camgen.vehicles.cabin`)."""
CABIN_ROUGHNESS = 0.8
"""The cabin's lining and its driver: rough dielectrics (fabric, plastics, skin)."""
VEHICLE_SURFACES = {
    "glass": ((*GLASS_RGB, 1.0), 0.0, 0.05),
    "cabin": ((1.0, 1.0, 1.0, 1.0), 0.0, CABIN_ROUGHNESS),
    "gear": ((1.0, 1.0, 1.0, 1.0), 0.3, 0.6),
    "head": ((0.55, 0.56, 0.58, 1.0), 0.0, 0.15),
    "tail": ((0.25, 0.01, 0.01, 1.0), 0.0, 0.2),
    "brake": ((0.25, 0.01, 0.01, 1.0), 0.0, 0.2),
    "indicator_left": ((0.45, 0.2, 0.02, 1.0), 0.0, 0.2),
    "indicator_right": ((0.45, 0.2, 0.02, 1.0), 0.0, 0.2),
    "cycle_head": ((0.55, 0.56, 0.58, 1.0), 0.0, 0.15),
    "cycle_tail": ((0.25, 0.01, 0.01, 1.0), 0.0, 0.2),
    "destination": ((0.45, 0.2, 0.02, 1.0), 0.0, 0.2),
    "shade": ((1.0, 1.0, 1.0, 1.0), 0.0, 1.0),
    "lens": ((1.0, 1.0, 1.0, 1.0), 0.0, 0.1),
}
"""Base colour (linear, alpha), metallic and roughness of a vehicle's surfaces other than its paint:
the running gear (tyres, rims, plate backings) takes its colours per vertex and one compromise between
rubber (dielectric, roughness ≈ 0.9) and alloy (metallic, ≈ 0.35), so that it is one draw; unlit lamps
show their lens colour (clear, red, amber) and emit `camgen.vehicles.LAMP_LUMINANCE_CD_M2` when lit (a bus's
destination display its `sign_luminance_cd_m2`)."""


def _lamp(surface: str) -> str | None:
    """The lamp a surface is (head, tail, brake, indicator_left, indicator_right, a bicycle's cycle_head and
    cycle_tail, a bus's destination display), or None."""
    return surface if surface in LAMP_COLOUR_RGB or surface.startswith("indicator") else None


def _lamp_emission(surface: str, lit: bool, sign_cd_m2: float) -> tuple[float, float, float]:
    if not lit:
        return (0.0, 0.0, 0.0)
    kind = "indicator" if surface.startswith("indicator") else surface
    luminance = sign_cd_m2 if kind == "destination" else LAMP_LUMINANCE_CD_M2[kind]
    return tuple(luminance * c for c in LAMP_COLOUR_RGB[kind])


def relative_intensity(light, pose: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """(N,) a point or spot light's intensity towards unit `directions` (N, 3) away from it, relative to its
    `intensity`, as the lit shader takes it: 1 for a point light; a spot's ((cos θ − cos θₒ)/(cos θᵢ − cos θₒ))²
    clipped to 0–1 (the renderer's cone, `camgen.world.night`), or an IES lamp's table at (γ, C) in its own axes
    (`intensity_profile`, `camgen.world.ies`). `pose`: the light node's, which points it along its −z."""
    directions = np.atleast_2d(np.asarray(directions, dtype=np.float64))
    if not isinstance(light, pyrender.SpotLight):
        return np.ones(len(directions))
    profile = getattr(light, "intensity_profile", None)
    if profile is not None:
        local = directions @ profile.axes(pose).T  # (C = 0°, C = 90°, the lamp's axis) components
        gamma_deg = np.degrees(np.arccos(np.clip(local[:, 2], -1.0, 1.0)))
        return grid_intensity_cd(profile.relative, gamma_deg, np.degrees(np.arctan2(local[:, 1], local[:, 0])))
    cos_i, cos_o = math.cos(light.innerConeAngle), math.cos(light.outerConeAngle)
    share = np.clip((directions @ -pose[:3, 2] - cos_o) / max(cos_i - cos_o, 1e-9), 0.0, 1.0)
    return share * share


def horizontal_illuminance_lux(scene: pyrender.Scene, point_m: np.ndarray) -> float:
    """Illuminance of an upward-facing surface at `point_m` from `scene`'s lights as they are set now, lux, in
    photometric units (each light's colour weighted Y = 0.2126 R + 0.7152 G + 0.0722 B), nothing shadowed: the
    ambient light's π·ambient_light (its E), each directional light's E·sin(elevation), and each point and
    spot light's I(θ)·cos(incidence)/d² (I(θ) by `relative_intensity`)."""
    total = math.pi * float(LUMINANCE_WEIGHTS @ np.asarray(scene.ambient_light, dtype=np.float64))
    point = np.asarray(point_m, dtype=np.float64)
    for node in scene.light_nodes:
        light, pose = node.light, scene.get_pose(node)
        power = light.intensity * float(LUMINANCE_WEIGHTS @ np.asarray(light.color, dtype=np.float64))
        if isinstance(light, pyrender.DirectionalLight):
            total += power * max(0.0, float(pose[2, 2]))  # the light travels along the node's −z
            continue
        towards = pose[:3, 3] - point
        distance_m = float(np.linalg.norm(towards))
        if distance_m < 1e-6 or towards[2] <= 0.0:
            continue
        towards /= distance_m
        power *= float(relative_intensity(light, pose, -towards)[0])
        total += power * towards[2] / distance_m**2
    return total


def sign_luminance_cd_m2(scene: pyrender.Scene, rig: VehicleRig) -> float:
    """Luminance of `rig`'s destination display under `scene`'s lights now (`camgen.vehicles.sign`:
    `display_luminance_cd_m2` of the horizontal illuminance at its middle), cd/m²; 0 without a display."""
    centre = rig.sign_centre_m
    return 0.0 if centre is None else float(display_luminance_cd_m2(horizontal_illuminance_lux(scene, centre)))


def vehicle_mesh(rig: VehicleRig, sign_cd_m2: float) -> pyrender.Mesh:
    """A procedural vehicle as one primitive per part (paint, glass, running gear, each lamp, plates),
    posed in world coordinates, its destination display (if any) at `sign_cd_m2`; `SceneGraph.place_actors`
    moves it and lights its lamps."""
    paint = rig.look.paint
    primitives = []
    for part, piece in zip(rig.model.parts, rig.parts, strict=True):
        if part.surface == "paint":
            material = ClearcoatMaterial(
                baseColorFactor=(*paint.color_rgb, 1.0), metallicFactor=paint.metallic, roughnessFactor=paint.roughness
            )
        elif part.surface == "plates":  # a car's front plate over its rear one; a motorcycle's one plate
            image = plate_texture(rig.look)
            material = pyrender.MetallicRoughnessMaterial(
                baseColorFactor=(1.0, 1.0, 1.0, 1.0),
                baseColorTexture=MipmappedTexture(srgb=True, source=encode_srgb8(image), source_channels="RGB"),
                metallicFactor=0.0,
                roughnessFactor=0.5,
            )
        else:
            colour, metallic, roughness = VEHICLE_SURFACES[part.surface]
            material = (ShadeMaterial if part.surface == "shade" else pyrender.MetallicRoughnessMaterial)(
                baseColorFactor=colour,
                metallicFactor=metallic,
                roughnessFactor=roughness,
                # Glass blends over the cabin behind it (per-vertex opacity 1 − transmittance), drawn after
                # every opaque surface (`camgen.render.renderer`).
                alphaMode="BLEND" if part.surface == "glass" else "OPAQUE",
            )
        lamp = _lamp(part.surface)
        if lamp is not None:
            material.emissiveFactor = _lamp_emission(lamp, rig.lit.get(lamp, False), sign_cd_m2)
        primitives.append(
            pyrender.Primitive(
                positions=rig.vertices_m[piece],
                normals=rig.normals[piece],
                texcoord_0=part.texcoords,
                color_0=part.colours,
                indices=part.faces,
                material=material,
            )
        )
    return pyrender.Mesh(primitives=primitives)


def _pose_vehicle_mesh(node: pyrender.Node, rig: VehicleRig, deformed: set, sign_cd_m2: float) -> None:
    """Copy a placed vehicle's vertices into its primitives and light its lamps (its destination display at
    `sign_cd_m2`)."""
    # One conversion to the primitives' float32 for the whole vehicle; each primitive takes its rows' view.
    vertices, normals = rig.vertices_m.astype(np.float32), rig.normals.astype(np.float32)
    bounds = _piece_bounds(vertices, rig.parts)
    for k, (primitive, part, piece) in enumerate(zip(node.mesh.primitives, rig.model.parts, rig.parts, strict=True)):
        primitive.positions = vertices[piece]
        primitive.normals = normals[piece]
        if bounds is not None:
            primitive._bounds = bounds[k]  # what pyrender's `Primitive.bounds` would compute from them
        deformed.add(primitive)
        lamp = _lamp(part.surface)
        if lamp is not None:
            primitive.material.emissiveFactor = _lamp_emission(lamp, rig.lit.get(lamp, False), sign_cd_m2)
    node.mesh._bounds = None  # pyrender caches a mesh's bounds


def _piece_bounds(vertices: np.ndarray, pieces: list[slice]) -> np.ndarray | None:
    """(K, 2, 3) (low, high) of the rows of each of `pieces` of `vertices` (V, 3), in one reduction each way
    instead of pyrender's two per primitive (`Primitive.bounds`, at the first use after each placement: a
    vehicle's tens of primitives, placed at every motion-blur sub-frame); the same values (a minimum is exact).
    None unless the pieces are non-empty and run back to back over every row (a vehicle's `parts` do)."""
    starts = [piece.start for piece in pieces]
    stops = [piece.stop for piece in pieces]
    if not pieces or starts[0] != 0 or stops[-1] != len(vertices) or starts[1:] != stops[:-1]:
        return None
    if any(piece.step not in (None, 1) or piece.stop <= piece.start for piece in pieces):
        return None
    return np.stack(
        [np.minimum.reduceat(vertices, starts, axis=0), np.maximum.reduceat(vertices, starts, axis=0)], axis=1
    )


def _light_display(node: pyrender.Node, rig: VehicleRig, sign_cd_m2: float) -> None:
    """Light a vehicle's destination display at `sign_cd_m2` (the daylight moved, the vehicle did not)."""
    for primitive, part in zip(node.mesh.primitives, rig.model.parts, strict=True):
        if part.surface == "destination":
            primitive.material.emissiveFactor = _lamp_emission(
                part.surface, rig.lit.get(part.surface, False), sign_cd_m2
            )


def character_mesh(rig: CharacterRig, override: Material | None) -> pyrender.Mesh:
    """A glTF character as one primitive per file primitive, with its PBR material and textures
    (mipmapped and filtered trilinearly: pyrender's default for a texture with an image), posed in
    world coordinates; `override`: the scene's material instead of the file's."""
    primitives = []
    for primitive, part in zip(rig.character.primitives, rig.parts, strict=True):
        m = primitive.material
        if override is not None:
            material = _material(override)
        else:
            material = pyrender.MetallicRoughnessMaterial(
                baseColorFactor=m.base_color_factor,
                baseColorTexture=_texture(m.base_color_image, m.wrap, srgb=True),
                metallicFactor=m.metallic_factor,
                roughnessFactor=m.roughness_factor,
                metallicRoughnessTexture=_texture(m.metallic_roughness_image, m.wrap, srgb=False),
                normalTexture=_texture(m.normal_image, m.wrap, srgb=False),
                occlusionTexture=_texture(m.occlusion_image, m.wrap, srgb=False),
                doubleSided=m.double_sided,
            )
        uses_uv = override is None and any(
            image is not None
            for image in (m.base_color_image, m.metallic_roughness_image, m.normal_image, m.occlusion_image)
        )
        primitives.append(
            pyrender.Primitive(
                positions=rig.vertices_m[part],
                normals=rig.normals[part],
                texcoord_0=primitive.texcoords if uses_uv else None,
                color_0=primitive.colours if override is None else None,
                indices=primitive.faces,
                material=material,
            )
        )
    return pyrender.Mesh(primitives=primitives)


def _texture(image: np.ndarray | None, wrap: tuple[int, int], *, srgb: bool):
    """A glTF texture with its mip levels averaged as its texels mean (`camgen.render.mipmaps`): colour
    (`srgb`) as linear values, data as stored."""
    if image is None:
        return None
    sampler = pyrender.Sampler(wrapS=wrap[0], wrapT=wrap[1])  # filters: pyrender's trilinear default
    return MipmappedTexture(srgb=srgb, source=image, source_channels="RGBA"[: image.shape[2]], sampler=sampler)


def _look_along(direction: np.ndarray, position=(0.0, 0.0, 0.0)) -> np.ndarray:
    """A node pose whose −z axis points along `direction` (how pyrender aims lights)."""
    z = -np.asarray(direction, dtype=np.float64)
    z /= np.linalg.norm(z)
    helper = np.array([0.0, 0.0, 1.0]) if abs(z[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return T_world_from_cam(position, np.column_stack([x, np.cross(z, x), z]))


def _towards_sun(light: SunLight) -> np.ndarray:
    return _towards(light.azimuth_deg, light.elevation_deg)


def _towards(azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    """Unit vector of a scene azimuth (counter-clockwise from +X) and elevation."""
    az, el = math.radians(azimuth_deg), math.radians(elevation_deg)
    return np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])


@dataclass
class SiteDaylightTrack:
    """A site's daylight through a sequence (`camgen.world.site`): the sun moves as the site's sun does,
    and each light the scene resolved for its first frame, and the sky, scales as the model's value does
    (so an illuminance the scene gave itself is the model's shape through its own level)."""

    site: Site
    sky: str
    start: SiteDaylight
    """The model's daylight at the first frame."""
    suns: list[tuple[pyrender.Node, float]]
    """Each sun light's node and its illuminance at the first frame, lux."""
    ambient_lux: float
    sky_luminance_cd_m2: float

    def at(self, time_s: float) -> SiteDaylight:
        site = self.site
        time = site.time + timedelta(seconds=time_s)
        return site_daylight(site.latitude_deg, site.longitude_deg, time, site.north_deg, self.sky)

    @staticmethod
    def ratio(now: float, start: float) -> float:
        return now / start if start > 0 else 0.0


def site_daylight_track(scene: Scene, graph: pyrender.Scene, ambient_lux: float) -> SiteDaylightTrack | None:
    """The daylight track of a scene whose site's daylight changes over the sequence (beyond
    `camgen.world.site.DIRECTION_CHANGE_DEG` or `ILLUMINANCE_CHANGE_REL`); None for a held one."""
    site, sky = scene.environment.site, scene.environment.sky
    if (
        site is None
        or scene.environment.night_sky is not None  # a night sky holds its level (`Environment.night_sky`)
        or not daylight_change(site.latitude_deg, site.longitude_deg, site.time, sky, scene.duration_s).varies
    ):
        return None
    return SiteDaylightTrack(
        site=site,
        sky=sky,
        start=site_daylight(site.latitude_deg, site.longitude_deg, site.time, site.north_deg, sky),
        suns=[(node, float(node.light.intensity)) for node in graph.directional_light_nodes],
        ambient_lux=ambient_lux,
        sky_luminance_cd_m2=scene.environment.sky_luminance_cd_m2,
    )


def _sun_direction(lights) -> np.ndarray | None:
    suns = [light for light in lights if isinstance(light, SunLight)]
    return _towards_sun(suns[0]) if suns else None


@dataclass(frozen=True)
class SpotProfile:
    """An IES lamp's intensity table as the renderer's lit shader looks it up (`camgen.render.renderer`)."""

    relative: np.ndarray
    """I(γ, C) / I_max on `camgen.world.ies.grid_angles_deg`'s grid, (181, 72) float32."""
    c0_direction: np.ndarray
    """World vector of the C = 0° plane."""

    def axes(self, pose: np.ndarray) -> np.ndarray:
        """Rows: the C = 0° and C = 90° directions and the beam axis (γ = 0) of a light at `pose`."""
        axis = -np.asarray(pose, dtype=np.float64)[:3, 2]
        c0 = self.c0_direction - (self.c0_direction @ axis) * axis
        if np.linalg.norm(c0) < 1e-9:  # C = 0 along the axis: any perpendicular will do
            c0 = np.cross(axis, [0.0, 1.0, 0.0] if abs(axis[1]) < 0.9 else [1.0, 0.0, 0.0])
        c0 /= np.linalg.norm(c0)
        return np.stack([c0, np.cross(c0, axis), axis])


IES_CONE_DEG = 70.0
"""An IES lamp's spot cone, degrees from its axis, which sets only its shadow map's field of view
(pyrender's: 2·cone + 30° = 170°, which must stay under 180°); the table alone shapes the light."""


def _ies_lamp(light: LampLight, resolve_path: Callable[[str], Path] | None) -> pyrender.SpotLight:
    if resolve_path is None:
        raise ConfigError(f"IES file {light.ies_file!r} needs the scene's directory to be found")
    grid = intensity_grid_cd(read_ies(resolve_path(light.ies_file)))
    peak_cd = float(grid.max())
    if peak_cd <= 0:
        raise ConfigError(f"IES file {light.ies_file!r} holds no light (every candela value is 0)")
    scale = 1.0 if light.flux_lm is None else light.flux_lm / ies_flux_lm(grid)
    node_light = pyrender.SpotLight(
        color=light.color_rgb,
        intensity=peak_cd * scale,
        innerConeAngle=math.radians(IES_CONE_DEG) - 1e-3,
        outerConeAngle=math.radians(IES_CONE_DEG),
    )
    az = math.radians(light.c0_azimuth_deg)
    node_light.intensity_profile = SpotProfile(
        relative=(grid / peak_cd).astype(np.float32), c0_direction=np.array([math.cos(az), math.sin(az), 0.0])
    )
    return node_light


@dataclass
class Headlamp:
    """A vehicle's lit low beams as one spot light (`camgen.vehicles.headlamps`: a car's pair of lamps as one
    light midway between them): its node, placed with the vehicle (`place`), at `intensity_cd` while the
    vehicle's head lamps are lit and 0 while they are not.

    The light holds still over each frame's exposure, where the vehicle stands at the frame's time (the time
    rounded to the scene's frames, `frame_s`): its pool, metres long and soft-edged, would smear by the
    vehicle's travel in the exposure (0.33 m at 30 km/h in 1/25 s), which nobody sees; a light that moves during
    the exposure makes the renderer draw the whole frame at every motion-blur sub-frame (`camgen.render.sequence`),
    where a held one lets it blur the moving vehicle's pixels alone. It moves from frame to frame."""

    actor_index: int
    node: pyrender.Node
    point_m: np.ndarray
    """(3,) where the light stands in the vehicle's frame, m (`VehicleRig.headlamp`)."""
    intensity_cd: float
    """The beam's peak, all its lamps together, cd."""
    frame_s: float
    """The scene's frame period, s."""

    def place(self, scene: pyrender.Scene, rig: VehicleRig, time_s: float) -> None:
        """Put the light where `rig` holds its lamps at the frame time nearest `time_s`, aimed level along its
        heading; lit as they are then."""
        frame_time_s = round(time_s / self.frame_s) * self.frame_s
        T, _ = rig.pose(frame_time_s)
        ahead = np.array([T[0, 0], T[1, 0], 0.0])
        scene.set_pose(self.node, _look_along(ahead, T[:3, :3] @ self.point_m + T[:3, 3]))
        self.node.light.intensity = self.intensity_cd if rig.lamps(frame_time_s)["head"] else 0.0


def add_headlamps(graph: pyrender.Scene, scene: Scene, vehicles: list[VehicleRig | None]) -> list[Headlamp]:
    """A `Headlamp` for each vehicle of `scene` whose head lamps are lit at its first or last frame while
    their pool would show: its brightest illuminance on the road at least `BEAM_VISIBLE_FRACTION` of the
    daylight's then (`camgen.vehicles.headlamps.daylight_horizontal_lux`; by day a lit lamp only glows).

    The renderer shades at most `MAX_LIGHTS["spot"]` spot lights, the scene's spot and lamp lights among them:
    the vehicles beyond that room, in the scene's order of actors, keep glowing lenses but light nothing,
    and a warning names them."""
    times_s = (0.0, float(scene.duration_s))
    daylight = daylight_horizontal_lux(scene)
    darkest_lux = min(daylight(t) for t in times_s)
    wanted = []
    for index, rig in enumerate(vehicles):
        carried = rig.headlamp if rig is not None else None
        if carried is None or not any(lit_at(rig.lights_on, t) for t in times_s):
            continue
        point_m, lamps = carried
        if peak_road_illuminance_lux(float(point_m[2]), lamps) >= BEAM_VISIBLE_FRACTION * darkest_lux:
            wanted.append((index, point_m, lamps))
    room = max(MAX_LIGHTS["spot"] - len(graph.spot_light_nodes), 0)
    if len(wanted) > room:
        names = ", ".join(scene.actors[index].name for index, _, _ in wanted[room:])
        warnings.warn(
            f"{len(wanted)} vehicles have lit low beams but the renderer shades at most {MAX_LIGHTS['spot']} spot "
            f"lights ({len(graph.spot_light_nodes)} of them the scene's lamps): {names} light no road, their "
            "lamps only glow; remove some lamps or vehicles, or set their vehicle.lights_on: false",
            stacklevel=2,
        )
    table = low_beam_table()
    peak_cd = float(table.max())
    outer = math.radians(BEAM_CONE_DEG)
    headlamps = []
    for index, point_m, lamps in wanted[:room]:
        light = pyrender.SpotLight(
            color=(1.0, 1.0, 1.0), intensity=lamps * peak_cd, innerConeAngle=outer - 1e-3, outerConeAngle=outer
        )
        light.intensity_profile = SpotProfile(
            relative=(table / peak_cd).astype(np.float32), c0_direction=np.array([0.0, 0.0, 1.0])
        )
        node = graph.add(light, name=f"headlamp:{scene.actors[index].name}")
        headlamps.append(Headlamp(index, node, point_m, lamps * peak_cd, 1.0 / scene.fps))
    return headlamps


def _add_lights(scene: pyrender.Scene, lights, resolve_path: Callable[[str], Path] | None = None) -> None:
    for light in lights:
        if isinstance(light, SunLight):
            towards_sun = _towards_sun(light)
            node_light = pyrender.DirectionalLight(color=light.color_rgb, intensity=light.illuminance_lux)
            scene.add(node_light, pose=_look_along(-towards_sun))
        elif isinstance(light, PointLight):
            node_light = pyrender.PointLight(color=light.color_rgb, intensity=light.intensity_cd)
            scene.add(node_light, pose=T_world_from_cam(light.position_m, np.eye(3)))
        elif isinstance(light, SpotLight):
            outer = math.radians(light.cone_half_angle_deg)
            node_light = pyrender.SpotLight(
                color=light.color_rgb,
                intensity=light.intensity_cd,
                innerConeAngle=SPOT_FULL_INTENSITY_FRACTION * outer,
                outerConeAngle=outer,
            )
            direction = np.subtract(light.target_m, light.position_m)
            scene.add(node_light, pose=_look_along(direction, light.position_m))
        elif isinstance(light, LampLight):
            outer = math.radians(light.cone_half_angle_deg)
            node_light = (
                _ies_lamp(light, resolve_path)
                if light.ies_file is not None
                else pyrender.SpotLight(
                    color=light.color_rgb,
                    intensity=peak_intensity_cd(light.flux_lm, outer),
                    innerConeAngle=SPOT_FULL_INTENSITY_FRACTION * outer,
                    outerConeAngle=outer,
                )
            )
            scene.add(node_light, pose=_look_along(np.asarray(light.direction), light.position_m))
        elif not isinstance(light, AmbientLight):
            raise TypeError(f"unknown light {type(light).__name__}")


def _character_rig(actor: Actor, route: Route, characters: dict[str, Character], resolve_path) -> CharacterRig:
    shape = actor.shape
    if resolve_path is None:
        raise ConfigError(f"character file {shape.path!r} needs the scene's directory to be found")
    if shape.path not in characters:
        characters[shape.path] = load_character(resolve_path(shape.path))
    animation = shape.animation
    return character_rig(
        characters[shape.path],
        route,
        T_actor_from_mesh=placement(shape),
        scale=shape.scale,
        clip=animation.clip if animation is not None else None,
        idle_clip=animation.idle_clip if animation is not None else None,
        clip_speed_m_s=animation.clip_speed_m_s if animation is not None else None,
    )


def wet_ground(mesh, node_mesh: pyrender.Mesh) -> None:
    """Wet a level plane facing up (`camgen.world.rain`): its base colour × WET_ALBEDO_FACTOR and its
    roughness × WET_ROUGHNESS_FACTOR (a texture's maps are scaled by the material's factors); other meshes
    stay dry (walls shed water, and the renderer knows no puddles)."""
    if not is_level_plane(mesh):
        return
    for primitive in node_mesh.primitives:
        material = primitive.material
        rgb = np.asarray(material.baseColorFactor, np.float64)
        material.baseColorFactor = np.array([*(WET_ALBEDO_FACTOR * rgb[:3]), rgb[3]])
        material.roughnessFactor = WET_ROUGHNESS_FACTOR * material.roughnessFactor


def build_scene_graph(scene: Scene, resolve_path: Callable[[str], Path] | None = None) -> SceneGraph:
    """Meshes, actors (at t = 0) and lights of `scene` as a pyrender scene; no camera yet."""
    ambient_lux = sum(light.illuminance_lux for light in scene.lights if isinstance(light, AmbientLight))
    graph = OrderedScene(bg_color=(0.0, 0.0, 0.0, 0.0), ambient_light=np.full(3, ambient_lux / math.pi))
    _add_lights(graph, scene.lights, resolve_path)
    # pyrender's shadow passes sort meshes by distance to the main camera; draws set its pose.
    graph.add(pyrender.IntrinsicsCamera(1.0, 1.0, 0.0, 0.0), name="camera")
    instances = instance_table(scene)
    routes = actor_routes(scene)
    vehicle_by_name = vehicle_rigs(scene, routes)
    actor_nodes, local_poses, environment_nodes, people, vehicles = [], [], [], [], []
    characters: dict[str, Character] = {}
    for index, actor in enumerate(scene.actors):
        if is_procedural_person(actor):
            if actor.rides is not None:  # seated on its bicycle or motorcycle
                rig = rider_rig(actor, vehicle_by_name[actor.rides], scene_seed=scene.seed, actor_index=index)
            else:
                rig = person_rig(actor, routes[actor.name], scene_seed=scene.seed, actor_index=index)
            actor_nodes.append(graph.add(person_mesh(rig), name=f"actor:{actor.name}"))
            local_poses.append(np.eye(4))
            people.append(rig)
            vehicles.append(None)
            continue
        if is_procedural_vehicle(actor):
            vehicle = vehicle_by_name[actor.name]
            mesh = vehicle_mesh(vehicle, sign_luminance_cd_m2(graph, vehicle))
            actor_nodes.append(graph.add(mesh, name=f"actor:{actor.name}"))
            local_poses.append(np.eye(4))
            people.append(None)
            vehicles.append(vehicle)
            continue
        if is_character(actor):
            rig = _character_rig(actor, routes[actor.name], characters, resolve_path)
            override = actor.shape.material if "material" in actor.shape.model_fields_set else None
            actor_nodes.append(graph.add(character_mesh(rig, override), name=f"actor:{actor.name}"))
            local_poses.append(np.eye(4))
            people.append(rig)
            vehicles.append(None)
            continue
        shape = actor_shape(actor)
        actor_nodes.append(graph.add(build_mesh(shape, resolve_path), name=f"actor:{actor.name}"))
        local_poses.append(placement(shape))
        people.append(None)
        vehicles.append(None)
    wet = ground_is_wet(scene.environment)
    for mesh in scene.environment.meshes:
        pyrender_mesh = build_mesh(mesh, resolve_path)
        if wet:
            wet_ground(mesh, pyrender_mesh)
        node = graph.add(pyrender_mesh, pose=placement(mesh), name=f"environment:{mesh.name}")
        environment_nodes.append(node)
    prop_nir = {}
    swaying = []
    gusts = wind_gusts(scene.environment.wind, scene_seed=scene.seed)
    for prop in placed_props(scene.environment, scene_seed=scene.seed):
        swings = gusts is not None and prop.model.type in SWAYING_TYPES
        model = bendable(prop.model) if swings else prop.model  # a trunk that curves as it bends
        mesh = prop_mesh(model)
        prop_nir[id(mesh.primitives[0])] = model.arrays()[4]
        node = graph.add(mesh, pose=prop.T_world_from_prop, name=f"environment:{prop.name}")
        environment_nodes.append(node)
        if swings:
            vertices, normals = model.arrays()[:2]
            swaying.append(SwayingProp(node, prop_sway(model, prop.T_world_from_prop, gusts), vertices, normals))
    names = marking_names(scene.environment.markings)
    for index, marking in enumerate(scene.environment.markings):
        paint = marking_paint(marking, scene_seed=scene.seed, index=index)
        mesh = paint_mesh_node(paint, wet=wet)
        prop_nir[id(mesh.primitives[0])] = paint.nir_reflectance
        environment_nodes.append(graph.add(mesh, name=f"environment:{names[index]}"))
    for kerb, name in zip(scene.environment.kerbs, kerb_names(scene.environment.kerbs), strict=True):
        environment_nodes.append(graph.add(kerb_mesh_node(kerb), name=f"environment:{name}"))
    nodes = actor_nodes + environment_nodes
    instance_ids = {node: instance.instance_id for node, instance in zip(nodes, instances, strict=True)}
    result = SceneGraph(
        scene=graph,
        actors=list(scene.actors),
        actor_nodes=actor_nodes,
        environment_nodes=environment_nodes,
        instance_ids=instance_ids,
        instances=instances,
        sky_luminance_cd_m2=scene.environment.sky_luminance_cd_m2,
        sky=scene.environment.sky,
        sun_direction=_sun_direction(scene.lights),
        fog_visibility_m=scene.environment.fog.visibility_m if scene.environment.fog is not None else None,
        rain_rate_mm_h=scene.environment.rain.rate_mm_h if scene.environment.rain is not None else None,
        rain_seed=scene.environment.rain.seed if scene.environment.rain is not None else 0,
        far_ground=far_ground(scene, resolve_path),
        daylight=site_daylight_track(scene, graph, ambient_lux),
        shadows=scene.environment.shadows,
        actor_local_poses=local_poses,
        actor_routes=[routes[actor.name] for actor in scene.actors],
        people=people,
        crowd=Crowd([rig for rig in people if isinstance(rig, PersonRig)]),
        vehicles=vehicles,
        prop_nir=prop_nir,
        swaying=swaying,
        headlamps=add_headlamps(graph, scene, vehicles),
        source=(scene, resolve_path),
    )
    result.place_actors(0.0)
    return result
