"""A user's character from a glTF 2.0 file: its skinned mesh, PBR textures and animation clips.

Reading follows the glTF 2.0 specification (Khronos, version 2.0.1) exactly where it sets rules:

- **Nodes** carry either a matrix or translation/rotation (unit quaternion x, y, z, w)/scale; a node's
  local transform is T·R·S, its global transform the product of its ancestors' (§3.5.2–3.5.3).
- **Animations** target a node's translation, rotation or scale; keyframe times are seconds; LINEAR
  interpolates translations and scales linearly and rotations by spherical linear interpolation
  (shortest arc); STEP holds the previous keyframe; CUBICSPLINE is a cubic Hermite spline whose
  output holds (in-tangent, value, out-tangent) triplets, tangents scaled by the keyframe interval
  (§3.11, Appendix C). Before the first keyframe a channel holds its first value, after the last its
  last. Clips loop: a clip's duration is its latest keyframe time.
- **Skins**: a joint's matrix is ``G_joint · inverseBindMatrix``, and a vertex moves by the
  weighted sum of its (up to four per JOINTS_n/WEIGHTS_n set) joints' matrices; "only the joint
  transforms are applied to the skinned mesh; the transform of the skinned mesh node MUST be
  ignored" (§3.7.3.3). Weights are renormalised to sum to one (the specification requires that
  they do; exporters round).
- **Axes and units**: glTF is right-handed, +Y up, metres, and "the front of a glTF asset faces +Z".
  camgen's actor frame is x forward, y left, z up (DESIGN.md), so glTF (x, y, z) becomes camgen
  (z, x, y): glTF +X, the asset's left, becomes camgen's +y (left).
- **Textures** (base colour, metallic-roughness, normal, emissive, occlusion) keep their sampler's
  wrap modes; the renderer filters them trilinearly over mipmaps. glTF's texture coordinates run
  from the image's top-left corner; OpenGL's from its bottom-left, so v becomes 1 − v.

`load_character` reads a file (pygltflib parses it; OpenCV decodes embedded images); the rest are
pure functions of what it read, as the specification defines them: a node hierarchy posed by a clip
at a time, and a primitive skinned by it. `camgen.actors.character` moves a character along a route.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from camgen.errors import ConfigError

CAMGEN_FROM_GLTF = np.array([[0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
"""glTF (x left, y up, z front) → camgen's actor frame (x front, y left, z up); a rotation."""

IN_PLACE_SPEED_M_S = 0.05
"""A clip whose body travels slower than this, m/s, walks in place: its walking speed must be given."""

_COMPONENT = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_NORMALISED_MAX = {np.uint8: 255.0, np.uint16: 65535.0, np.int8: 127.0, np.int16: 32767.0}


@dataclass(frozen=True)
class Material:
    """A glTF metallic-roughness material; images are (H, W, C) uint8 as stored (sRGB colour)."""

    base_color_factor: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    base_color_image: np.ndarray | None = None
    metallic_factor: float = 1.0
    roughness_factor: float = 1.0
    metallic_roughness_image: np.ndarray | None = None
    normal_image: np.ndarray | None = None
    occlusion_image: np.ndarray | None = None
    emissive_factor: tuple[float, float, float] = (0.0, 0.0, 0.0)
    emissive_image: np.ndarray | None = None
    double_sided: bool = False
    wrap: tuple[int, int] = (10497, 10497)
    """OpenGL wrap modes (S, T) of the base colour texture's sampler (10497 = REPEAT)."""


@dataclass(frozen=True)
class Primitive:
    node: int
    """The node whose mesh this is (its transform places an unskinned primitive)."""
    skin: int | None
    positions: np.ndarray
    """(V, 3) float64, in the mesh's own frame (glTF axes)."""
    normals: np.ndarray
    texcoords: np.ndarray | None
    """(V, 2) in OpenGL's convention (v up from the image's bottom)."""
    colours: np.ndarray | None
    """(V, 4) COLOR_0 as floats, or None."""
    joints: np.ndarray | None
    """(V, 4k) indices into the skin's joint list."""
    weights: np.ndarray | None
    """(V, 4k) weights, each row summing to one."""
    faces: np.ndarray
    """(F, 3) uint32 triangles."""
    material: Material


@dataclass(frozen=True)
class Channel:
    node: int
    path: str
    """"translation", "rotation" or "scale"."""
    times_s: np.ndarray
    values: np.ndarray
    """(K, C) keyframe values, or (K, 3, C) (in-tangent, value, out-tangent) for CUBICSPLINE."""
    interpolation: str


@dataclass(frozen=True)
class Clip:
    name: str
    channels: tuple[Channel, ...]

    @property
    def duration_s(self) -> float:
        return max((float(c.times_s[-1]) for c in self.channels), default=0.0)


@dataclass(frozen=True)
class Character:
    """A glTF scene's nodes (rest transforms), meshes, skins and animation clips."""

    path: str
    parents: np.ndarray
    """(N,) each node's parent index, −1 for a root; parents come before their children in `order`."""
    order: np.ndarray
    """Node indices, parents before children."""
    translations: np.ndarray
    """(N, 3) rest translations."""
    rotations: np.ndarray
    """(N, 4) rest rotations, quaternions (x, y, z, w)."""
    scales: np.ndarray
    """(N, 3) rest scales."""
    matrices: dict[int, np.ndarray]
    """Nodes given by a matrix (not animatable, §3.5.2): node → (4, 4)."""
    primitives: tuple[Primitive, ...]
    skins: tuple[tuple[np.ndarray, np.ndarray], ...]
    """Per skin: (joint node indices (J,), inverse bind matrices (J, 4, 4))."""
    clips: tuple[Clip, ...]
    scene_nodes: frozenset[int] = field(default_factory=frozenset)
    """The nodes of the file's default scene (and their descendants)."""
    names: tuple[str, ...] = ()
    """Each node's name ("" where the file gives none): joints are found by name (`camgen.actors.character`)."""

    def clip(self, name: str | None) -> Clip | None:
        """The clip of that name; None names the file's first clip (None when it has none)."""
        if name is None:
            return self.clips[0] if self.clips else None
        for clip in self.clips:
            if clip.name == name:
                return clip
        known = ", ".join(repr(c.name) for c in self.clips) or "none"
        raise ConfigError(f"{self.path}: has no animation named {name!r} (its animations: {known})")


# --------------------------------------------------------------------------------------------------
# Reading


def load_character(path: str | Path) -> Character:
    """Read a .glb or .gltf file (buffers embedded, in the .glb's binary chunk, or beside the file)."""
    import pygltflib

    path = Path(path)
    try:
        gltf = pygltflib.GLTF2().load(str(path))
    except Exception as exc:  # pygltflib raises whatever its JSON and struct readers raise
        raise ConfigError(f"{path}: is not a readable glTF 2.0 file ({type(exc).__name__}: {exc})") from exc
    if gltf is None:
        raise ConfigError(f"{path}: is not a readable glTF 2.0 file")
    version = str(getattr(gltf.asset, "version", "") or "")
    if not version.startswith("2."):
        raise ConfigError(f"{path}: is glTF {version or 'of no version'}; camgen reads glTF 2.0")
    buffers = [_buffer(gltf, i, path) for i in range(len(gltf.buffers))]
    reader = _Reader(gltf, buffers, path)

    n = len(gltf.nodes)
    parents = np.full(n, -1, dtype=np.int64)
    for i, node in enumerate(gltf.nodes):
        for child in node.children or ():
            parents[child] = i
    translations, rotations, scales = np.zeros((n, 3)), np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)), np.ones((n, 3))
    matrices = {}
    for i, node in enumerate(gltf.nodes):
        if node.matrix is not None and not np.allclose(node.matrix, np.eye(4).ravel()):
            matrices[i] = np.array(node.matrix, dtype=np.float64).reshape(4, 4).T  # column-major
        if node.translation is not None:
            translations[i] = node.translation
        if node.rotation is not None:
            rotations[i] = _normalised(np.array(node.rotation, dtype=np.float64))
        if node.scale is not None:
            scales[i] = node.scale
    order = _topological(parents)

    scene_index = gltf.scene if gltf.scene is not None else 0
    roots = gltf.scenes[scene_index].nodes if gltf.scenes else [i for i in range(n) if parents[i] < 0]
    in_scene = set()
    stack = list(roots or ())
    while stack:
        i = stack.pop()
        in_scene.add(i)
        stack.extend(gltf.nodes[i].children or ())

    materials = [reader.material(m) for m in gltf.materials]
    primitives = []
    for i, node in enumerate(gltf.nodes):
        if node.mesh is None or i not in in_scene:
            continue
        for primitive in gltf.meshes[node.mesh].primitives:
            primitives.append(reader.primitive(primitive, i, node.skin, materials))
    if not primitives:
        raise ConfigError(f"{path}: holds no triangle mesh in its scene; give a file with a mesh")

    skins = []
    for skin in gltf.skins:
        joints = np.array(skin.joints, dtype=np.int64)
        if skin.inverseBindMatrices is None:
            inverse = np.tile(np.eye(4), (len(joints), 1, 1))
        else:
            inverse = reader.accessor(skin.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1)
        skins.append((joints, inverse.astype(np.float64)))

    clips = []
    for k, animation in enumerate(gltf.animations):
        channels = []
        for channel in animation.channels:
            if channel.target.node is None or channel.target.path not in ("translation", "rotation", "scale"):
                continue  # morph-target weights and extension targets do not move the mesh here
            sampler = animation.samplers[channel.sampler]
            times = reader.accessor(sampler.input).astype(np.float64).ravel()
            values = reader.accessor(sampler.output).astype(np.float64)
            interpolation = sampler.interpolation or "LINEAR"
            width = 4 if channel.target.path == "rotation" else 3
            values = (
                values.reshape(len(times), 3, width) if interpolation == "CUBICSPLINE" else values.reshape(-1, width)
            )
            channels.append(Channel(channel.target.node, channel.target.path, times, values, interpolation))
        clips.append(Clip(animation.name or f"animation_{k}", tuple(channels)))
    return Character(
        path=str(path),
        parents=parents,
        order=order,
        translations=translations,
        rotations=rotations,
        scales=scales,
        matrices=matrices,
        primitives=tuple(primitives),
        skins=tuple(skins),
        clips=tuple(clips),
        scene_nodes=frozenset(in_scene),
        names=tuple(str(node.name or "") for node in gltf.nodes),
    )


def _buffer(gltf, index: int, path: Path) -> bytes:
    buffer = gltf.buffers[index]
    if buffer.uri is None:
        data = gltf.binary_blob()
        if data is None:
            raise ConfigError(f"{path}: buffer {index} has no data (no URI and no binary chunk)")
        return bytes(data)
    if buffer.uri.startswith("data:"):
        import base64

        return base64.b64decode(buffer.uri.split(",", 1)[1])
    beside = path.parent / buffer.uri
    try:
        return beside.read_bytes()
    except OSError as exc:
        raise ConfigError(
            f"{path}: its buffer {buffer.uri!r} cannot be read ({exc.strerror}); keep it beside the file"
        ) from exc


class _Reader:
    def __init__(self, gltf, buffers: list[bytes], path: Path):
        self.gltf, self.buffers, self.path = gltf, buffers, path
        self._images: dict[int, np.ndarray] = {}

    def accessor(self, index: int) -> np.ndarray:
        accessor = self.gltf.accessors[index]
        dtype = np.dtype(_COMPONENT[accessor.componentType]).newbyteorder("<")
        width = _WIDTH[accessor.type]
        out = np.zeros((accessor.count, width), dtype=dtype)
        if accessor.bufferView is not None:
            view = self.gltf.bufferViews[accessor.bufferView]
            data = self.buffers[view.buffer]
            start = (view.byteOffset or 0) + (accessor.byteOffset or 0)
            stride = view.byteStride or dtype.itemsize * width
            if accessor.type in ("MAT2", "MAT3") and dtype.itemsize < 4:
                raise ConfigError(f"{self.path}: accessor {index} packs small matrices, which camgen does not read")
            if stride == dtype.itemsize * width:
                out = np.frombuffer(data, dtype, accessor.count * width, start).reshape(accessor.count, width).copy()
            else:
                rows = np.lib.stride_tricks.as_strided(
                    np.frombuffer(data, np.uint8, len(data) - start, start),
                    (accessor.count, dtype.itemsize * width),
                    (stride, 1),
                )
                out = np.ascontiguousarray(rows).view(dtype).reshape(accessor.count, width).copy()
        sparse = getattr(accessor, "sparse", None)
        if sparse is not None and sparse.count:
            idx_view = self.gltf.bufferViews[sparse.indices.bufferView]
            idx = np.frombuffer(
                self.buffers[idx_view.buffer],
                np.dtype(_COMPONENT[sparse.indices.componentType]).newbyteorder("<"),
                sparse.count,
                (idx_view.byteOffset or 0) + (sparse.indices.byteOffset or 0),
            )
            val_view = self.gltf.bufferViews[sparse.values.bufferView]
            values = np.frombuffer(
                self.buffers[val_view.buffer], dtype, sparse.count * width,
                (val_view.byteOffset or 0) + (sparse.values.byteOffset or 0),
            ).reshape(sparse.count, width)  # fmt: skip
            out[idx] = values
        if accessor.normalized and dtype.type in _NORMALISED_MAX:
            return np.maximum(out.astype(np.float64) / _NORMALISED_MAX[dtype.type], -1.0)
        return out

    def image(self, texture_index: int | None) -> np.ndarray | None:
        if texture_index is None:
            return None
        source = self.gltf.textures[texture_index].source
        if source is None:
            return None
        if source not in self._images:
            image = self.gltf.images[source]
            if image.bufferView is not None:
                view = self.gltf.bufferViews[image.bufferView]
                start = view.byteOffset or 0
                raw = self.buffers[view.buffer][start : start + view.byteLength]
            elif image.uri and image.uri.startswith("data:"):
                import base64

                raw = base64.b64decode(image.uri.split(",", 1)[1])
            else:
                try:
                    raw = (self.path.parent / (image.uri or "")).read_bytes()
                except OSError as exc:
                    raise ConfigError(
                        f"{self.path}: its image {image.uri!r} cannot be read ({exc.strerror}); keep it beside the file"
                    ) from exc
            import cv2  # only for files with textures

            decoded = cv2.imdecode(np.frombuffer(raw, np.uint8), cv2.IMREAD_UNCHANGED)
            if decoded is None:
                raise ConfigError(f"{self.path}: image {source} is not a PNG or JPEG that OpenCV can decode")
            if decoded.ndim == 2:
                decoded = np.repeat(decoded[..., None], 3, axis=2)
            if decoded.dtype != np.uint8:
                decoded = (decoded / 257).astype(np.uint8)
            order = [2, 1, 0, 3][: decoded.shape[2]]  # OpenCV's BGR(A) → RGB(A)
            self._images[source] = np.ascontiguousarray(decoded[..., order])
        return self._images[source]

    def material(self, material) -> Material:
        pbr = material.pbrMetallicRoughness
        base = pbr.baseColorTexture if pbr is not None else None
        wrap = (10497, 10497)
        if base is not None:
            sampler_index = self.gltf.textures[base.index].sampler
            if sampler_index is not None:
                sampler = self.gltf.samplers[sampler_index]
                wrap = (sampler.wrapS or 10497, sampler.wrapT or 10497)
        return Material(
            base_color_factor=tuple(pbr.baseColorFactor) if pbr is not None and pbr.baseColorFactor else (1.0,) * 4,
            base_color_image=self.image(base.index if base is not None else None),
            metallic_factor=1.0 if pbr is None or pbr.metallicFactor is None else float(pbr.metallicFactor),
            roughness_factor=1.0 if pbr is None or pbr.roughnessFactor is None else float(pbr.roughnessFactor),
            metallic_roughness_image=self.image(
                pbr.metallicRoughnessTexture.index if pbr is not None and pbr.metallicRoughnessTexture else None
            ),
            normal_image=self.image(material.normalTexture.index if material.normalTexture else None),
            occlusion_image=self.image(material.occlusionTexture.index if material.occlusionTexture else None),
            emissive_factor=tuple(material.emissiveFactor or (0.0, 0.0, 0.0)),
            emissive_image=self.image(material.emissiveTexture.index if material.emissiveTexture else None),
            double_sided=bool(material.doubleSided),
            wrap=wrap,
        )

    def primitive(self, primitive, node: int, skin: int | None, materials: list[Material]) -> Primitive:
        mode = 4 if primitive.mode is None else primitive.mode
        if mode != 4:
            raise ConfigError(
                f"{self.path}: a primitive of node {node} is drawn in mode {mode}; camgen reads triangles (4)"
            )
        attributes = primitive.attributes
        if attributes.POSITION is None:
            raise ConfigError(f"{self.path}: a primitive of node {node} has no POSITION")
        positions = self.accessor(attributes.POSITION).astype(np.float64)
        faces = (
            np.arange(len(positions), dtype=np.uint32).reshape(-1, 3)
            if primitive.indices is None
            else self.accessor(primitive.indices).astype(np.uint32).reshape(-1, 3)
        )
        if attributes.NORMAL is not None:
            normals = self.accessor(attributes.NORMAL).astype(np.float64)
        else:  # §3.7.2.1: flat normals when none are given; smooth ones are the closest a shared vertex gets
            normals = _vertex_normals(positions, faces)
        texcoords = None
        if attributes.TEXCOORD_0 is not None:
            uv = self.accessor(attributes.TEXCOORD_0).astype(np.float64)
            texcoords = np.column_stack([uv[:, 0], 1.0 - uv[:, 1]])
        colours = None
        if attributes.COLOR_0 is not None:
            colours = self.accessor(attributes.COLOR_0).astype(np.float64)
            if colours.shape[1] == 3:
                colours = np.column_stack([colours, np.ones(len(colours))])
        joints = weights = None
        if skin is not None and attributes.JOINTS_0 is not None and attributes.WEIGHTS_0 is not None:
            sets = [(attributes.JOINTS_0, attributes.WEIGHTS_0)]
            extra = getattr(attributes, "JOINTS_1", None), getattr(attributes, "WEIGHTS_1", None)
            if extra[0] is not None and extra[1] is not None:
                sets.append(extra)
            joints = np.concatenate([self.accessor(j).astype(np.int64) for j, _ in sets], axis=1)
            weights = np.concatenate([self.accessor(w).astype(np.float64) for _, w in sets], axis=1)
            total = weights.sum(axis=1, keepdims=True)
            if np.any(total <= 0):
                raise ConfigError(
                    f"{self.path}: {int(np.count_nonzero(total <= 0))} vertices of node {node} have no skin weight"
                )
            weights = weights / total
        material = materials[primitive.material] if primitive.material is not None else Material()
        return Primitive(node, skin if joints is not None else None, positions, normals, texcoords, colours,
                         joints, weights, faces, material)  # fmt: skip


def _vertex_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    a, b, c = (positions[faces[:, k]] for k in range(3))
    face = np.cross(b - a, c - a)
    normals = np.zeros_like(positions)
    for k in range(3):
        np.add.at(normals, faces[:, k], face)
    return normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)


def _topological(parents: np.ndarray) -> np.ndarray:
    depth = np.zeros(len(parents), dtype=np.int64)
    for i in range(len(parents)):
        j, d = i, 0
        while parents[j] >= 0:
            j, d = parents[j], d + 1
            if d > len(parents):
                raise ConfigError("the glTF node hierarchy has a cycle")
        depth[i] = d
    return np.argsort(depth, kind="stable")


# --------------------------------------------------------------------------------------------------
# Animation and skinning


def _normalised(q: np.ndarray) -> np.ndarray:
    return q / np.maximum(np.linalg.norm(q, axis=-1, keepdims=True), 1e-300)


def slerp(q0: np.ndarray, q1: np.ndarray, u: float) -> np.ndarray:
    """Spherical linear interpolation of unit quaternions along the shorter arc."""
    dot = float(np.dot(q0, q1))
    if dot < 0.0:
        q1, dot = -q1, -dot
    if dot > 0.9995:
        return _normalised(q0 + u * (q1 - q0))
    theta = math.acos(min(dot, 1.0))
    s = math.sin(theta)
    return (math.sin((1 - u) * theta) / s) * q0 + (math.sin(u * theta) / s) * q1


def sample_channel(channel: Channel, time_s: float) -> np.ndarray:
    """A channel's value at `time_s` (held before the first and after the last keyframe)."""
    times, values = channel.times_s, channel.values
    cubic = channel.interpolation == "CUBICSPLINE"
    point = values[:, 1] if cubic else values
    if time_s <= times[0] or len(times) == 1:
        return point[0].copy()
    if time_s >= times[-1]:
        return point[-1].copy()
    k = int(np.searchsorted(times, time_s, side="right")) - 1
    dt = times[k + 1] - times[k]
    u = (time_s - times[k]) / dt
    if channel.interpolation == "STEP":
        return point[k].copy()
    if cubic:
        u2, u3 = u * u, u * u * u
        value = (
            (2 * u3 - 3 * u2 + 1) * values[k, 1]
            + (u3 - 2 * u2 + u) * dt * values[k, 2]
            + (-2 * u3 + 3 * u2) * values[k + 1, 1]
            + (u3 - u2) * dt * values[k + 1, 0]
        )
        return _normalised(value) if channel.path == "rotation" else value
    if channel.path == "rotation":
        return slerp(values[k], values[k + 1], u)
    return (1 - u) * values[k] + u * values[k + 1]


def _quaternion_matrix(q: np.ndarray) -> np.ndarray:
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def global_transforms(character: Character, clip: Clip | None, time_s: float) -> np.ndarray:
    """(N, 4, 4) every node's global transform (glTF axes) with `clip` sampled at `time_s`."""
    t, r, s = character.translations.copy(), character.rotations.copy(), character.scales.copy()
    for channel in clip.channels if clip is not None else ():
        value = sample_channel(channel, time_s)
        {"translation": t, "rotation": r, "scale": s}[channel.path][channel.node] = value
    G = np.empty((len(t), 4, 4))
    for i in character.order:
        local = character.matrices.get(int(i))
        if local is None:
            local = np.eye(4)
            local[:3, :3] = _quaternion_matrix(_normalised(r[i])) * s[i]
            local[:3, 3] = t[i]
        parent = character.parents[i]
        G[i] = local if parent < 0 else G[parent] @ local
    return G


def pose_primitive(character: Character, primitive: Primitive, G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(positions (V, 3), normals (V, 3)) of a primitive in the file's scene frame (glTF axes)."""
    if primitive.skin is None:
        M = G[primitive.node]
        A = np.broadcast_to(M[:3, :3], (len(primitive.positions), 3, 3))
        positions = primitive.positions @ M[:3, :3].T + M[:3, 3]
    else:
        joints, inverse_bind = character.skins[primitive.skin]
        J = G[joints] @ inverse_bind  # (J, 4, 4) joint matrices, §3.7.3.3
        blended = np.einsum("vk,vkij->vij", primitive.weights, J[primitive.joints])
        A = blended[:, :3, :3]
        positions = np.einsum("vij,vj->vi", A, primitive.positions) + blended[:, :3, 3]
    # Normals by the inverse transpose (the blended matrix may scale); |det| > 0 for any sane pose.
    normals = np.einsum("vji,vj->vi", np.linalg.inv(A), primitive.normals)
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    return positions, normals


def pose_character(character: Character, clip: Clip | None, time_s: float) -> list[tuple[np.ndarray, np.ndarray]]:
    G = global_transforms(character, clip, time_s)
    return [pose_primitive(character, p, G) for p in character.primitives]


def clip_ground_travel(character: Character, clip: Clip) -> tuple[np.ndarray, float]:
    """(Δ (3,), duration_s): how far the clip carries the character over the ground (glTF x, z) from its
    first to its last keyframe, measured on the mean of its vertices (the body's centre)."""
    duration = clip.duration_s
    if duration <= 0:
        return np.zeros(3), 0.0
    travel = _centre(character, clip, duration) - _centre(character, clip, 0.0)
    travel[1] = 0.0
    return travel, duration


def clip_ground_speed_m_s(character: Character, clip: Clip, scale: float) -> float:
    """The speed the clip itself carries the character at over the ground, m/s, at `scale` (0 for a
    clip without duration); under `IN_PLACE_SPEED_M_S` it walks in place."""
    travel, duration = clip_ground_travel(character, clip)
    return float(np.linalg.norm(travel)) * scale / duration if duration > 0 else 0.0


def _centre(character: Character, clip: Clip, time_s: float) -> np.ndarray:
    return np.concatenate([p for p, _ in pose_character(character, clip, time_s)]).mean(axis=0)


def posed_bounds(character: Character, clips: list[Clip | None], samples: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """(low (3,), high (3,)) of the character's vertices in camgen's axes over `clips` (None: the rest
    pose), each sampled at `samples` times over its duration."""
    low, high = np.full(3, np.inf), np.full(3, -np.inf)
    for clip in clips:
        duration = clip.duration_s if clip is not None else 0.0
        for t in np.linspace(0.0, duration, samples) if duration > 0 else [0.0]:
            p = np.concatenate([q for q, _ in pose_character(character, clip, float(t))])
            p = p @ CAMGEN_FROM_GLTF[:3, :3].T
            low, high = np.minimum(low, p.min(axis=0)), np.maximum(high, p.max(axis=0))
    return low, high
