"""The near-infrared pass of a camera in night mode (`camgen.world.night`).

A second scene graph of the same scene whose surfaces take their 850 nm reflectance as a grey base
colour and whose only light is the camera's IR illuminator, a spot at the camera along its optical
axis with the candela that count as its 850 nm radiant intensity does on the sensor
(`camgen.world.night.nir_equivalent_intensity_cd`). No ambient, no emission, no sky: the scene's
lamps are taken to emit no 850 nm light (LED street lights emit almost none; the NIR lines of
high-pressure sodium lamps are not modelled), and so are vehicles' headlamps (`camgen.vehicles.headlamps`:
LED low beams emit almost none; a halogen lamp's near-infrared tail is not modelled), whose visible light
still reaches the sensor through the visible pass. The pass is drawn without shadows: the illuminator sits
at the lens, so the shadows it casts hide behind what casts them. Its radiance, in the visible pass's
units, is added to every colour channel: without the IR-cut filter the colour filters pass 850 nm
about equally.

NIR reflectance of each surface: the scene material's `nir_reflectance`; else, for a procedural
texture, its type's (`NIR_REFLECTANCE_BY_TEXTURE`, the texture's own variation kept; a kerb's precast
concrete, concrete's, unless the kerb gives its own colour: `kerb_nir_reflectance`); a procedural
prop's, per vertex (`camgen.props`: leaves 0.45–0.5); else the rule
`default_nir_reflectance` on the base colour (vertex colours and textures included: people, vehicles,
plates, glTF characters, file textures).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from camgen.config.kerbs import Kerb
from camgen.config.profile import Profile
from camgen.config.scene import Material, Scene, actor_shape
from camgen.render.gl import pyrender
from camgen.render.mipmaps import MipmappedTexture
from camgen.render.scene_graph import SceneGraph, _look_along, build_scene_graph
from camgen.world.night import (
    NIR_REFLECTANCE_BY_TEXTURE,
    SPOT_FULL_INTENSITY_FRACTION,
    default_nir_reflectance,
    nir_equivalent_intensity_cd,
)
from camgen.world.textures import decode_srgb8, encode_srgb8


def material_nir_reflectance(material: Material) -> float | None:
    """ρ₈₅₀ of a scene material: its own, its texture type's, or the base-colour rule (module docstring);
    None for a file texture's, whose texels each take the rule (`_nir_material`)."""
    if material.nir_reflectance is not None:
        return material.nir_reflectance
    if material.texture is not None and material.texture.type == "file":
        return None
    if material.texture is not None and "color_rgb" not in material.model_fields_set:
        return NIR_REFLECTANCE_BY_TEXTURE[material.texture.type]
    return float(default_nir_reflectance(material.color_rgb))


def kerb_nir_reflectance(kerb: Kerb) -> float:
    """ρ₈₅₀ of a kerb (`camgen.render.scene_graph.kerb_mesh_node`: precast concrete's texture): concrete's, as a
    concrete-textured material's; the rule on its colour when the kerb gives one (as `material_nir_reflectance`)."""
    if kerb.color_rgb is None:
        return NIR_REFLECTANCE_BY_TEXTURE["concrete"]
    return float(default_nir_reflectance(kerb.color_rgb))


def _nir_material(material, reflectance: float | None) -> None:
    """Turn a pyrender material into its NIR version in place: grey base `reflectance` (or the rule on
    its colour), textures converted, no emission."""
    factor = np.asarray(material.baseColorFactor, dtype=np.float64)
    texture = material.baseColorTexture
    if texture is not None and texture.source is not None:
        image = texture.source
        encoded = image.dtype == np.uint8
        linear = (decode_srgb8(image[..., :3]) if encoded else np.asarray(image[..., :3])).astype(np.float32)
        rule = default_nir_reflectance(linear * factor[:3])
        if reflectance is not None:  # keep the texture's variation around the material's mean
            mean = float(np.mean(rule))
            rule = rule * (reflectance / mean) if mean > 0 else np.full_like(rule, reflectance)
        grey = np.repeat(np.clip(rule, 0, 1)[..., None], 3, axis=-1).astype(np.float32)
        material.baseColorTexture = MipmappedTexture(
            srgb=True, source=encode_srgb8(grey), source_channels="RGB", sampler=texture.sampler
        )
        material.baseColorFactor = (1.0, 1.0, 1.0, factor[3])
    else:
        value = float(default_nir_reflectance(factor[:3])) if reflectance is None else reflectance
        material.baseColorFactor = (value, value, value, factor[3])
    material.emissiveFactor = (0.0, 0.0, 0.0)


def build_nir_graph(
    scene: Scene, profile: Profile, resolve_path: Callable[[str], Path] | None = None
) -> SceneGraph | None:
    """The NIR scene graph of `scene` for a camera of `profile`, lit by its IR illuminator only; None
    when the profile has no night mode with an illuminator behind a removable IR-cut filter."""
    night = profile.night_mode
    if night is None or not night.ir_cut_filter or night.ir_illuminator is None:
        return None
    graph = build_scene_graph(scene, resolve_path)
    known: dict[int, float] = {}
    meshes = scene.environment.meshes  # the props' nodes follow the meshes' (`graph.prop_nir`)
    for node, mesh in zip(graph.environment_nodes[: len(meshes)], meshes, strict=True):
        known[id(node)] = material_nir_reflectance(mesh.material)
    kerbs = scene.environment.kerbs  # the last environment nodes (`build_scene_graph`)
    kerb_nodes = graph.environment_nodes[len(graph.environment_nodes) - len(kerbs) :]
    for node, kerb in zip(kerb_nodes, kerbs, strict=True):
        known[id(node)] = kerb_nir_reflectance(kerb)
    for index, (node, actor) in enumerate(zip(graph.actor_nodes, graph.actors, strict=True)):
        if graph.rig(index) is None:
            known[id(node)] = material_nir_reflectance(actor_shape(actor).material)
    for node in list(graph.environment_nodes) + list(graph.actor_nodes):
        for primitive in node.mesh.primitives:
            _nir_material(primitive.material, known.get(id(node)))
            if primitive.color_0 is not None:
                colours = np.asarray(primitive.color_0, dtype=np.float64)
                prop_nir = graph.prop_nir.get(id(primitive))
                grey = np.clip(default_nir_reflectance(colours[:, :3]) if prop_nir is None else prop_nir, 0, 1)
                converted = np.repeat(grey[:, None], colours.shape[1], axis=1)
                if colours.shape[1] == 4:
                    converted[:, 3] = colours[:, 3]
                primitive.color_0 = converted.astype(np.float32)
    for light_node in list(graph.scene.light_nodes):
        graph.scene.remove_node(light_node)
    graph.headlamps = []
    graph.scene.ambient_light = np.zeros(3)
    illuminator = night.ir_illuminator
    outer = math.radians(illuminator.half_angle_deg)
    graph.scene.add(
        pyrender.SpotLight(
            color=(1.0, 1.0, 1.0),
            intensity=nir_equivalent_intensity_cd(illuminator.radiant_intensity_mw_sr, profile.sensor.qe_850nm_rel),
            innerConeAngle=SPOT_FULL_INTENSITY_FRACTION * outer,
            outerConeAngle=outer,
        ),
        name="ir_illuminator",
    )
    graph.sky_luminance_cd_m2 = 0.0
    graph.sky = "uniform"
    graph.daylight = None
    graph.shadows = False
    return graph


def aim_illuminator(graph: SceneGraph, T_world_from_cam: np.ndarray) -> None:
    """Put the NIR graph's illuminator at the camera, its beam along the optical axis (OpenCV +z)."""
    (node,) = [n for n in graph.scene.light_nodes if n.name == "ir_illuminator"]
    T = np.asarray(T_world_from_cam, dtype=np.float64)
    graph.scene.set_pose(node, _look_along(T[:3, 2], T[:3, 3]))
