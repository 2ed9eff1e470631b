"""Linear HDR radiance, metric depth and instance ids from pyrender, in one draw.

pyrender 0.1.45 reads back 8-bit, clamped, gamma-encoded colour and a depth buffer resolved from
multisamples. This module keeps pyrender's scene graph, meshes, PBR materials, lights, shadow maps and
draw calls, and replaces what it renders into and with:

- a framebuffer of our own with up to three colour attachments, one per pass: RGBA32F radiance,
  RG32F depth_m and R32UI instance_id, plus a 32-bit float depth buffer, single-sampled, so every
  value is the one at the pixel centre;
- shaders of our own, handed to pyrender through its program cache: its lit shader without gamma
  and clamp, writing all three targets (multiple render targets: one draw), and a geometry-only
  shader for depth and ids without lighting;
- a projection built from OpenCV intrinsics with pixel centres at integers and rows top-down, so
  arrays come back in image order without a flip.

Radiance unit: linear RGB (BT.709 primaries) scaled so that 0.2126 R + 0.7152 G + 0.0722 B is the
luminance in cd/m² (see `camgen.render.scene_graph`); unclamped. depth_m: distance along the optical
axis (camera z), m, +inf where no geometry is hit. instance_id: uint32, 0 for background.

The sky fills the pixels no surface covers, except where their ray goes down to the scene's far ground
(`camgen.render.scene_graph.FarGround`: the ground plane continued to the horizon), which fills those,
and shows through glass in the share the glass transmits (the radiance target's alpha is coverage,
`composite_background`); fog (`camgen.world.fog`) then blends every radiance pixel towards the horizon
sky by its distance (behind glass, by both the glass's and the background's), which a draw with fog renders
beside the radiance even when depth_m is not asked for (and does not return).
"""

from __future__ import annotations

import math
import operator
import sys
import weakref
from collections import OrderedDict
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from camgen.config.placement import box_corners
from camgen.config.scene import MAX_LIGHTS
from camgen.errors import ConfigError
from camgen.render.gl import pyrender

from OpenGL import GL  # isort: skip — after camgen.render.gl, which selects the EGL platform
from pyrender.constants import SHADOW_TEX_SZ, ProgramFlags, RenderFlags  # isort: skip
from pyrender.light import DirectionalLight, SpotLight  # isort: skip
from pyrender.shader_program import ShaderProgram, ShaderProgramCache  # isort: skip

SHADER_DIR = Path(__file__).parent / "shaders"
PASSES = ("radiance", "depth_m", "instance_id")
# Geometry closer than this to the camera is clipped, m.
NEAR_CLIP_M = 0.05

# Cleared depth_m: finite, because pyrender draws with blending on (GL_ONE, GL_ZERO) and 0·inf is NaN;
# read back as +inf.
_NO_DEPTH = np.finfo(np.float32).max

# The OpenGL camera looks down −z with y up; OpenCV's looks down +z with y down.
_GL_FROM_CV = np.diag([1.0, -1.0, -1.0, 1.0])


@dataclass(frozen=True)
class View:
    """An ideal pinhole camera for one draw (OpenCV conventions, DESIGN.md)."""

    K_px: np.ndarray
    """3×3 camera matrix; pixel centres at integer coordinates, (0, 0) the top-left pixel."""
    T_world_from_cam: np.ndarray
    """4×4 pose of the OpenCV camera frame (x right, y down, z forward) in the world."""
    width_px: int
    height_px: int

    def scaled(self, factor: int) -> View:
        """The same view sampled `factor` times more finely per axis (for supersampling).

        Output pixel u covers [u − ½, u + ½]; sub-pixel centres sit at (u + ½)·s − ½, so the
        principal point moves to (c + ½)·s − ½.
        """
        K = self.K_px.copy()
        K[0, 0] *= factor
        K[1, 1] *= factor
        K[0, 2] = (K[0, 2] + 0.5) * factor - 0.5
        K[1, 2] = (K[1, 2] + 0.5) * factor - 0.5
        return View(K, self.T_world_from_cam, self.width_px * factor, self.height_px * factor)

    def key(self) -> tuple:
        """What a draw through this view depends on, as a hashable key: its size, K and pose (bytes)."""
        return self.width_px, self.height_px, self.K_px.tobytes(), self.T_world_from_cam.tobytes()

    def cropped(self, rect_px: tuple[int, int, int, int]) -> View:
        """The part (x0, y0, x1, y1) of this view (x1, y1 exclusive) as a view of its own: its pixel (u, v)
        sees what this view sees at (u + x0, v + y0)."""
        x0, y0, x1, y1 = rect_px
        K = self.K_px.copy()
        K[0, 2] -= x0
        K[1, 2] -= y0
        return View(K, self.T_world_from_cam, x1 - x0, y1 - y0)


@dataclass(frozen=True)
class ShadowFit:
    """What a draw fits its shadow maps to, instead of its own view and the scene's current bounds.

    Draws that must agree pixel for pixel share one: a frame's motion sub-frames (whose actors move the
    scene's bounds and whose jittered views move the frustum) and a crop of a frame's view (whose frustum is
    smaller). Without it each draw's sun shadow map is fitted to that draw alone, so its texels, and the
    shadow edges they sample, move between draws that see the same surfaces."""

    view: View
    """The view whose frustum the sun's shadow map covers (`seen_part_of_box_m`)."""
    low_m: np.ndarray
    """(3,) world corner of a box holding every shadow caster at any time (an actor's whole route)."""
    high_m: np.ndarray
    """(3,) its opposite corner."""


@dataclass
class Passes:
    """What one draw returns; a pass that was not asked for is None."""

    radiance: np.ndarray | None = None
    """(H, W, 3) float32, cd/m² (see the module docstring)."""
    depth_m: np.ndarray | None = None
    """(H, W) float32, camera z in metres, +inf for background."""
    instance_id: np.ndarray | None = None
    """(H, W) uint32, 0 for background."""


def gl_projection(K_px: np.ndarray, width_px: int, height_px: int, near_m: float, far_m: float) -> np.ndarray:
    """OpenGL projection whose window rows run top-down and whose pixel centres are OpenCV's.

    An OpenCV pixel (u, v) has its centre at window coordinates (u + ½, v + ½) with row 0 at the
    top: x_ndc = 2(u + ½)/W − 1 and y_ndc = 2(v + ½)/H − 1 for u = fx·X/Z + cx, v = fy·Y/Z + cy,
    written in the OpenGL camera frame (X, −Y, −Z). Rows top-down reverse the winding of triangles,
    so draws use glFrontFace(GL_CW).
    """
    fx, fy, cx, cy = K_px[0, 0], K_px[1, 1], K_px[0, 2], K_px[1, 2]
    s = K_px[0, 1]
    P = np.zeros((4, 4))
    P[0, 0] = 2.0 * fx / width_px
    P[0, 1] = -2.0 * s / width_px
    P[0, 2] = 1.0 - 2.0 * (cx + 0.5) / width_px
    P[1, 1] = 2.0 * fy / height_px
    P[1, 2] = 2.0 * (cy + 0.5) / height_px - 1.0
    P[2, 2] = (far_m + near_m) / (near_m - far_m)
    P[2, 3] = 2.0 * far_m * near_m / (near_m - far_m)
    P[3, 2] = -1.0
    # Flip y: row v of the framebuffer then holds image row v.
    return np.diag([1.0, -1.0, 1.0, 1.0]) @ P


def gl_camera_pose(T_world_from_cam: np.ndarray) -> np.ndarray:
    """Pose of the OpenGL camera (x right, y up, looking down −z) for an OpenCV camera pose."""
    return np.asarray(T_world_from_cam, dtype=np.float64) @ _GL_FROM_CV


class _LinearProgramCache(ShaderProgramCache):
    """pyrender's program cache, answering with camgen's shaders for its lit and depth-only programs, each
    compiled without the light loops of the kinds that the scene being drawn has none of (`absent_lights`:
    the defines NO_SUNS, NO_POINT_LIGHTS, NO_SPOT_LIGHTS of `linear_mesh.frag`; a loop over no lights adds
    nothing, so the same pixels) and with the paths of the primitive's kind of material only (`material_kind`:
    CLEARCOATED_MATERIAL, TRANSMISSIVE_MATERIAL; the same code as a branch on a uniform, which llvmpipe ran for
    every surface)."""

    absent_lights: tuple[str, ...] = ()
    """The defines for the kinds of light the current scene has none of (`_PassRenderer.forward` sets it)."""
    material_kind: tuple[str, ...] = ()
    """The defines of the primitive being drawn's kind of material (`material_defines`; set per primitive)."""

    OURS = {
        "mesh.vert": "linear_mesh.vert",
        "mesh.frag": "linear_mesh.frag",
        "mesh_depth.vert": "geometry.vert",
        "mesh_depth.frag": "geometry.frag",
        "depth_prepass.frag": "depth_prepass.frag",
    }

    def __init__(self, shader_dir=None):
        super().__init__(shader_dir)
        self._answers: dict[tuple, _RememberingProgram] = {}
        """Each asked-for program by what it was asked with (and `absent_lights`): pyrender is asked once per
        primitive and draw, and its own lookup splits paths, asks PyOpenGL for the context and sorts the
        defines each time (about a tenth of a millisecond; 300 primitives a step of a small simulated view)."""

    def get_program(self, vertex_shader, fragment_shader, geometry_shader=None, defines=None):
        extra = self.absent_lights + self.material_kind if fragment_shader == "mesh.frag" else ()
        key = (vertex_shader, fragment_shader, geometry_shader, tuple((defines or {}).items()), extra)
        program = self._answers.get(key)
        if program is not None:
            return program

        def ours(name):
            return str(SHADER_DIR / self.OURS[name]) if name in self.OURS else name

        if extra:
            defines = {**(defines or {}), **dict.fromkeys(extra, 1)}
        program = super().get_program(ours(vertex_shader), ours(fragment_shader), geometry_shader, defines)
        if not isinstance(program, _RememberingProgram):
            program.__class__ = _RememberingProgram
            program.locations, program.values = {}, {}
        if fragment_shader == "mesh.frag":  # its depth pre-pass: the same vertex shader, source and defines
            program.prepass_asked = (vertex_shader, "depth_prepass.frag", geometry_shader, defines)
        self._answers[key] = program
        return program

    def prepass_program(self, program: _RememberingProgram) -> _RememberingProgram:
        """The depth pre-pass program of a lit program (`_PassRenderer.forward`): its vertex shader, compiled from the
        same source with the same defines, and a fragment shader that writes nothing."""
        prepass = self.get_program(*program.prepass_asked)
        if not prepass._in_context():
            prepass._add_to_context()
        return prepass

    def clear(self):
        self._answers.clear()
        super().clear()


@contextmanager
def _linked_without_validation() -> Iterator[None]:
    """pyrender's programs linked (link errors raised) but not validated: PyOpenGL's `compileProgram`
    validates a program just linked, whose sampler uniforms all still name texture unit 0, and refuses one
    with samplers of two types (a sun's 2D array of cascades beside the materials' 2D maps) as "different
    types refer to the same texture image unit"; at a draw each sampler has its own unit (`_bind_lighting`)."""
    from OpenGL.GL import shaders

    validating = shaders.compileProgram

    def link(*shader_ids):
        program = GL.glCreateProgram()
        for shader in shader_ids:
            GL.glAttachShader(program, shader)
        GL.glLinkProgram(program)
        if GL.glGetProgramiv(program, GL.GL_LINK_STATUS) != GL.GL_TRUE:
            raise RuntimeError(f"shader program failed to link: {GL.glGetProgramInfoLog(program)!r}")
        for shader in shader_ids:
            GL.glDeleteShader(shader)
        return program

    shaders.compileProgram = link
    try:
        yield
    finally:
        shaders.compileProgram = validating


class _RememberingProgram(ShaderProgram):
    """pyrender's shader program, remembering each uniform's location and last value.

    pyrender sets every uniform of every primitive for every draw (camera, material, each light) and
    asks OpenGL for the uniform's location each time: about 1,500 calls through PyOpenGL per draw of the
    parking lot, 148,000 per 4K frame with motion blur (measured on an H100, where they were the largest
    cost of a draw). A uniform keeps its value in its program until set again, so setting it to the
    value it holds changes nothing: those calls are skipped, and locations are asked once. Values are
    compared as pyrender would send them (the same conversions), so what OpenGL holds is bit for bit
    what pyrender's own `set_uniform` leaves there."""

    locations: dict[str, int]
    values: dict[str, tuple]

    def _add_to_context(self):
        with _linked_without_validation():
            super()._add_to_context()

    def set_uniform(self, name, value, unsigned=False):
        location = self.locations.get(name)
        if location is None:
            location = self.locations[name] = int(GL.glGetUniformLocation(self._program_id, name))
        if location == -1:  # pyrender ignores a name its shader does not use; so do we
            return
        if isinstance(value, np.ndarray):
            held = (value.dtype.str, value.shape, value.tobytes(), unsigned)
        else:  # a float by its bits: −0.0 is not 0.0 to OpenGL's copy of it
            held = (type(value), value.hex() if isinstance(value, float) else value, unsigned)
        if self.values.get(name) == held:
            return
        try:  # pyrender's dispatch (shader_program.py), without its second location lookup
            if isinstance(value, np.ndarray):
                if value.ndim == 1:
                    if np.issubdtype(value.dtype, np.unsignedinteger) or unsigned:
                        kind, value = "u", value.astype(np.uint32)
                    elif np.issubdtype(value.dtype, np.integer):
                        kind, value = "i", value.astype(np.int32)
                    else:
                        kind, value = "f", value.astype(np.float32)
                    self._FUNC_MAP[(value.shape[0], kind)](location, 1, value)
                else:
                    self._FUNC_MAP[(value.shape[0], value.shape[1])](location, 1, GL.GL_TRUE, value)
            elif isinstance(value, float):
                GL.glUniform1f(location, value)
            elif isinstance(value, int):  # bool too, as pyrender (its bool branch is never reached)
                (GL.glUniform1ui if unsigned else GL.glUniform1i)(location, value)
            else:
                return  # pyrender raises and swallows 'Invalid data type'
        except Exception:  # pyrender swallows every error of setting a uniform
            return
        self.values[name] = held

    def delete(self):
        self.locations.clear()
        self.values.clear()
        super().delete()


class _Framebuffer:
    """An offscreen target with one colour attachment per pass and a float depth buffer."""

    # depth_m uses two channels of which it reads one: pyrender draws with blending on (GL_ONE,
    # GL_ZERO), and Mesa's llvmpipe blends into a one-channel R32F target as zeros (measured).
    FORMATS = {"radiance": GL.GL_RGBA32F, "depth_m": GL.GL_RG32F, "instance_id": GL.GL_R32UI}

    def __init__(self, width_px: int, height_px: int, passes: tuple[str, ...]):
        self.width_px, self.height_px, self.passes = width_px, height_px, passes
        self.coverage: np.ndarray | None = None
        """(H, W) float32 after a `read` of radiance: the alpha of the radiance target, 0 where no surface
        was drawn (the sky and the far ground), 1 over any opaque surface, and 1 − τ where only glass lies in
        front of the background, τ the product of its panes' transmittances (`_blend_with_coverage`)."""
        self.fbo = GL.glGenFramebuffers(1)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.fbo)
        self.renderbuffers = []
        for name in passes:
            self.renderbuffers.append(self._attach(self.FORMATS[name], GL.GL_COLOR_ATTACHMENT0 + PASSES.index(name)))
        # A stencil beside the depth: a lit draw's depth pre-pass keeps the first surface drawn at a pixel's depth
        # (`_PassRenderer.forward`).
        self.renderbuffers.append(self._attach(GL.GL_DEPTH32F_STENCIL8, GL.GL_DEPTH_STENCIL_ATTACHMENT))
        status = GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
        if status != GL.GL_FRAMEBUFFER_COMPLETE:
            raise RuntimeError(f"OpenGL framebuffer for {passes} at {width_px}×{height_px} incomplete: {status:#x}")
        self.draw_buffers = [
            GL.GL_COLOR_ATTACHMENT0 + i if name in passes else GL.GL_NONE for i, name in enumerate(PASSES)
        ]

    def _attach(self, internal_format, attachment):
        rb = GL.glGenRenderbuffers(1)
        GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, rb)
        GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, internal_format, self.width_px, self.height_px)
        GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, attachment, GL.GL_RENDERBUFFER, rb)
        return rb

    def bind(self) -> None:
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.fbo)
        GL.glDrawBuffers(len(self.draw_buffers), self.draw_buffers)
        GL.glViewport(0, 0, self.width_px, self.height_px)

    def clear(self, sky_luminance_cd_m2: float) -> None:
        if "radiance" in self.passes:
            # Alpha 0 marks the sky: every opaque surface writes alpha 1, glass its coverage (`read`).
            GL.glClearBufferfv(GL.GL_COLOR, 0, np.array([sky_luminance_cd_m2] * 3 + [0.0], np.float32))
        if "depth_m" in self.passes:
            GL.glClearBufferfv(GL.GL_COLOR, 1, np.full(4, _NO_DEPTH, np.float32))
        if "instance_id" in self.passes:
            GL.glClearBufferuiv(GL.GL_COLOR, 2, np.zeros(4, np.uint32))
        GL.glClearBufferfi(GL.GL_DEPTH_STENCIL, 0, 1.0, 0)

    def copy_from(self, other: _Framebuffer) -> None:
        """Blit every pass and the depth buffer of `other` (same size and passes) into this one."""
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, other.fbo)
        GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, self.fbo)
        w, h = self.width_px, self.height_px
        for name in self.passes:
            attachment = GL.GL_COLOR_ATTACHMENT0 + PASSES.index(name)
            GL.glReadBuffer(attachment)
            GL.glDrawBuffer(attachment)
            GL.glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL.GL_COLOR_BUFFER_BIT, GL.GL_NEAREST)
        GL.glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL.GL_DEPTH_BUFFER_BIT | GL.GL_STENCIL_BUFFER_BIT, GL.GL_NEAREST)

    def read(self, rect_px: tuple[int, int, int, int] | None = None) -> Passes:
        """Every pass, of the whole target or of its pixels (x0, y0, x1, y1; x1, y1 exclusive)."""
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self.fbo)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        x, y, w, h = (0, 0, self.width_px, self.height_px) if rect_px is None else _origin_size(rect_px)
        out = Passes()
        for name in self.passes:
            GL.glReadBuffer(GL.GL_COLOR_ATTACHMENT0 + PASSES.index(name))
            if name == "radiance":
                # Colour and alpha read apart, each straight into its own array: OpenGL's conversion gives the same
                # values as reading RGBA and splitting it with OpenCV (which beat numpy's strided copy), in less
                # time (a 2816 × 1624 read, 25 → 16 ms; llvmpipe, load 6).
                out.radiance = np.empty((h, w, 3), np.float32)
                GL.glReadPixels(x, y, w, h, GL.GL_RGB, GL.GL_FLOAT, out.radiance)
                self.coverage = np.empty((h, w), np.float32)
                GL.glReadPixels(x, y, w, h, GL.GL_ALPHA, GL.GL_FLOAT, self.coverage)
            elif name == "depth_m":
                data = GL.glReadPixels(x, y, w, h, GL.GL_RED, GL.GL_FLOAT)
                depth = np.frombuffer(data, np.float32).reshape(h, w).copy()
                depth[depth == _NO_DEPTH] = np.inf
                out.depth_m = depth
            else:
                data = GL.glReadPixels(x, y, w, h, GL.GL_RED_INTEGER, GL.GL_UNSIGNED_INT)
                out.instance_id = np.frombuffer(data, np.uint32).reshape(h, w)
        return out

    def delete(self) -> None:
        GL.glDeleteFramebuffers(1, [self.fbo])
        GL.glDeleteRenderbuffers(len(self.renderbuffers), self.renderbuffers)


def check_gl_features(version: tuple[int, int], extensions: set[str], gl_renderer: str) -> None:
    """Refuse an OpenGL without what camgen's shaders use beyond pyrender's 3.3: texture gathers (OpenGL 4.0 or
    GL_ARB_texture_gather; the shadow lookups) and 2D array textures (3.0), with a message that says what to
    do, instead of a shader compiler's log at the first draw."""
    if version >= (4, 0) or "GL_ARB_texture_gather" in extensions:
        return
    raise ConfigError(
        f"OpenGL {version[0]}.{version[1]} ({gl_renderer}) lacks texture gathers (OpenGL 4.0 or "
        "GL_ARB_texture_gather), which camgen's shadow lookups use; render with Mesa's llvmpipe (headless EGL, "
        "OpenGL 4.5, no GPU needed) or a GPU driver with OpenGL 4.0 or newer"
    )


def copies_images(version: tuple[int, int], extensions: set[str]) -> bool:
    """Whether this OpenGL has glCopyImageSubData (4.3 or GL_ARB_copy_image), with which a sun's cascades start
    from the kept depths of the casters that held still (`_PassRenderer.keep_still_casters`); without it (an
    OpenGL 4.0–4.2 that `check_gl_features` accepts) every caster is drawn, the same texels."""
    return version >= (4, 3) or "GL_ARB_copy_image" in extensions


def _origin_size(rect_px: tuple[int, int, int, int]) -> tuple[int, int, int, int]:
    """(x, y, width, height) of a rectangle (x0, y0, x1, y1), x1 and y1 exclusive."""
    x0, y0, x1, y1 = rect_px
    return x0, y0, x1 - x0, y1 - y0


class _StillCasters:
    """Which casters of a sun's cascade `_PassRenderer._sun_shadow_pass` copies from its last draw of the
    cascade instead of drawing again: bookkeeping only (the textures are the renderer's).

    Per (sun, cascade) it remembers the last pass (its scene, map size, light matrix and each reaching node's
    look count, `_PassRenderer.caster_versions`) and the kept set (the same key, and the counts of the
    nodes whose depths the kept layer holds). A pass is a "hit" when its key is the kept one's and every
    kept node reaches it with the same count: the kept depths stand for those nodes. Otherwise, when the
    key is the last pass's (the light and the map's fit held) and some reaching nodes kept their counts since
    then (parked vehicles, buildings; not the walkers), those are drawn first and kept ("keep"); else every
    node is drawn ("none"): a head that turns refits its cascades at every frame, and keeps nothing."""

    def __init__(self) -> None:
        self._last: dict[tuple[int, int], tuple[weakref.ref, tuple, dict[int, int]]] = {}
        self._kept: dict[tuple[int, int], tuple[weakref.ref, tuple, dict[int, int]]] = {}

    def plan(self, scene, light_node, layer: int, size: int, light_matrix: np.ndarray, nodes: list, versions: dict):
        """("hit" | "keep" | "none", the nodes whose depths are kept, the nodes to draw), `nodes` split."""
        slot = (id(light_node), layer)
        key = (id(light_node), size, np.asarray(light_matrix, np.float64).tobytes())
        counts = {id(node): versions.get(id(node)) for node in nodes}
        kept = self._kept.get(slot)
        last, self._last[slot] = self._last.get(slot), (weakref.ref(scene), key, counts)
        if kept is not None and kept[0]() is scene and kept[1] == key:
            if all(counts.get(node) == count for node, count in kept[2].items()):
                return "hit", *_split(nodes, kept[2])
        self._kept.pop(slot, None)
        if last is None or last[0]() is not scene or last[1] != key:
            return "none", [], nodes
        held = {node: count for node, count in counts.items() if count is not None and last[2].get(node) == count}
        if not held:
            return "none", [], nodes
        self._kept[slot] = (weakref.ref(scene), key, held)
        return "keep", *_split(nodes, held)

    def kept_entry(self, light_node, layer: int) -> tuple | None:
        """The kept set of a sun's cascade (`plan` made it: a new object whenever the kept layer is drawn again),
        or None."""
        return self._kept.get((id(light_node), layer))


def _split(nodes: list, held: dict[int, int]) -> tuple[list, list]:
    """`nodes` in and out of `held` (by id), each in their order."""
    return [n for n in nodes if id(n) in held], [n for n in nodes if id(n) not in held]


def caster_versions(graph) -> dict[int, int]:
    """Per mesh node (by id) of `graph` whose look is counted: its `SceneGraph.look_versions` count if it
    moves, 0 if it is still environment (it never changes). Other graphs count nothing."""
    versions = {id(node): 0 for node in getattr(graph, "still_nodes", ())}
    counts = getattr(graph, "look_versions", None)
    if counts:
        versions.update((id(node), count) for node, count in zip(graph.moving_nodes, counts, strict=True))
    return versions


CASCADE_FITS_KEPT = 8
"""Cascade fits a renderer keeps (`_PassRenderer._cascade_matrices`): each of a few views' suns."""


@dataclass
class _SunPassPlan:
    """What one cascade's pass draws (`_PassRenderer._sun_shadow_plan`): `mode` ("hit", "keep" or "none",
    `_StillCasters.plan`), the casters whose depths are kept and the others, the kept set (`_StillCasters.kept_entry`),
    the array of kept depths, and the cascade's (V, P)."""

    mode: str
    kept: list
    others: list
    entry: tuple | None
    kept_array: int | None
    V: np.ndarray
    P: np.ndarray


def _float_table_texture(table: np.ndarray, texture: int | None = None) -> int:
    """A float 2D texture holding `table` ((H, W) one channel, or (H, W, 3)), made, or filled again in `texture`,
    and left bound on the active unit: sampled bilinearly, repeating across (an angle that wraps: an IES table's C,
    the sky's azimuth) and clamped at its first and last rows."""
    table = np.ascontiguousarray(table, dtype=np.float32)
    internal, layout = (GL.GL_R32F, GL.GL_RED) if table.ndim == 2 else (GL.GL_RGB32F, GL.GL_RGB)
    texture = int(GL.glGenTextures(1)) if texture is None else texture
    GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
    GL.glTexImage2D(GL.GL_TEXTURE_2D, 0, internal, table.shape[1], table.shape[0], 0, layout, GL.GL_FLOAT, table)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_S, GL.GL_REPEAT)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_T, GL.GL_CLAMP_TO_EDGE)
    return texture


SKY_MAP_TEXELS = (256, 64)
"""Columns (azimuth over 360°) and rows (elevation 0–90°) of `SkyMap`: 1.4° a texel, against the clear sky's
circumsolar peak, which falls by e over 19° (indicatrix d = −3 rad⁻¹: `camgen.world.sky`)."""


class SkyMap:
    """The graph's CIE sky (`camgen.world.sky.sky_radiance`) over the upper hemisphere as a float texture,
    which the lit shader's `sky_along` reads for what a smooth clear coat and glass mirror (`mirrored_environment`):
    texel (i, j) holds the radiance at azimuth (i + ½)/W·360° − 180° (atan2(y, x)) and elevation (j + ½)/H·90°,
    sampled bilinearly (repeating in azimuth). Made again when the sky changes (`_sky_key`: its type, zenith
    luminance and the sun, which a dusk moves frame by frame). A uniform sky has none: the shader mirrors
    `ambient_light` (radiance E/π) there, as before the map."""

    def __init__(self) -> None:
        self.texture: int | None = None
        self.key: tuple | None = None
        self.used = False

    @staticmethod
    def directions() -> np.ndarray:
        """(H, W, 3) unit world directions of the texel centres (z up)."""
        columns, rows = SKY_MAP_TEXELS
        azimuth = (np.arange(columns) + 0.5) / columns * 2.0 * math.pi - math.pi
        elevation = (np.arange(rows) + 0.5) / rows * 0.5 * math.pi
        el, az = np.meshgrid(elevation, azimuth, indexing="ij")
        return np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], axis=-1)

    def update(self, graph) -> None:
        """Make the map of `graph`'s sky unless it is the one made last; a uniform sky uses none."""
        from camgen.world.sky import SKY_TYPES, sky_radiance

        sky = getattr(graph, "sky", "uniform")
        self.used = sky in SKY_TYPES
        if not self.used:
            return
        key = _sky_key(graph)
        if key == self.key and self.texture is not None:
            return
        sun = graph.sun_direction if graph.sun_direction is not None else np.array([0.0, 0.0, 1.0])
        radiance = np.ascontiguousarray(sky_radiance(self.directions(), sun, sky, graph.sky_luminance_cd_m2))
        self.texture = _float_table_texture(radiance, self.texture)
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
        self.key = key

    def bind(self, program, unit: int) -> None:
        """The map on texture `unit` for `program` (every lit program declares the sampler: left at unit 0 it
        would share a unit with another sampler type, which OpenGL refuses at the draw), and whether it is used."""
        program.set_uniform("sky_map_used", int(self.used))
        # The sampler's own unit first: binding on the unit left active (the last spot-light table's or shadow
        # map's) would replace that texture for this primitive.
        GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
        if self.texture is None:
            # a uniform sky before any map: the sampler still needs a unit of its own and a 2D texture there
            self.texture = _float_table_texture(np.zeros((1, 1, 3), np.float32))
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.texture)
        program.set_uniform("sky_map", unit)

    def delete(self) -> None:
        if self.texture is not None:
            GL.glDeleteTextures([self.texture])
        self.texture, self.key = None, None


class _PassRenderer(pyrender.Renderer):
    """pyrender's renderer with camgen's shaders and a forward pass that sets each node's id."""

    def __init__(self):
        super().__init__(1, 1)
        self._program_cache = _LinearProgramCache()
        self._profile_textures: dict[int, tuple[weakref.ref, int]] = {}
        """Per scene (by id, with a weak reference to tell a reused id): its spot-light table texture."""
        self.texture_lod_bias = 0.0
        """Added to every material texture's level of detail in the current draw (`Renderer.draw`)."""
        self.sky_map = SkyMap()
        """The CIE sky's radiance that smooth coats and glass mirror (`SkyMap`), set for each lit draw."""
        self.depth_prepass = False
        """Whether a lit draw draws its depth first and shades each pixel once (`forward`); False shades every
        fragment that passes the depth test as it comes (the same pixels, at more cost on llvmpipe). `Renderer`
        turns it on for llvmpipe only, where it was measured (bit for bit, and cheaper): a GPU culls hidden
        fragments in hardware before shading them, and its compiler need not place a vertex bit for bit alike in
        two programs (no `invariant gl_Position`), which GL_EQUAL needs. Not measured on a GPU."""
        self.mirrored = False
        """Whether the current draw's view is mirrored (an improper pose: `camgen.render.wet`), which reverses
        the winding of its triangles on screen."""
        self.shadow_view: View | None = None
        """The view (and `shadow_clip_m` its near and far planes, m) a sun's cascaded shadow maps are fitted
        to in the current draw: the `ShadowFit`'s, or the draw's own."""
        self.shadow_clip_m: tuple[float, float] = (NEAR_CLIP_M, 1.0)
        self.shadow_bounds_m: tuple[np.ndarray, np.ndarray] | None = None
        """(low, high) world box the current draw's shadow maps span instead of the scene's bounds (a
        `ShadowFit`'s), or None."""
        self._sun_cascades: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {}
        """Per sun's node (by id): its cascades' (V, P) in the last shadow-map pass, finest first."""
        self._sun_arrays_drawn: dict[int, int] = {}
        """Per sun's node (by id): the array texture its cascades were drawn into in the last shadow-map pass."""
        self._cascade = 0
        """The cascade whose map `_shadow_mapping_pass` draws (and whose matrices pyrender binds: 0)."""
        self.shadow_map_texels = SHADOW_TEX_SZ
        """Texels per side of each sun's shadow maps in the current draw (`shadow_map_size_texels`)."""
        self._sun_arrays: dict[int, tuple[weakref.ref, dict[tuple[int, bool], int]]] = {}
        """Per sun (by id, with a weak reference to tell a reused id), per map size and kind (the maps, or the
        still casters' kept depths): the 2D array texture whose layers are its cascades, finest first
        (`_sun_cascade_array`)."""
        self._sun_layer: tuple[int, int, int] | None = None
        """(array texture, layer, size) the sun's shadow pass in progress draws into, else None."""
        self.light_matrices: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}
        """Each light's shadow camera (V, P) in the current draw, by the light node's id and cascade; emptied
        when a draw renders its shadow maps (`Renderer.draw`), so that the maps and the lookups share it."""
        self._shadow_pass: tuple | None = None
        """(light node, flags) of the shadow map being drawn (`_shadow_mapping_pass`), else None."""
        self._max_n_lights: dict[int, list[int]] = {}
        """`_compute_max_n_lights` per flags: the texture units of this context do not change."""
        self.caster_versions: dict[int, int] = {}
        """Per mesh node (by id) of the current draw's graph whose look is counted (`SceneGraph.look_versions`;
        0 for the still environment): equal counts, the same triangles where they were (`_StillCasters`)."""
        self._still_casters = _StillCasters()
        self._cascade_fits: OrderedDict[tuple, list[tuple[np.ndarray, np.ndarray]]] = OrderedDict()
        """The last `CASCADE_FITS_KEPT` `sun_cascade_matrices` results, by what they were fitted to
        (`_cascade_matrices`)."""
        self._drawn_over_kept: dict[tuple[int, int], tuple[tuple, list[tuple[int, int, int, int]]]] = {}
        """Per (sun's array texture, layer) whose last pass drew over kept depths: that kept set
        (`_StillCasters.kept_entry`) and the rectangles of texels (x0, y0, x1, y1) it drew its other casters in."""
        self.keep_still_casters = True
        """Whether a sun's cascades start from the kept depths of the casters that held still (a test turns it off
        to compare with every caster drawn)."""
        self._context_of: tuple | None = None
        """(weak reference to the scene, its `node_changes`, the flags) of the last context update
        (`_update_context`)."""

    def _update_context(self, scene, flags):
        """pyrender's update of what the context holds for a scene (its meshes' buffers, its materials' textures, its
        lights' shadow maps), skipped when the last one was for the same scene, with no node added or removed since
        (`scene_graph.OrderedScene.node_changes`), and the same flags: it would find nothing to add or delete, but
        gathers every primitive's textures to learn so (1.8 ms a draw of the intersection, 829 crops in 4 frames).
        A material's textures are set before the scene is first drawn (`camgen.render.nir` converts its graph's
        first); a scene without the count is updated at every draw."""
        changes = getattr(scene, "node_changes", None)
        last = self._context_of
        if changes is not None and last is not None and last[0]() is scene and last[1:] == (changes, flags):
            return
        super()._update_context(scene, flags)
        self._context_of = None if changes is None else (weakref.ref(scene), changes, flags)

    def _get_light_cam_matrices(self, scene, light_node, flags):
        """A light's shadow camera (V, P), worked out once per draw and cascade (`light_matrices`): pyrender
        asks for it for every primitive it shades."""
        key = (id(light_node), self._cascade)
        if key not in self.light_matrices:
            self.light_matrices[key] = self._light_cam_matrices(scene, light_node, flags)
        return self.light_matrices[key]

    def _light_cam_matrices(self, scene, light_node, flags):
        """A sun's shadow camera: the current cascade's (`sun_cascade_matrices`: fitted to what the draw's
        shadow fit sees, where pyrender's covers a square twice the scene's diagonal, wasting most of its
        texels)."""
        light = light_node.light
        bounds = scene.bounds if self.shadow_bounds_m is None else self.shadow_bounds_m
        if isinstance(light, SpotLight) and self.shadow_bounds_m is not None:
            # pyrender's spot shadow camera, its near and far planes from the fixed box's diagonal.
            scale = float(np.linalg.norm(np.subtract(bounds[1], bounds[0])))
            P = light._get_shadow_camera(scale).get_projection_matrix()
            return np.linalg.inv(scene.get_pose(light_node)), P
        if not isinstance(light, DirectionalLight):
            return super()._get_light_cam_matrices(scene, light_node, flags)
        return self._sun_cascades[id(light_node)][self._cascade]

    def _compute_max_n_lights(self, flags):
        """Room in the shader for the lights `camgen.config.scene.MAX_LIGHTS` allows (pyrender: 4 each).

        With shadows on, pyrender shares the texture units left by the materials among the kinds of light
        that cast them, one a shadow map; a sun is given `SUN_CASCADES` (it takes two: pyrender's own map, which
        its lighting still binds though the shader reads none, and the array of its cascades; room to spare).
        Kept per flags (`_max_n_lights`): pyrender asks OpenGL for its texture units at each call, and its
        lighting calls this for every primitive it shades."""
        kept = self._max_n_lights.get(flags)
        if kept is not None:
            return list(kept)
        directional, spot, _ = super()._compute_max_n_lights(flags)
        kept = self._max_n_lights[flags] = [
            min(directional // SUN_CASCADES, MAX_LIGHTS["sun"])
            if flags & RenderFlags.SHADOWS_DIRECTIONAL
            else MAX_LIGHTS["sun"],
            min(spot, MAX_LIGHTS["spot"]) if flags & RenderFlags.SHADOWS_SPOT else MAX_LIGHTS["spot"],
            MAX_LIGHTS["point"],
        ]
        return list(kept)

    def check_light_counts(self, scene, flags) -> None:
        """pyrender drops lights beyond the shader's room without a word; refuse instead."""
        room = self._compute_max_n_lights(flags)
        counts = (len(scene.directional_light_nodes), len(scene.spot_light_nodes), len(scene.point_light_nodes))
        for kind, count, limit in zip(("sun", "spot", "point"), counts, room, strict=True):
            if count > limit:
                raise RuntimeError(f"{count} {kind} lights, but this OpenGL implementation can shade only {limit}")

    def shadow_flags(self, scene, shadows: bool) -> int:
        if not shadows:
            return RenderFlags.NONE
        flags = RenderFlags.NONE
        if scene.directional_light_nodes:
            flags |= RenderFlags.SHADOWS_DIRECTIONAL
        if scene.spot_light_nodes:
            flags |= RenderFlags.SHADOWS_SPOT
        return flags

    def render_shadow_maps(self, scene, flags: int) -> None:
        """Every shadow-casting light's maps for the current draw (each sun's cascades at `shadow_map_texels`, in
        the layers of its array, `_sun_cascade_array`; each spot light's in pyrender's map)."""
        GL.glFrontFace(GL.GL_CCW)  # the shadow cameras are pyrender's own, with rows bottom-up
        self._sun_cascades.clear()  # this draw's suns only (earlier scenes' nodes are gone)
        self._sun_arrays_drawn.clear()
        for node in scene.light_nodes:
            if isinstance(node.light, DirectionalLight) and flags & RenderFlags.SHADOWS_DIRECTIONAL:
                bounds = scene.bounds if self.shadow_bounds_m is None else self.shadow_bounds_m
                self._sun_cascades[id(node)] = self._cascade_matrices(scene.get_pose(node)[:3, :3], bounds)
                array, size = self._sun_cascade_array(node.light), self.shadow_map_texels
                self._sun_arrays_drawn[id(node)] = array
                try:
                    # Every cascade's copies of kept depths before any cascade's draw: a copy into the array waits
                    # for the draws into it to be rasterised, a draw does not (`_sun_shadow_pass`).
                    planned = []
                    for k in range(SUN_CASCADES):
                        self._cascade, self._sun_layer = k, (array, k, size)
                        planned.append(self._sun_shadow_plan(scene, node, flags))
                    for k, plan in enumerate(planned):
                        self._cascade, self._sun_layer = k, (array, k, size)
                        self._shadow_mapping_pass(scene, node, flags, plan)
                finally:
                    self._cascade, self._sun_layer = 0, None
            elif isinstance(node.light, SpotLight) and flags & RenderFlags.SHADOWS_SPOT:
                self._shadow_mapping_pass(scene, node, flags)

    def _cascade_matrices(self, R_world_from_light: np.ndarray, bounds) -> list[tuple[np.ndarray, np.ndarray]]:
        """`sun_cascade_matrices` of the current draw's shadow view, clip range and map size, kept for the last
        `CASCADE_FITS_KEPT` (sun, box, view) it was asked for: a held view's draws fit the same cascades frame
        after frame (1.7 ms each on llvmpipe's machine), and the kept depths are told by the same matrices."""
        low, high = (np.asarray(bound, np.float64) for bound in bounds)
        key = (
            np.asarray(R_world_from_light, np.float64).tobytes(),
            low.tobytes(),
            high.tobytes(),
            self.shadow_view.key(),
            tuple(float(value) for value in self.shadow_clip_m),
            self.shadow_map_texels,
        )
        kept = self._cascade_fits.get(key)
        if kept is None:
            kept = sun_cascade_matrices(
                R_world_from_light, (low, high), self.shadow_view, *self.shadow_clip_m, self.shadow_map_texels
            )
            for V, P in kept:
                V.setflags(write=False)  # shared by the draws that ask again
                P.setflags(write=False)
            self._cascade_fits[key] = kept
            while len(self._cascade_fits) > CASCADE_FITS_KEPT:
                self._cascade_fits.popitem(last=False)
        else:
            self._cascade_fits.move_to_end(key)
        return kept

    def _shadow_mapping_pass(self, scene, light_node, flags, plan: _SunPassPlan | None = None):
        """pyrender's draw of one shadow map, over the nodes that reach it (`_sorted_mesh_nodes`); a sun's
        cascade starts from the kept depths of the casters that held still (`_sun_shadow_pass`, as `plan`ned)."""
        self._shadow_pass = (light_node, flags)
        try:
            if self._sun_layer is None and not any(node.mesh.is_visible for node in self._sorted_mesh_nodes(scene)):
                # Nothing reaches the map (a car's headlamp aimed past every mesh): pyrender's pass, with no primitive
                # to draw, fails on its unset program; the map is cleared, so nothing is in shadow.
                self._configure_shadow_mapping_viewport(light_node.light, flags)
            elif self._sun_layer is None:
                super()._shadow_mapping_pass(scene, light_node, flags)
            else:
                self._sun_shadow_pass(scene, light_node, flags, plan)
        finally:
            self._shadow_pass = None

    def _sun_shadow_plan(self, scene, light_node, flags) -> _SunPassPlan:
        """What `_sun_shadow_pass` draws for the cascade `_sun_layer` of a sun, the kept depths of a hit copied into
        the layer already (all of them, or what the last pass drew over them)."""
        self._shadow_pass = (light_node, flags)
        try:
            array, layer, size = self._sun_layer
            V, P = self._get_light_cam_matrices(scene, light_node, flags)
            nodes = [node for node in self._sorted_mesh_nodes(scene) if node.mesh.is_visible]
        finally:
            self._shadow_pass = None
        mode, kept, others = (
            self._still_casters.plan(scene, light_node, layer, size, P @ V, nodes, self.caster_versions)
            if self.keep_still_casters
            else ("none", [], nodes)
        )
        entry = self._still_casters.kept_entry(light_node, layer)
        drawn = self._drawn_over_kept.pop((array, layer), None)
        kept_array = self._sun_cascade_array(light_node.light, still=True) if mode != "none" else None
        if mode == "hit":
            # Over a layer that holds this kept set and the last pass's others only, those are restored, not all.
            restore = drawn[1] if drawn is not None and drawn[0] is entry else [(0, 0, size, size)]
            for x0, y0, x1, y1 in restore:
                GL.glCopyImageSubData(
                    kept_array, GL.GL_TEXTURE_2D_ARRAY, 0, x0, y0, layer,
                    array, GL.GL_TEXTURE_2D_ARRAY, 0, x0, y0, layer, x1 - x0, y1 - y0, 1,
                )  # fmt: skip
        return _SunPassPlan(mode, kept, others, entry, kept_array, V, P)

    def _sun_shadow_pass(self, scene, light_node, flags, plan: _SunPassPlan | None = None) -> None:
        """One cascade of a sun (`_sun_layer`), drawn as pyrender draws a shadow map, except that the depths
        of the casters that held still are copied from the last draw of the same cascade (same light, size
        and matrices; `_StillCasters` decides) and only the others are drawn over them.

        The same texels bit for bit: a depth-only pass with the test GL_LESS leaves each texel the least
        depth of the fragments drawn to it (or the clear, 1), whatever their order, so the kept least over
        the still casters, then the others drawn over it, is the least over all (and a copy moves the bits
        unchanged). In a held view the parked vehicles, buildings and ground are not drawn again: the
        parking lot's held sim step drew its three cascades in 67 ms of CPU, of which its five parked
        vehicles took 31 ms (llvmpipe, 2048² maps).

        A hit restores only what the last pass drew over the kept depths of the same kept set
        (`_drawn_over_kept`: the texels each of its other casters' boxes reaches, `_texel_rects`) instead of
        copying the whole kept layer: everywhere else the layer holds the kept depths already (no other pass
        wrote it since; one that did, or one that drew every caster, leaves no record, and the next hit copies
        the whole layer). A 2048² layer is 16 MB; ptz_follow's held step restores up to 0.1 M texels of its
        4.2 M. `plan`: `_sun_shadow_plan`'s, made (and a hit's copies done) before the draws of the sun's
        cascades; None makes it here."""
        array, layer, size = self._sun_layer
        plan = self._sun_shadow_plan(scene, light_node, flags) if plan is None else plan
        V, P, kept, others = plan.V, plan.P, plan.kept, plan.others
        # A hit's layer holds the kept depths already (`_sun_shadow_plan`); the others' passes start from a clear.
        self._configure_shadow_mapping_viewport(light_node.light, flags, clear=plan.mode != "hit")
        if plan.mode == "keep":
            self._depth_only(scene, kept, V, P)
            GL.glCopyImageSubData(
                array, GL.GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer,
                plan.kept_array, GL.GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, size, size, 1,
            )  # fmt: skip
        self._depth_only(scene, others, V, P)
        if plan.mode != "none":  # the layer is the kept layer but where `others` were drawn
            self._drawn_over_kept[(array, layer)] = (plan.entry, _texel_rects(scene, others, P @ V, size))
        GL.glFlush()

    def _depth_only(self, scene, nodes, V, P) -> None:
        """pyrender's shadow-pass draw of `nodes` (`pyrender.Renderer._shadow_mapping_pass`'s loop)."""
        program = None
        cam_pos = scene.get_pose(scene.main_camera_node)[:3, 3]
        for node in nodes:
            pose = scene.get_pose(node)
            for primitive in node.mesh.primitives:
                program = self._get_primitive_program(primitive, RenderFlags.DEPTH_ONLY, ProgramFlags.NONE)
                program._bind()
                program.set_uniform("V", V)
                program.set_uniform("P", P)
                program.set_uniform("cam_pos", cam_pos)
                self._bind_and_draw_primitive(primitive, pose, program, RenderFlags.DEPTH_ONLY)
                self._reset_active_textures()
        if program is not None:
            program._unbind()

    def _sorted_mesh_nodes(self, scene):
        """pyrender's mesh nodes in its order, for its shadow pass (their only user here), less those whose
        box lies wholly beyond one of the planes bounding the map's view (`meshes_reach_clip_volume`): every
        triangle of such a node is clipped, so it would write no texel of the map (the same depths without
        it), while its vertices would be transformed and its draw calls made all the same. A sun's cascade
        over the nearest slice of the view holds few of a site's meshes (and the vertex work of a person's or
        a vehicle's many triangles is the largest cost of the pass on llvmpipe)."""
        nodes = super()._sorted_mesh_nodes(scene)
        if self._shadow_pass is None:
            return nodes
        V, P = self._get_light_cam_matrices(scene, *self._shadow_pass)  # pyrender's pass asked first: cached
        poses = np.array([scene.get_pose(node) for node in nodes]).reshape(-1, 4, 4)
        reaching = meshes_reach_clip_volume([node.mesh for node in nodes], poses, P @ V)
        return [node for node, reaches in zip(nodes, reaching, strict=True) if reaches]

    def _configure_shadow_mapping_viewport(self, light, flags, *, clear: bool = True):
        """pyrender's set-up of a shadow pass, over the map's own size (pyrender's: `SHADOW_TEX_SZ`); a sun's
        cascade is drawn into its layer of the sun's array (`_sun_cascade_array`) instead of pyrender's map,
        cleared unless `clear` is False (the pass restores what it needs of the layer, `_sun_shadow_pass`)."""
        if self._sun_layer is None:
            super()._configure_shadow_mapping_viewport(light, flags)
            GL.glViewport(0, 0, light.shadow_texture.width, light.shadow_texture.height)
            return
        array, layer, size = self._sun_layer
        self._configure_shadow_framebuffer()  # pyrender's steps, the layer attached in place of its map
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self._shadow_fb)
        GL.glFramebufferTextureLayer(GL.GL_FRAMEBUFFER, GL.GL_DEPTH_ATTACHMENT, array, 0, layer)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glDrawBuffer(GL.GL_NONE)
        GL.glReadBuffer(GL.GL_NONE)
        if clear:
            GL.glClear(GL.GL_DEPTH_BUFFER_BIT)
        GL.glViewport(0, 0, size, size)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glDepthFunc(GL.GL_LESS)
        GL.glDepthRange(0.0, 1.0)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glDisable(GL.GL_BLEND)

    def _sun_cascade_array(self, light, *, still: bool = False) -> int:
        """A sun's 2D array texture at `shadow_map_texels`, one layer per cascade (finest first), made as
        pyrender makes a shadow map (depth, float, nearest, repeat, a white border) at its first use and kept
        per size; those of suns that are gone, deleted. The lit shader reads every cascade through one sampler
        (`linear_mesh.frag`): llvmpipe runs both sides of a branch, so three maps behind branches cost three
        filtered lookups a pixel, where a layer index costs one (a sunlit 2134 × 1242 draw of the parking lot:
        0.95 s of CPU with three 2D maps, 0.73 s with the array). With `still`, a second array of the same
        kind: the depths of the casters that held still, per cascade (`_sun_shadow_pass`)."""
        for key, (ref, by_size) in list(self._sun_arrays.items()):
            if ref() is None:
                GL.glDeleteTextures(list(by_size.values()))
                del self._sun_arrays[key]
                self._drawn_over_kept.clear()  # a name may come back for another texture
        cached = self._sun_arrays.get(id(light))
        if cached is None or cached[0]() is not light:
            cached = self._sun_arrays[id(light)] = (weakref.ref(light), {})
        size = self.shadow_map_texels
        array = cached[1].get((size, still))
        if array is None:
            array = cached[1][(size, still)] = int(GL.glGenTextures(1))
            target = GL.GL_TEXTURE_2D_ARRAY
            GL.glBindTexture(target, array)
            GL.glTexImage3D(
                target, 0, GL.GL_DEPTH_COMPONENT, size, size, SUN_CASCADES, 0, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT, None
            )
            sampler = pyrender.Sampler()  # pyrender's shadow maps' sampling (pyrender.Texture._add_to_context)
            GL.glTexParameteri(target, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
            GL.glTexParameteri(target, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
            GL.glTexParameteri(target, GL.GL_TEXTURE_WRAP_S, sampler.wrapS)
            GL.glTexParameteri(target, GL.GL_TEXTURE_WRAP_T, sampler.wrapT)
            GL.glTexParameterfv(target, GL.GL_TEXTURE_BORDER_COLOR, np.ones(4, np.float32))
            GL.glBindTexture(target, 0)
        return array

    def delete(self):
        """pyrender's resources, and the suns' shadow maps made here."""
        for _, by_size in self._sun_arrays.values():
            GL.glDeleteTextures(list(by_size.values()))
        self._sun_arrays.clear()
        self.sky_map.delete()
        self._drawn_over_kept.clear()
        super().delete()

    def _bind_lighting(self, scene, program, node, flags):
        """pyrender's lighting uniforms (with each sun's first cascade), and each sun's other cascades."""
        super()._bind_lighting(scene, program, node, flags)
        if flags & RenderFlags.SHADOWS_SPOT:
            # pyrender sets the shadow maps of the scene's spot lights only: an entry a scene drawn before with more
            # spot lights set keeps its unit, which may now hold another kind of texture (a sun's array, the sky
            # map): OpenGL refuses such a draw ("invalid operation"). The unused entries name the first map's unit.
            spots = sum(isinstance(n.light, SpotLight) for n in scene.light_nodes)
            first = program.values.get("spot_lights[0].shadow_map") if spots else None
            for i in range(spots, int(program.defines.get("MAX_SPOT_LIGHTS", 0)) if first else 0):
                program.set_uniform(f"spot_lights[{i}].shadow_map", first[1])
        if not flags & RenderFlags.SHADOWS_DIRECTIONAL:
            return
        suns = [n for n in scene.light_nodes if isinstance(n.light, DirectionalLight)]  # pyrender's order
        for i, sun in enumerate(suns):
            cascades = self._sun_cascades[id(sun)]
            unit = self._get_next_active_texture()
            GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
            GL.glBindTexture(GL.GL_TEXTURE_2D_ARRAY, self._sun_arrays_drawn[id(sun)])
            program.set_uniform(f"directional_lights[{i}].shadow_maps", unit)
            for k in range(1, SUN_CASCADES):
                V, P = cascades[k]
                program.set_uniform(f"directional_lights[{i}].cascade_matrices[{k - 1}]", P @ V)
            for k, scales in enumerate(sun_cascade_scales(cascades, self.shadow_map_texels)):
                program.set_uniform(f"directional_lights[{i}].cascade_scales[{k}]", scales)
        # The array's unused entries name a sun's array unit: left at unit 0 they would be array samplers on
        # the unit of the 2D samplers left unset (spot maps, spot_profile), which OpenGL refuses at the draw.
        for i in range(len(suns), int(program.defines.get("MAX_DIRECTIONAL_LIGHTS", 0)) if suns else 0):
            program.set_uniform(f"directional_lights[{i}].shadow_maps", unit)

    def _bind_lit(self, scene, program, node, flags, lit_programs: dict[int, int]) -> None:
        """The lights' uniforms and textures for a lit primitive (`_bind_lighting`, `_bind_spot_profiles`, the sky's
        map `SkyMap.bind`), worked out at the first primitive of each program in a draw only (`lit_programs`, by the
        program's id: the texture units
        they took). Within a draw they are the same for every primitive: the lights, their shadow maps and matrices
        do not change, nor does which node is lit matter (pyrender sorts lights by distance to the node only when
        there are more than the shader holds, which `check_light_counts` refuses); the units are taken in the same
        order from the first one after each primitive (`_reset_active_textures`) whatever the program, and a
        material's textures go to the units after them, so those units still hold the lights' textures; and the
        program kept its uniforms (`_RememberingProgram` would send none of them again). pyrender's lighting costs
        about 0.1 ms of Python a primitive, for each of a crop's few hundred."""
        units = lit_programs.get(id(program))
        if units is not None:
            self._texture_alloc_idx = units  # the material's textures after the lights', as on a full binding
            return
        self._bind_lighting(scene, program, node, flags)
        self._bind_spot_profiles(scene, program)
        self.sky_map.bind(program, self._get_next_active_texture())
        lit_programs[id(program)] = self._texture_alloc_idx

    def _bind_spot_profiles(self, scene, program) -> None:
        """Each spot light's `intensity_profile` (`SpotProfile`: an IES lamp's table) for the lit
        shader, in the order pyrender binds the spot lights; row 0 (the glTF cone) for the others."""
        spots = [node for node in scene.light_nodes if isinstance(node.light, SpotLight)]
        profiled = [getattr(node.light, "intensity_profile", None) for node in spots]
        for k, profile in enumerate(profiled):
            program.set_uniform(f"spot_profile_row[{k}]", 0 if profile is None else k + 1)
        if not any(profile is not None for profile in profiled):
            return
        for k, (node, profile) in enumerate(zip(spots, profiled, strict=True)):
            if profile is not None:
                # Directly: pyrender's set_uniform sends a 3×3 matrix through glUniformMatrix4fv.
                location = GL.glGetUniformLocation(program._program_id, f"spot_profile_axes[{k}]")
                axes = np.ascontiguousarray(profile.axes(scene.get_pose(node)), dtype=np.float32)
                GL.glUniformMatrix3fv(location, 1, GL.GL_TRUE, axes)
        unit = self._get_next_active_texture()
        GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self._spot_profile_texture(scene, profiled))
        program.set_uniform("spot_profile", unit)

    def _spot_profile_texture(self, scene, profiled) -> int:
        """The float texture of a scene's spot-light tables, one band of rows per spot light (zeros for
        lights without one); made once per scene and context."""
        cached = self._profile_textures.get(id(scene))
        if cached is not None and cached[0]() is scene:
            return cached[1]
        bands = [
            np.zeros_like(next(p for p in profiled if p is not None).relative) if p is None else p.relative
            for p in profiled
        ]
        texture = _float_table_texture(np.concatenate(bands, axis=0))
        self._profile_textures[id(scene)] = (weakref.ref(scene), texture)
        return texture

    def _bind_and_draw_primitive(self, primitive, pose, program, flags):
        """pyrender's draw of a primitive, except for blended ones (glass): the shadow-map pass (the only
        depth-only caller here) skips them, and a lit draw blends their alpha as coverage.

        Glass casts no shadow: it passes about 75 % of the light (`camgen.vehicles.cabin`), so a cabin lit
        through unshadowed glass is nearer the truth than one that only the ambient term reaches (pyrender's
        shadow pass draws every primitive, and a car's windows blocked all sun and lamp light inside).
        pyrender blends with glBlendFunc(SRC_ALPHA, ONE_MINUS_SRC_ALPHA), which leaves a² + (1 − a)·behind
        in alpha; for the duration of the draw its glBlendFunc becomes glBlendFuncSeparate with alpha's
        factors (ONE, ONE_MINUS_SRC_ALPHA), so alpha becomes a + (1 − a)·behind: 1 − τ after every pane,
        τ the product of their transmittances (`Renderer.draw` composites the background behind it).
        Opaque primitives are drawn by pyrender unchanged, except that a material whose `casts_shadow` is False
        (road paint, `scene_graph.PaintMaterial`) is left out of the shadow maps too."""
        if flags & RenderFlags.DEPTH_ONLY and not getattr(primitive.material, "casts_shadow", True):
            return None
        if primitive.material.alphaMode != "BLEND":
            return super()._bind_and_draw_primitive(primitive, pose, program, flags)
        if flags & RenderFlags.DEPTH_ONLY:
            return None
        module = sys.modules[pyrender.Renderer.__module__]
        own_blend_func, module.glBlendFunc = module.glBlendFunc, _blend_with_coverage
        try:
            return super()._bind_and_draw_primitive(primitive, pose, program, flags)
        finally:
            module.glBlendFunc = own_blend_func

    def forward(self, scene, nodes, instance_ids, V, P, cam_position, flags: int, lit: bool) -> None:
        """Draw `nodes` into the bound target. A lit draw first draws its opaque primitives' depth alone
        (`_depth_prepass`), then shades them where they lie at the pixel's final depth, the first drawn there
        winning, as the depth test alone keeps it (the same pixels of every pass bit for bit:
        tests/render/test_depth_prepass.py); blended primitives (glass) after them, depth-tested as before."""
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glDepthFunc(GL.GL_LESS)
        GL.glDepthRange(0.0, 1.0)
        GL.glDisable(GL.GL_MULTISAMPLE)
        # gl_projection flips rows, which reverses the triangles' winding; a mirrored view (an improper pose:
        # camgen.render.wet) reverses it again
        GL.glFrontFace(GL.GL_CCW if self.mirrored else GL.GL_CW)
        draw_flags = flags if lit else RenderFlags.DEPTH_ONLY
        program_flags = ProgramFlags.USE_MATERIAL if lit else ProgramFlags.NONE
        kinds = (
            ("NO_SUNS", scene.directional_light_nodes),
            ("NO_POINT_LIGHTS", scene.point_light_nodes),
            ("NO_SPOT_LIGHTS", scene.spot_light_nodes),
        )
        self._program_cache.absent_lights = tuple(define for define, lights in kinds if not lights)
        order = _draw_order(scene, nodes, cam_position, lit)
        prepass = lit and self.depth_prepass
        program = None
        lit_programs: dict[int, int] = {}  # per program (by id) lit in this draw: the units its lights took
        try:
            if prepass:  # inside: a failed pre-pass leaves no stencil test on (the `finally`)
                self._depth_prepass(scene, order, V, P, draw_flags, program_flags)
            for node, primitive in order:
                if prepass and primitive.material.alphaMode == "BLEND":  # glass: depth-tested as drawn alone
                    GL.glDepthFunc(GL.GL_LESS)
                    GL.glStencilFunc(GL.GL_ALWAYS, 1, 0xFF)
                    GL.glStencilOp(GL.GL_KEEP, GL.GL_KEEP, GL.GL_REPLACE)
                self._program_cache.material_kind = material_defines(primitive.material) if lit else ()
                program = self._get_primitive_program(primitive, draw_flags, program_flags)
                program._bind()
                program.set_uniform("V", V)
                program.set_uniform("P", P)
                unlabelled = getattr(primitive.material, "unlabelled", False)  # scene_graph.ShadeMaterial: background
                program.set_uniform("instance_id", 0 if unlabelled else instance_ids[node], unsigned=True)
                if lit:
                    program.set_uniform("cam_pos", cam_position)
                    program.set_uniform("texture_lod_bias", self.texture_lod_bias)
                    self._bind_lit(scene, program, node, flags, lit_programs)
                    self._bind_and_draw_primitive(primitive, scene.get_pose(node), program, draw_flags)
                else:
                    _draw_geometry(primitive, scene.get_pose(node), program)
                self._reset_active_textures()
        finally:
            if prepass:
                GL.glDisable(GL.GL_STENCIL_TEST)
                GL.glDepthFunc(GL.GL_LESS)
        if program is not None:
            program._unbind()

    def _depth_prepass(self, scene, order: list, V, P, draw_flags: int, program_flags: int) -> None:
        """The depth of the opaque primitives of `order` alone, each through its lit program's vertex shader
        (`_LinearProgramCache.prepass_program`: the same positions bit for bit), culled and filled as the lit draw
        does; where one lies nearer than what the target held, the stencil is cleared. Then the shading pass is set
        up: a fragment is shaded only at its pixel's final depth (GL_EQUAL) while the stencil is 0, and sets it, so
        that the first primitive drawn at that depth wins, as GL_LESS alone keeps it, and what a kept background
        drew there (stencil 1, `Renderer.draw`'s `background`) stays; glass sets it where it lies nearest.

        llvmpipe shades every fragment that passes the depth test when it comes, also where a later one covers it:
        the still world behind a moving node (still nodes are drawn first), a crown's leaves behind its other leaves.
        With the pre-pass each pixel is shaded once, for a second pass over the vertices and the depth. Measured by
        CPU time (llvmpipe's threads included; 2 cores, load 4-10): a crop of the parking lot's 2x draw over three
        swaying trees and the facade behind them 710-742 -> 630-647 ms, the intersection's 4K box camera's whole 2x
        draw 2545 -> 2295 ms, the plaza's 1600 -> 1465 ms; where little is hidden it costs a little (the corridor's
        whole draw 948 -> 990 ms). Shading the pre-pass's fragments with the lit program and colour writes masked
        cost as much as shading them (llvmpipe still runs the shader), hence a program of its own."""
        GL.glEnable(GL.GL_STENCIL_TEST)
        GL.glStencilMask(0xFF)
        GL.glStencilFunc(GL.GL_ALWAYS, 0, 0xFF)
        GL.glStencilOp(GL.GL_KEEP, GL.GL_KEEP, GL.GL_ZERO)
        GL.glColorMask(GL.GL_FALSE, GL.GL_FALSE, GL.GL_FALSE, GL.GL_FALSE)
        GL.glDisable(GL.GL_BLEND)
        program = None
        try:
            for node, primitive in order:
                material = primitive.material
                if material.alphaMode == "BLEND":
                    continue
                self._program_cache.material_kind = material_defines(material)
                program = self._program_cache.prepass_program(
                    self._get_primitive_program(primitive, draw_flags, program_flags)
                )
                program._bind()
                program.set_uniform("V", V)
                program.set_uniform("P", P)
                program.set_uniform("M", scene.get_pose(node))
                primitive._bind()
                # As pyrender's draw of a lit primitive culls and fills it (`_bind_and_draw_primitive`).
                wireframe = material.wireframe != bool(draw_flags & RenderFlags.FLIP_WIREFRAME)
                line = draw_flags & RenderFlags.ALL_WIREFRAME or wireframe
                GL.glPolygonMode(GL.GL_FRONT_AND_BACK, GL.GL_LINE if line else GL.GL_FILL)
                _cull_and_draw(primitive, material.doubleSided or bool(draw_flags & RenderFlags.SKIP_CULL_FACES))
                primitive._unbind()
        finally:
            if program is not None:
                program._unbind()
            GL.glColorMask(GL.GL_TRUE, GL.GL_TRUE, GL.GL_TRUE, GL.GL_TRUE)
        GL.glDepthFunc(GL.GL_EQUAL)
        GL.glStencilFunc(GL.GL_EQUAL, 0, 0xFF)
        GL.glStencilOp(GL.GL_KEEP, GL.GL_KEEP, GL.GL_INCR)


def material_defines(material) -> tuple[str, ...]:
    """The defines of `linear_mesh.frag` for a material's kind: CLEARCOATED_MATERIAL for a clear-coated one
    (`scene_graph.ClearcoatMaterial`: a car's paint), TRANSMISSIVE_MATERIAL for a blended one (glass)."""
    kind = ()
    if getattr(material, "clearcoat", False):
        kind += ("CLEARCOATED_MATERIAL",)
    if material.alphaMode == "BLEND":
        kind += ("TRANSMISSIVE_MATERIAL",)
    return kind


def meshes_reach_clip_volume(meshes: list, poses: np.ndarray, P_V: np.ndarray) -> np.ndarray:
    """(N,) bool: for each mesh (placed at its pose, `poses` (N, 4, 4)), False when its box lies wholly beyond
    one of the six planes of the clip volume of the projection `P_V` (−w ≤ x, y, z ≤ w): then every primitive
    of it is clipped away and draws nothing. Each plane is a half-space in homogeneous coordinates, which holds
    the whole box when it holds its eight corners, whether the projection is orthographic (a sun's map) or
    perspective (a spot light's). A texel's centre lies half a texel inside the map's edge, far more than
    float rounding. Meshes with instanced primitives say True: pyrender's bounds of instances take their
    translations only."""
    clip, instanced = _clip_corners(meshes, poses, P_V)
    w = clip[..., 3:]
    beyond = np.all(clip[..., :3] > w, axis=1) | np.all(clip[..., :3] < -w, axis=1)  # (N, 3)
    return instanced | ~np.any(beyond, axis=1)


def _clip_corners(meshes: list, poses: np.ndarray, P_V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, 8, 4) clip coordinates under `P_V` of the corners of each mesh's box placed at its pose (`poses`
    (N, 4, 4)), and (N,) whether the mesh has instanced primitives (its corners then mean nothing: pyrender's
    bounds of instances take their translations only)."""
    boxes = np.zeros((len(meshes), 2, 3))
    instanced = np.zeros(len(meshes), dtype=bool)
    for k, mesh in enumerate(meshes):
        instanced[k] = any(primitive.poses is not None for primitive in mesh.primitives)
        if not instanced[k]:
            # The least and greatest of its primitives' bounds, which pyrender keeps for the mesh until a placement
            # forgets them (`scene_graph.SceneGraph.place_actors`) as it resets a primitive's when its vertices change.
            boxes[k] = mesh.bounds
    corner = (np.arange(8)[:, None] >> np.arange(3)) & 1  # (8, 3): which end of each axis
    local = np.where(corner, boxes[:, 1:2], boxes[:, 0:1])  # (N, 8, 3)
    world = local @ np.transpose(poses[:, :3, :3], (0, 2, 1)) + poses[:, None, :3, 3]
    return world @ P_V[:, :3].T + P_V[:, 3], instanced


SHADOW_RECT_PAD_TEXELS = 1
"""Texels `_texel_rects` grows a projected box by: a triangle writes the texels whose centres it covers, half a
texel inside its projection's extent, far more than the rounding of OpenGL's float32 transform."""


def _texel_rects(scene, nodes: list, light_matrix: np.ndarray, size: int) -> list[tuple[int, int, int, int]]:
    """Rectangles (x0, y0, x1, y1) of texels (x1, y1 exclusive) of a `size`² sun cascade drawn with the
    orthographic `light_matrix` (P·V), one per node of `nodes` that reaches the map, outside which a depth-only
    draw of `nodes` writes nothing: the corners of each node's box projected, grown by `SHADOW_RECT_PAD_TEXELS`;
    the whole map where a bound is not known (an instanced mesh, a projection that is not orthographic)."""
    if not nodes:
        return []
    poses = np.array([scene.get_pose(node) for node in nodes]).reshape(-1, 4, 4)
    clip, instanced = _clip_corners([node.mesh for node in nodes], poses, light_matrix)
    if instanced.any() or not np.all(clip[..., 3] == 1.0) or not np.all(np.isfinite(clip)):
        return [(0, 0, size, size)]
    texels = (clip[..., :2] + 1.0) * (size / 2.0)  # (N, 8, 2), the viewport: NDC −1…1 over 0…size
    low = np.clip(np.floor(texels.min(axis=1)) - SHADOW_RECT_PAD_TEXELS, 0, size).astype(int)
    high = np.clip(np.ceil(texels.max(axis=1)) + SHADOW_RECT_PAD_TEXELS, 0, size).astype(int)
    return [
        (x0, y0, x1, y1) for (x0, y0), (x1, y1) in zip(low.tolist(), high.tolist(), strict=True) if x1 > x0 and y1 > y0
    ]


CROP_CULL_PAD_PX = 2
"""Pixels a crop's frustum is widened by when meshes are culled against it (`_nodes_reaching_crop`): a mesh
that reaches a pixel centre of the crop lies at least half a pixel inside it; the rest is spare."""


def _nodes_reaching_crop(scene, nodes: list, view: View, crop_px, V: np.ndarray, near_m: float, far_m: float) -> list:
    """`nodes` (in their order) less those whose box lies wholly outside the frustum of the crop `crop_px` of
    `view` (the whole view, or the part a scissored draw fills), widened by `CROP_CULL_PAD_PX`
    (`meshes_reach_clip_volume`): they cannot reach a pixel of the draw, yet llvmpipe would transform, clip
    and bin every triangle of them. The pixels are the same bit for bit (each primitive is rasterised
    alone; a culled one wrote none of them). Measured on the 2-core machine under load 5: a held 720p sim
    step of ptz_follow 0.94 → 0.80 s, a 1080p frame of the parking lot's PTZ 5.8 → 3.3 s (crops only)."""
    if not nodes:
        return nodes
    x0, y0, x1, y1 = crop_px
    pad = CROP_CULL_PAD_PX
    part = view.cropped((x0 - pad, y0 - pad, x1 + pad, y1 + pad))
    P_V = gl_projection(part.K_px, part.width_px, part.height_px, near_m, far_m) @ V
    poses = np.array([scene.get_pose(node) for node in nodes])
    reach = meshes_reach_clip_volume([node.mesh for node in nodes], poses, P_V)
    return [node for node, kept in zip(nodes, reach, strict=True) if kept]


def _blend_with_coverage(source_factor, destination_factor) -> None:
    """pyrender's blend factors for colour, and (ONE, ONE_MINUS_SRC_ALPHA) for alpha (coverage: the
    target's alpha accumulates 1 − ∏(1 − a), `_PassRenderer._bind_and_draw_primitive`)."""
    GL.glBlendFuncSeparate(source_factor, destination_factor, GL.GL_ONE, GL.GL_ONE_MINUS_SRC_ALPHA)


def _draw_order(scene, nodes, cam_position: np.ndarray, lit: bool) -> list:
    """(node, primitive) pairs in the order a draw takes them: the nodes' order, except that a lit draw
    takes blended primitives (vehicle glass: `camgen.render.scene_graph.vehicle_mesh`) after every opaque
    one, the farthest node's first and a node's in its own order (a vehicle's inner glass faces before its
    outer ones), so that each blends over whatever lies behind it. A draw of depth and ids only takes
    glass as the opaque surface it is to the annotations."""
    pairs = [(node, primitive) for node in nodes if node.mesh.is_visible for primitive in node.mesh.primitives]
    if not lit:
        return pairs
    opaque = [pair for pair in pairs if pair[1].material.alphaMode != "BLEND"]
    blended = [pair for pair in pairs if pair[1].material.alphaMode == "BLEND"]

    def distance_m(pair) -> float:
        node = pair[0]
        pose = scene.get_pose(node)
        centre = pose[:3, :3] @ node.mesh.centroid + pose[:3, 3]
        return float(np.linalg.norm(centre - cam_position))

    return opaque + sorted(blended, key=distance_m, reverse=True)  # a stable sort: ties keep their order


def _draw_geometry(primitive, pose: np.ndarray, program) -> None:
    """Draw a primitive for depth and ids only, culling as its material says.

    pyrender's depth-only path always culls back faces, so double-sided surfaces seen from behind
    would have radiance but no depth or id.
    """
    program.set_uniform("M", pose)
    primitive._bind()
    GL.glDisable(GL.GL_BLEND)
    GL.glPolygonMode(GL.GL_FRONT_AND_BACK, GL.GL_FILL)
    _cull_and_draw(primitive, primitive.material.doubleSided)


def _cull_and_draw(primitive, double_sided: bool) -> None:
    """Draw a bound primitive's instances (one where it has no poses), culling back faces unless `double_sided`."""
    if double_sided:
        GL.glDisable(GL.GL_CULL_FACE)
    else:
        GL.glEnable(GL.GL_CULL_FACE)
        GL.glCullFace(GL.GL_BACK)
    instances = 1 if primitive.poses is None else len(primitive.poses)
    if primitive.indices is not None:
        GL.glDrawElementsInstanced(primitive.mode, primitive.indices.size, GL.GL_UNSIGNED_INT, None, instances)
    else:
        GL.glDrawArraysInstanced(primitive.mode, 0, len(primitive.positions), instances)
    primitive._unbind()


SCRATCH_FRAMEBUFFERS = 4
"""Render targets a `Renderer` keeps for draws that are not kept as backgrounds (one per size and set of passes):
a frame's supersampled radiance, its 1× sub-frames, its depth and ids, an actor's ids alone. Each holds
16-20 bytes a pixel (a 4268 × 2484 radiance target 212 MB)."""


class Renderer:
    """A headless OpenGL context (EGL) that draws camgen scene graphs into float passes.

    One per process (or thread); reuse it across frames, cameras and scenes. Use as a context
    manager, or call `close`.
    """

    def __init__(self, device_index: int = 0):
        from pyrender.platforms import egl

        platform = egl.EGLPlatform(1, 1, device=egl.get_device_by_index(device_index))
        platform.init_context()
        platform.make_current()
        # This Renderer owns the context: destroyed on close or garbage collection, never with
        # eglTerminate (pyrender's delete_context), because the process shares the EGL display.
        self._display, self._context = platform._egl_display, platform._egl_context
        platform._egl_display = platform._egl_context = None  # pyrender's clean-up then does nothing
        self._release_context = weakref.finalize(self, _destroy_context, self._display, self._context)
        self._platform = platform
        self._renderer = _PassRenderer()
        self._framebuffers: dict[tuple, _Framebuffer] = {}
        """The draws kept as backgrounds (`keep_as`), by key: one each, of the size it was last drawn at."""
        self._scratch: OrderedDict[tuple, _Framebuffer] = OrderedDict()
        """The targets of draws that are not kept, by key, size and passes, least recently used first (at most
        `SCRATCH_FRAMEBUFFERS`)."""
        self.backgrounds = BackgroundCache()
        """The sky and far ground behind the views drawn lately (`BackgroundCache`)."""
        self._staged_vertices: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
        """Per deformed primitive, its interleaved vertex rows as last uploaded (`_upload_deformed`)."""
        self.gl_renderer = GL.glGetString(GL.GL_RENDERER).decode()
        """The OpenGL implementation drawing (llvmpipe, or a GPU's name)."""
        version = (int(GL.glGetIntegerv(GL.GL_MAJOR_VERSION)), int(GL.glGetIntegerv(GL.GL_MINOR_VERSION)))
        count = int(GL.glGetIntegerv(GL.GL_NUM_EXTENSIONS))
        extensions = {GL.glGetStringi(GL.GL_EXTENSIONS, i).decode() for i in range(count)}
        check_gl_features(version, extensions, self.gl_renderer)
        self._renderer.keep_still_casters = copies_images(version, extensions)
        self._renderer.depth_prepass = "llvmpipe" in self.gl_renderer
        self.max_size_px = int(GL.glGetIntegerv(GL.GL_MAX_RENDERBUFFER_SIZE))
        """The largest width or height of a render target here."""

    def _make_current(self) -> None:
        from OpenGL import EGL

        if self._platform is None:
            raise RuntimeError("this Renderer is closed")
        if not EGL.eglMakeCurrent(self._display, EGL.EGL_NO_SURFACE, EGL.EGL_NO_SURFACE, self._context):
            raise RuntimeError("cannot make the OpenGL context current (was the EGL display terminated?)")

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self._platform is None:
            return
        self._make_current()
        for framebuffer in [*self._framebuffers.values(), *self._scratch.values()]:
            framebuffer.delete()
        self._renderer.delete()
        self._release_context()
        self._platform = None

    def forget(self, kept: str) -> None:
        """Free a draw kept with `keep_as`."""
        framebuffer = self._framebuffers.pop(("main", kept), None)
        if framebuffer is not None:
            self._make_current()
            framebuffer.delete()

    def _framebuffer(self, key: tuple, width_px: int, height_px: int, passes: tuple[str, ...]) -> _Framebuffer:
        """The target for a draw: a kept one's (``("main", name)``) of this size and passes, made anew when they
        change; a scratch one (``("main", None)``, ``("composite",)``) kept per size and passes, so that draws
        taking turns at two sizes or sets of passes (a frame's supersampled radiance, then its depth and ids,
        then each actor's ids alone) do not make their targets again each time: allocating a 4268 × 2484
        radiance target took 107 ms on llvmpipe, at every frame of the parking lot. A target is cleared (or
        copied from a kept one) before each draw, so which one is used changes no pixel."""
        if key[-1] is None or key == ("composite",):
            scratch_key = (key, width_px, height_px, passes)
            framebuffer = self._scratch.get(scratch_key)
            if framebuffer is None:
                framebuffer = self._scratch[scratch_key] = _Framebuffer(width_px, height_px, passes)
                while len(self._scratch) > SCRATCH_FRAMEBUFFERS:
                    _, dropped = self._scratch.popitem(last=False)
                    dropped.delete()
            else:
                self._scratch.move_to_end(scratch_key)
            return framebuffer
        framebuffer = self._framebuffers.get(key)
        if framebuffer is None or (framebuffer.width_px, framebuffer.height_px, framebuffer.passes) != (
            width_px,
            height_px,
            passes,
        ):
            if framebuffer is not None:
                framebuffer.delete()
            framebuffer = self._framebuffers[key] = _Framebuffer(width_px, height_px, passes)
        return framebuffer

    def draw(
        self,
        graph,
        view: View,
        passes: tuple[str, ...],
        *,
        nodes=None,
        background: str | None = None,
        keep_as: str | None = None,
        read: bool = True,
        clip_range_m: tuple[float, float] | None = None,
        shadow_fit: ShadowFit | None = None,
        crop_px: tuple[int, int, int, int] | None = None,
        shadow_maps_kept: bool = False,
        texture_lod_bias: float = 0.0,
    ) -> Passes:
        """Draw `nodes` (default: every mesh) of a `SceneGraph` as seen by `view`.

        passes: any of "radiance", "depth_m", "instance_id"; they share one draw. Without radiance
        the geometry-only shader runs (no lighting). `background` names a draw kept earlier with
        `keep_as` (same view and passes) to start from instead of an empty frame: the new nodes are
        depth-tested against it, exactly as if everything were drawn together, provided both draws
        use the same `clip_range_m` (near, far in m; default: from the scene's current bounds, which
        move with the actors). Nodes are shaded still before moving, each near to far (`front_to_back`),
        whatever the order given, and see-through (blended) primitives after every opaque one (`_draw_order`);
        the sky and the far ground, filled in after the draw, show through glass (`composite_background`),
        and fog lies before and behind it (`fogged_radiance`).
        `shadow_fit`: what the shadow maps are fitted to (default: this view and the scene's current
        bounds); draws sharing one shade every surface they both see alike. `crop_px`: draw only the
        pixels (x0, y0, x1, y1) of `view` (x1, y1 exclusive; passes of that size), at a cost that follows
        their number: the whole view's draw scissored to them, so each is bit for bit the whole draw's
        pixel. (A view cropped by moving its principal point, or a viewport moved by (−x0, −y0), rounds
        window positions differently, and shadow-map comparisons on lit ground flip here and there: up to
        6e-4 of a pixel's value, measured.) Its sky, far ground and fog are evaluated through
        `view.cropped(crop_px)`. Not with `keep_as`. `shadow_maps_kept`: the previous draw's shadow maps
        stand (the caller vouches that it drew the same graph, placed alike, with the same `shadow_fit`):
        another crop of the same sub-frame skips their pass. `texture_lod_bias`: added to every material
        texture's mip level; a draw at 1× that stands for s × s samples of each pixel takes −log2 s.
        """
        unknown = set(passes) - set(PASSES)
        if unknown or not passes:
            raise ValueError(f"passes must be a non-empty subset of {PASSES}, got {passes}")
        requested = passes
        fog_visibility_m = getattr(graph, "fog_visibility_m", None)
        if fog_visibility_m is not None and "radiance" in passes:
            passes = (*passes, "depth_m")  # fog needs each pixel's distance, drawn in the same draw
        passes = tuple(name for name in PASSES if name in passes)
        self._make_current()
        scene = graph.scene
        nodes = graph.environment_nodes + graph.actor_nodes if nodes is None else list(nodes)
        nodes = front_to_back(graph, nodes, view.T_world_from_cam[:3, 3])
        lit = "radiance" in passes
        renderer = self._renderer
        renderer.texture_lod_bias = float(texture_lod_bias)
        if lit:
            renderer.sky_map.update(graph)
        flags = renderer.shadow_flags(scene, graph.shadows) if lit else RenderFlags.NONE
        pose_gl = gl_camera_pose(view.T_world_from_cam)
        renderer.mirrored = bool(np.linalg.det(view.T_world_from_cam[:3, :3]) < 0.0)
        scene.set_pose(scene.main_camera_node, pose_gl)
        renderer.check_light_counts(scene, flags)
        _upload_deformed(graph, self._staged_vertices)
        renderer._update_context(scene, flags)
        near_m, far_m = clip_range_m or _scene_clip_range_m(scene, view.T_world_from_cam)
        if flags != RenderFlags.NONE:
            renderer.shadow_clip_m = (near_m, far_m)
            if shadow_fit is None:
                renderer.shadow_bounds_m, renderer.shadow_view = None, view
            else:
                renderer.shadow_bounds_m = (shadow_fit.low_m, shadow_fit.high_m)
                renderer.shadow_view = shadow_fit.view
            renderer.shadow_map_texels = shadow_map_size_texels(renderer.shadow_view)
            if not shadow_maps_kept:
                renderer.light_matrices.clear()
                renderer.caster_versions = caster_versions(graph)
                renderer.render_shadow_maps(scene, flags)

        size = (view.width_px, view.height_px)
        target = self._framebuffer(("main", keep_as), *size, passes)
        if background is not None:
            kept = self._framebuffers.get(("main", background))
            if kept is None or (kept.width_px, kept.height_px, kept.passes) != (*size, passes):
                raise ValueError(f"no kept draw {background!r} of size {size} with passes {passes}")
            target = self._framebuffer(("composite",), *size, passes)
            target.copy_from(kept)
            target.bind()
        else:
            target.bind()
            if crop_px is not None:
                if keep_as is not None:
                    raise ValueError("a cropped draw cannot be kept as a background")
                GL.glEnable(GL.GL_SCISSOR_TEST)
                GL.glScissor(*_origin_size(crop_px))  # framebuffer row v holds image row v (gl_projection)
            target.clear(graph.sky_luminance_cd_m2)

        P = gl_projection(view.K_px, view.width_px, view.height_px, near_m, far_m)
        V = np.linalg.inv(pose_gl)
        nodes = _nodes_reaching_crop(scene, nodes, view, crop_px or (0, 0, *size), V, near_m, far_m)
        renderer.forward(scene, nodes, graph.instance_ids, V, P, pose_gl[:3, 3], flags, lit)
        GL.glFlush()
        if crop_px is not None:
            GL.glDisable(GL.GL_SCISSOR_TEST)
            view = view.cropped(crop_px)
        if not read:
            return Passes()
        out = target.read(crop_px)
        if out.radiance is not None:
            behind = composite_background(graph, view, out.radiance, target.coverage, self.backgrounds)
            if fog_visibility_m is not None:
                depth_m = out.depth_m
                if behind.open_depth_m is not None:
                    depth_m = np.minimum(depth_m, behind.open_depth_m)
                out.radiance = fogged_radiance(
                    graph, view, out.radiance, depth_m, fog_visibility_m, behind, self.backgrounds
                )
        if "depth_m" not in requested:
            out.depth_m = None
        return out


def front_to_back(graph, nodes: list, camera_m: np.ndarray) -> list:
    """`nodes` in the order a draw shades them: the still environment (what a kept background holds) before
    whatever moves (`SceneGraph.moving_nodes`), each group nearest first by the centre of its world box.

    A fragment hidden by one already drawn fails the depth test before it is shaded (early depth test), so
    near-to-far order shades fewer fragments: on llvmpipe (2 cores under load, best of 4) a 1446×852
    radiance draw of the parking lot took 565 ms instead of 668 ms (the plaza's facade camera 769 ms
    instead of 995 ms), with identical pixels except where two surfaces meet at exactly equal depth (2 to
    12 pixels of the examples' frames), where the first
    drawn wins. Still before moving keeps those ties as a kept background draws them: a frame composited
    over a kept background equals the whole draw (`camgen.render.sequence`). Blended (see-through)
    primitives are then taken after every opaque one, farthest first (`_draw_order`)."""
    moving = {id(node) for node in getattr(graph, "moving_nodes", graph.actor_nodes)}
    scene = graph.scene

    def key(node) -> tuple[bool, float]:
        low, high = node.mesh.bounds
        pose = scene.get_pose(node)
        return id(node) in moving, float(np.linalg.norm(pose[:3, :3] @ ((low + high) / 2.0) + pose[:3, 3] - camera_m))

    return sorted(nodes, key=key)


SKY_STEP_PX = 8
"""The sky is evaluated every this many pixels and interpolated (it varies smoothly over degrees)."""


def sky_view(graph, view: View, region: tuple[int, int, int, int] | None = None) -> np.ndarray:
    """(H, W, 3) radiance of the graph's CIE sky through each pixel of `view` (`camgen.world.sky`),
    evaluated on a grid every `SKY_STEP_PX` pixels and interpolated bilinearly; with `region` (x0, y0, x1, y1),
    its pixels only ((y1 − y0, x1 − x0, 3)), each the value the whole view's has there."""
    return _sky_on_grid(graph, view, horizontal=False, region=region)


def _sky_nodes(graph, view: View, *, horizontal: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sky's grid (`_grid_rays` every `SKY_STEP_PX` pixels): columns, rows and the radiance at each node
    (len(vs), len(us), 3), in the world direction of the node's ray (or, with `horizontal`, at the horizon
    under or over it)."""
    from camgen.world.sky import sky_radiance

    us, vs, rays = _grid_rays(view, SKY_STEP_PX)
    if horizontal:
        rays = rays * np.array([1.0, 1.0, 0.0])
        vertical = np.linalg.norm(rays, axis=-1, keepdims=True) < 1e-9  # straight down or up: any azimuth
        rays = np.where(vertical, np.array([1.0, 0.0, 0.0]), rays)
    sun = graph.sun_direction if graph.sun_direction is not None else np.array([0.0, 0.0, 1.0])
    return us, vs, np.ascontiguousarray(sky_radiance(rays, sun, graph.sky, graph.sky_luminance_cd_m2))


def _sky_on_grid(graph, view: View, *, horizontal: bool, region: tuple[int, int, int, int] | None = None) -> np.ndarray:
    """(H, W, 3) the graph's CIE sky radiance in the world direction of each pixel's ray (or, with
    `horizontal`, at the horizon under or over it), evaluated every `SKY_STEP_PX` pixels and
    interpolated bilinearly (the sky varies smoothly over degrees); with `region`, its pixels only."""
    return _sky_interpolated(_sky_nodes(graph, view, horizontal=horizontal), view, region)


def _region_axes(view: View, region: tuple[int, int, int, int] | None) -> tuple[np.ndarray, np.ndarray] | None:
    """The pixel columns and rows of `region` (x0, y0, x1, y1; x1, y1 exclusive) of `view`, None for all."""
    if region is None or tuple(region) == (0, 0, view.width_px, view.height_px):
        return None
    x0, y0, x1, y1 = region
    return np.arange(x0, x1), np.arange(y0, y1)


def _grid_rays(view: View, step_px: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Columns `us` and rows `vs` of a grid every `step_px` pixels from the view's corner plus its last
    pixel, and (len(vs), len(us), 3) the world direction of the ray through each node."""
    us = np.append(np.arange(0, view.width_px, step_px), view.width_px - 1).astype(np.float64)
    vs = np.append(np.arange(0, view.height_px, step_px), view.height_px - 1).astype(np.float64)
    uu, vv = np.meshgrid(us, vs)
    rays_cam = np.stack([uu, vv, np.ones_like(uu)], axis=-1) @ np.linalg.inv(view.K_px).T
    return us, vs, rays_cam @ view.T_world_from_cam[:3, :3].T


def _grid_interpolated(
    coarse: np.ndarray, us: np.ndarray, vs: np.ndarray, view: View, at: tuple[np.ndarray, np.ndarray] | None = None
) -> np.ndarray:
    """(H, W, C): `coarse` (len(vs), len(us), C), given at the grid nodes (`_grid_rays`),
    interpolated bilinearly onto every pixel of `view`, or onto the pixel columns × rows `at`."""

    columns, rows = (np.arange(view.width_px), np.arange(view.height_px)) if at is None else at
    map_u = np.interp(columns, us, np.arange(len(us))).astype(np.float32)
    map_v = np.interp(rows, vs, np.arange(len(vs))).astype(np.float32)
    mx, my = np.meshgrid(map_u, map_v)
    return cv2.remap(np.ascontiguousarray(coarse), mx, my, cv2.INTER_LINEAR)


def _grid_points(coarse: np.ndarray, us: np.ndarray, vs: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """(N, C): `coarse` (len(vs), len(us), C), given at the grid nodes, interpolated at the pixels (`rows`,
    `cols`) as `_grid_interpolated` interpolates them (the same map coordinates through the same `cv2.remap`:
    the same values bit for bit). The pixels are laid out in rows of `_POINTS_ROW` for remap, which refuses an
    image 32767 pixels or more on a side (a near bus's windows hold more pixels than that)."""
    count = len(rows)
    if not count:
        return np.zeros((0, coarse.shape[-1]), coarse.dtype)
    padded = -(-count // _POINTS_ROW) * _POINTS_ROW
    map_u = np.zeros(padded, np.float32)
    map_v = np.zeros(padded, np.float32)
    map_u[:count] = np.interp(cols, us, np.arange(len(us)))
    map_v[:count] = np.interp(rows, vs, np.arange(len(vs)))
    shape = (padded // _POINTS_ROW, _POINTS_ROW)
    out = cv2.remap(np.ascontiguousarray(coarse), map_u.reshape(shape), map_v.reshape(shape), cv2.INTER_LINEAR)
    return out.reshape(padded, -1)[:count]


_POINTS_ROW = 4096
"""Pixels per row of `_grid_points`'s maps: under remap's 32767 a side, and 32766 rows of them hold 134 million."""


def far_ground_depth_m(ground, view: View, region: tuple[int, int, int, int] | None = None) -> np.ndarray:
    """(H, W) float32 camera-z depth at which each pixel's ray meets the far ground's level plane
    (`camgen.render.scene_graph.FarGround`), +inf where the ray does not go down to it (or the camera is
    not above it); with `region` (x0, y0, x1, y1), its pixels only."""
    x0, y0, x1, y1 = region or (0, 0, view.width_px, view.height_px)
    u = np.arange(x0, x1, dtype=np.float64)
    v = np.arange(y0, y1, dtype=np.float64)
    return _far_ground_depth_at(ground, view, v[:, None], u[None, :])


def _far_ground_depth_at(ground, view: View, v: np.ndarray, u: np.ndarray) -> np.ndarray:
    """float32 camera-z depth of the far ground at pixel rows `v` and columns `u` (float64, broadcast
    together): `far_ground_depth_m` pixel by pixel, the same operations."""
    K_inv = np.linalg.inv(view.K_px)
    R = view.T_world_from_cam[:3, :3]
    height_m = float(view.T_world_from_cam[2, 3]) - ground.height_m
    # The world z of the ray (u, v, 1) through K⁻¹ is linear in u and v.
    a, b, c = R[2] @ K_inv
    dz = (a * u + (b * v + c)).astype(np.float32)
    with np.errstate(divide="ignore"):
        depth_m = np.where(dz < 0, np.float32(height_m) / -dz, np.float32(np.inf))
    return depth_m if height_m > 0 else np.full_like(depth_m, np.inf)


MIN_ROUGHNESS = 0.04
"""The shader's lower clamp of roughness (`linear_mesh.frag`), also its dielectric F0."""


FAR_GROUND_TOLERANCE = 1e-3
"""Largest relative difference between the far ground's radiance interpolated from a grid and from a grid
twice as coarse at which the finer one is used as it is; its cells beyond are evaluated pixel by pixel."""


def far_ground_radiance(
    graph, view: View, below: np.ndarray, region: tuple[int, int, int, int] | None = None
) -> np.ndarray:
    """(H, W, 3) float32 radiance of the far ground at the pixels `below` (H, W bool) of `view` (others
    undefined): the shader's BRDF for a level surface of the ground's material (`far_ground_brdf_radiance`).
    With `region` (x0, y0, x1, y1), its pixels only: `below` and the result are the region's.

    A rough ground's radiance changes over degrees, not pixels, so it is evaluated on a grid (nodes every
    `far_ground_step_px` / 2 pixels, placed as the sky's) and interpolated bilinearly, and checked against
    the same interpolation from a grid twice as coarse: a cell of the fine grid with a node where the two
    differ by more than `FAR_GROUND_TOLERANCE` of the radiance (near the horizon under a low sun, where
    Fresnel's grazing term turns fast) is evaluated at every pixel. Measured on the examples at 1280×720,
    max relative error 4e-4 against every pixel evaluated (a tenth of an 8-bit code at full scale). A pixel's
    value does not depend on which others are asked (`_FarGroundNodes`)."""
    return _far_ground_nodes(graph, view).region(graph, view, below, region)


class _FarGroundNodes:
    """The far ground's grid for one view and lighting (`far_ground_radiance`): the fine nodes' columns `us`,
    rows `vs` and radiance `values` (float32), and `far_off`, the nodes where the coarse grid's interpolation
    strays; `values` None for a ground smooth enough to be evaluated at every pixel (`far_ground_step_px` ≤ 2).
    Small (a node every 4 or 8 pixels): kept per view (`BackgroundCache`), the pixels interpolated as asked.

    A row of nodes is evaluated when a pixel first asks for it (`_evaluate_rows`: the rows its interpolation reads,
    and the coarse rows theirs read), each node exactly as the whole grid evaluates it (`far_ground_brdf_radiance`
    and the remap are per node and per pixel); the rows left unevaluated hold 0 and are read by no pixel but with
    weight 0. The far ground shows in a band under the horizon (and behind glass), where a turning head's new
    view each step evaluated the nodes of the whole view: a 2816 × 1624 draw of ptz_follow's dome evaluates 358 000
    nodes, of which its band needs a tenth."""

    def __init__(self, graph, view: View):
        coarse_px = far_ground_step_px(graph.far_ground, view)
        self.us = self.vs = self.values = self.far_off = None
        if coarse_px <= 2:
            return
        self._coarse = _grid_rays(view, coarse_px)
        self.us, self.vs, self._rays = _grid_rays(view, coarse_px // 2)
        self._coarse_values = np.zeros(self._coarse[2].shape)
        self._coarse_done = np.zeros(len(self._coarse[1]), bool)
        self.values = np.zeros((len(self.vs), len(self.us), 3), np.float32)
        self.far_off = np.zeros((len(self.vs), len(self.us)), bool)
        self._done = np.zeros(len(self.vs), bool)

    @property
    def nbytes(self) -> int:
        """What it holds, bytes (`BackgroundCache`), evaluated or not."""
        if self.values is None:
            return 0
        arrays = (*self._coarse, self._coarse_values, self.us, self.vs, self._rays, self.values, self.far_off)
        return sum(array.nbytes for array in arrays)

    def _evaluate_rows(self, graph, view: View, pixel_rows: np.ndarray) -> None:
        """Evaluate the fine rows that interpolation at the pixel rows `pixel_rows` reads (each pixel's row at or
        before it and the next: `cv2.remap` reads no other with a weight above 0), and the far-off test there:
        the coarse grid's interpolation at those fine nodes, from the coarse rows it reads, evaluated too."""
        needed = _rows_read(self.vs, pixel_rows)
        needed = needed[~self._done[needed]]
        if not len(needed):
            return
        us_c, vs_c, rays_c = self._coarse
        coarse_rows = _rows_read(vs_c, self.vs[needed])
        coarse_rows = coarse_rows[~self._coarse_done[coarse_rows]]
        if len(coarse_rows):
            evaluated = far_ground_brdf_radiance(graph, rays_c[coarse_rows].reshape(-1, 3))
            self._coarse_values[coarse_rows] = evaluated.reshape(len(coarse_rows), len(us_c), 3)
            self._coarse_done[coarse_rows] = True
        nodes_f = far_ground_brdf_radiance(graph, self._rays[needed].reshape(-1, 3)).reshape(
            len(needed), len(self.us), 3
        )
        # The coarse grid's interpolation at the fine nodes (each a pixel).
        from_coarse = _grid_interpolated(self._coarse_values, us_c, vs_c, view, at=(self.us, self.vs[needed]))
        scale = np.maximum(nodes_f.max(axis=-1), 1e-30)
        self.far_off[needed] = np.abs(from_coarse - nodes_f).max(axis=-1) / scale > FAR_GROUND_TOLERANCE
        self.values[needed] = nodes_f.astype(np.float32)
        self._done[needed] = True

    def region(self, graph, view: View, below: np.ndarray, region: tuple[int, int, int, int] | None) -> np.ndarray:
        """(h, w, 3) float32 radiance at the pixels `below` (h, w bool) of `region` (None: the view); the others
        undefined (the rows of the region without a pixel below are not interpolated from evaluated nodes)."""
        x0, y0, x1, y1 = region or (0, 0, view.width_px, view.height_px)
        if self.values is None:
            out = np.zeros((y1 - y0, x1 - x0, 3), np.float32)
            rows, cols = np.nonzero(below)
            out[rows, cols] = _far_ground_exact(graph, view, rows + y0, cols + x0)
            return out
        self._evaluate_rows(graph, view, np.flatnonzero(below.any(axis=1)) + y0)
        out = _grid_interpolated(self.values, self.us, self.vs, view, at=_region_axes(view, region))
        if self.far_off.any():
            # A pixel is evaluated where a node its interpolation reads is far off: the nodes at or before and
            # at or after it on each axis (its cell's four corners; on a grid line, only that line's two), so a
            # crop whose edges lie on grid lines decides each pixel as the whole view does.
            u_nodes, v_nodes = _cell_nodes(self.us, np.arange(x0, x1)), _cell_nodes(self.vs, np.arange(y0, y1))
            exact = np.zeros(below.shape, bool)
            for v in v_nodes:
                for u in u_nodes:
                    exact |= self.far_off[np.ix_(v, u)]
            rows, cols = np.nonzero(exact & below)
            out[rows, cols] = _far_ground_exact(graph, view, rows + y0, cols + x0)
        return out

    def points(self, graph, view: View, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """(N, 3) float32 radiance at the pixels (`rows`, `cols`), each as `region` gives it."""
        if self.values is None:
            return _far_ground_exact(graph, view, rows, cols)
        self._evaluate_rows(graph, view, np.unique(rows))
        out = _grid_points(self.values, self.us, self.vs, rows, cols)
        if self.far_off.any() and len(rows):
            exact = np.zeros(len(rows), bool)
            for v in _cell_nodes(self.vs, rows):
                for u in _cell_nodes(self.us, cols):
                    exact |= self.far_off[v, u]
            out[exact] = _far_ground_exact(graph, view, rows[exact], cols[exact])
        return out


def _rows_read(nodes: np.ndarray, pixels: np.ndarray) -> np.ndarray:
    """The grid rows (or columns) that the interpolation at `pixels` reads, sorted: the two that `cv2.remap` reads
    at each pixel's position on the grid as `_grid_interpolated` maps it (the one at or before and the next,
    which has weight 0 on a node), and the nodes at or before and at or after it (`_cell_nodes`, the far-off test)."""
    if not len(pixels):
        return np.zeros(0, np.int64)
    last = len(nodes) - 1
    position = np.floor(np.interp(pixels, nodes, np.arange(len(nodes))).astype(np.float32)).astype(np.int64)
    before, after = _cell_nodes(nodes, pixels)
    rows = np.concatenate([position, position + 1, before, after])
    return np.unique(np.clip(rows, 0, last))


def _cell_nodes(nodes: np.ndarray, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The grid nodes at or before and at or after each pixel on one axis (`far_ground_radiance`)."""
    return np.searchsorted(nodes, pixels, side="right") - 1, np.searchsorted(nodes, pixels, side="left")


def _far_ground_nodes(graph, view: View) -> _FarGroundNodes:
    """The far ground's grid for `view` under the graph's lights now (`_FarGroundNodes`)."""
    return _FarGroundNodes(graph, view)


def _far_ground_exact(graph, view: View, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """(N, 3) float32 far-ground radiance at the pixels (`rows`, `cols`) of `view`, each evaluated."""
    rays = np.stack([cols, rows, np.ones_like(cols)], axis=-1).astype(np.float64) @ np.linalg.inv(view.K_px).T
    return far_ground_brdf_radiance(graph, rays @ view.T_world_from_cam[:3, :3].T).astype(np.float32)


def far_ground_step_px(ground, view: View) -> int:
    """Grid step (1, 2, 4 or `SKY_STEP_PX` pixels) that puts at least eight nodes across the far ground's
    specular lobe. The GGX lobe's half-width in the half vector is about α = roughness² radians and the
    reflected ray turns twice as fast, so the lobe spans about 2α·f pixels, and the step is at most
    α·f / 4 (rough asphalt, roughness 0.9, at f = 1000 px: α·f / 4 = 200, so 8; a wet road at roughness
    0.1: 2.5, so 2)."""
    alpha = max(min(ground.roughness, 1.0), MIN_ROUGHNESS) ** 2
    f_px = float(max(abs(view.K_px[0, 0]), abs(view.K_px[1, 1])))
    bound = alpha * f_px / 4.0
    step_px = 1
    while step_px * 2 <= min(bound, SKY_STEP_PX):
        step_px *= 2
    return step_px


def far_ground_brdf_radiance(graph, rays: np.ndarray) -> np.ndarray:
    """(N, 3) float64 radiance towards the camera of the far ground seen along world `rays` (N, 3): the
    shader's BRDF (`linear_mesh.frag` compute_brdf: Lambert c_diff/π plus GGX D, Schlick–Smith G,
    Schlick F over 4 n·l n·v) for a level surface of the ground's material, under each sun light as it
    is now in the graph (a site's dusk moves them, `SceneGraph.set_daylight`), plus the ambient term
    ρ·ambient_light."""
    ground, scene = graph.far_ground, graph.scene
    v = -rays / np.linalg.norm(rays, axis=1, keepdims=True)  # towards the camera
    rho = np.asarray(ground.reflectance_rgb, np.float64)
    metallic = min(max(ground.metallic, 0.0), 1.0)
    roughness = min(max(ground.roughness, MIN_ROUGHNESS), 1.0)
    c_diff, f0 = rho * (1.0 - metallic), MIN_ROUGHNESS * (1.0 - metallic) + rho * metallic
    out = np.broadcast_to(rho * np.asarray(scene.ambient_light, np.float64), (len(v), 3)).copy()
    nv = np.clip(np.abs(v[:, 2]), 0.001, 1.0)
    k = (roughness + 1.0) ** 2 / 8.0
    a2 = roughness**4
    for node in scene.directional_light_nodes:
        towards_light = scene.get_pose(node)[:3, 2]  # a light shines along its node's −Z
        nl = max(0.0, float(towards_light[2]))
        if nl == 0.0:
            continue
        h = v + towards_light
        h /= np.linalg.norm(h, axis=1, keepdims=True)
        nh, vh = np.clip(h[:, 2], 0.0, 1.0), np.clip(np.sum(v * h, axis=1), 0.0, 1.0)
        fresnel = f0 + (1.0 - f0) * ((1.0 - vh) ** 5)[:, None]
        shadowing = nv / (nv * (1.0 - k) + k) * (nl / (nl * (1.0 - k) + k))
        distribution = a2 / (math.pi * (nh * nh * (a2 - 1.0) + 1.0) ** 2)
        specular = fresnel * (shadowing * distribution / (4.0 * nl * nv + 0.001))[:, None]
        radiance = node.light.intensity * np.asarray(node.light.color, np.float64)
        out += nl * radiance * (c_diff / math.pi + specular)
    return out


@dataclass
class Behind:
    """What a draw's background (the sky and the far ground, filled in after the draw) puts behind its
    pixels (`composite_background`)."""

    open_depth_m: np.ndarray | None
    """(H, W) camera-z depth of the far ground at the pixels that show nothing else, +inf elsewhere (and
    under the sky); None without a far ground or where the draw shows no background at all."""
    rows: np.ndarray
    """(N,) rows and `cols` (N,) columns of the pixels that see the background through glass only."""
    cols: np.ndarray
    transmittance: np.ndarray
    """(N,) float32 τ there: the product of the panes' transmittances, 1 − the target's alpha."""
    radiance: np.ndarray
    """(N, 3) float32 B there: the sky's or the far ground's radiance behind the glass."""
    depth_m: np.ndarray
    """(N,) float32 camera-z depth of that background: the far ground's, +inf for the sky."""


BACKGROUND_CACHE_BYTES = 256 * 2**20
"""What a renderer keeps of the backgrounds of the views it drew lately (`BackgroundCache`), bytes: a 4K
frame's largest crop of a moving region (2440 × 1306 px) keeps its sky, far ground and depth in 89 MB."""


class BackgroundCache:
    """The sky (`sky_view`), the far ground (`far_ground_depth_m`, `far_ground_radiance`) and fog's airlight
    and ray lengths (`fogged_radiance`) of the views drawn lately, each kept by the view (size, K, pose) and
    everything it is computed from (sky type and luminance, sun, the ground's level and material, the sun
    lights and the ambient light): the same values, computed once. A frame's motion blur draws each crop of
    a moving region at s² sub-pixel positions, each `samples` / s² times, and a camera that holds still
    draws the same crops frame after frame. Arrays are kept read-only; the least recently used go first
    past `max_bytes` (0: keep nothing).

    Each is kept as its grid (the sky's and the far ground's nodes, small) and as its pixels over the
    rectangle a draw asked for (`composite_background`: the one holding the draw's open pixels; the far
    ground at every pixel of it whose ray meets the ground); pixels behind glass are interpolated from the
    kept grid, not kept. A pixel's value does not depend on which others are asked
    (tests/render/test_far_ground.py, test_background_cache.py)."""

    def __init__(self, max_bytes: int = BACKGROUND_CACHE_BYTES):
        self.max_bytes = max_bytes
        self._entries: OrderedDict[tuple, tuple[object, int]] = OrderedDict()
        """Each kept value (an array, or a grid's arrays) and its bytes, least recently used first."""
        self._bytes = 0
        self.hits = self.misses = 0

    def __len__(self) -> int:
        return len(self._entries)

    @property
    def nbytes(self) -> int:
        return self._bytes

    def sky(self, graph, view: View, region: tuple[int, int, int, int] | None = None) -> np.ndarray:
        """`sky_view` of `view`, or of its `region`: kept by both."""
        key = ("sky", view.key(), *_sky_key(graph), _region_key(view, region))
        return self._get(key, lambda: _sky_interpolated(self.sky_nodes(graph, view), view, region))

    def sky_nodes(self, graph, view: View) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The sky's grid of `view` (`_sky_nodes`): what every region and pixel of it is interpolated from."""
        key = ("sky nodes", view.key(), *_sky_key(graph))
        return self._get(key, lambda: _sky_nodes(graph, view, horizontal=False))

    def sky_points(self, graph, view: View, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """(N, 3) the sky at the pixels (`rows`, `cols`), each as `sky` gives it; not kept (few, and another
        set each frame: those behind glass), interpolated from the kept grid."""
        us, vs, nodes = self.sky_nodes(graph, view)
        return _grid_points(nodes, us, vs, rows, cols)

    def airlight(self, graph, view: View) -> np.ndarray:
        return self._get(("airlight", view.key(), *_sky_key(graph)), lambda: horizon_airlight(graph, view))

    def ray_lengths(self, view: View) -> np.ndarray:
        key = ("ray lengths", view.width_px, view.height_px, view.K_px.tobytes())  # not the pose: a turning head's
        return self._get(key, lambda: ray_lengths(view))

    def ground_depth_m(self, graph, view: View, region: tuple[int, int, int, int] | None = None) -> np.ndarray:
        key = ("ground depth", view.key(), graph.far_ground.height_m, _region_key(view, region))
        return self._get(key, lambda: far_ground_depth_m(graph.far_ground, view, region))

    def ground_radiance(
        self, graph, view: View, below: np.ndarray, region: tuple[int, int, int, int] | None = None
    ) -> np.ndarray:
        """The far ground's radiance, right at the pixels `below` (`far_ground_radiance`; of `region` with
        one). Kept at every pixel of the view or region whose ray meets the ground. A ground smooth enough to
        be evaluated pixel by pixel (`far_ground_step_px` ≤ 2: a wet road) is not kept: evaluating every pixel
        under the horizon to keep them cost 7 times the open ones' (a 1280 × 720 view, 14 % open)."""
        nodes = self.ground_nodes(graph, view)
        if nodes.values is None:
            return nodes.region(graph, view, below, region)
        key = ("ground", *self._ground_key(graph, view), _region_key(view, region))
        return self._get(
            key, lambda: nodes.region(graph, view, np.isfinite(self.ground_depth_m(graph, view, region)), region)
        )

    def ground_nodes(self, graph, view: View) -> _FarGroundNodes:
        """The far ground's grid of `view` under the graph's lights (`_FarGroundNodes`), kept."""
        return self._get(("ground nodes", *self._ground_key(graph, view)), lambda: _far_ground_nodes(graph, view))

    def ground_points(self, graph, view: View, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """(N, 3) float32 the far ground at the pixels (`rows`, `cols`), each as `ground_radiance` gives it;
        not kept, interpolated from the kept grid."""
        return self.ground_nodes(graph, view).points(graph, view, rows, cols)

    @staticmethod
    def _ground_key(graph, view: View) -> tuple:
        scene = graph.scene
        lights = tuple(
            (scene.get_pose(node)[:3, 2].tobytes(), float(node.light.intensity), _bytes_of(node.light.color))
            for node in scene.directional_light_nodes
        )
        return view.key(), graph.far_ground, _bytes_of(scene.ambient_light), lights

    def _get(self, key: tuple, make):
        kept = self._entries.get(key)
        if kept is not None:
            self._entries.move_to_end(key)
            self.hits += 1
            return kept[0]
        self.misses += 1
        value = make()
        nbytes = _frozen_bytes(value)
        if self.max_bytes and nbytes <= self.max_bytes:  # 0 keeps nothing, an empty grid neither
            self._entries[key] = (value, nbytes)
            self._bytes += nbytes
            while self._bytes > self.max_bytes:
                _, (_, dropped) = self._entries.popitem(last=False)
                self._bytes -= dropped
        return value


def _frozen_bytes(value) -> int:
    """The bytes of the arrays in `value` (an array, a tuple of them or a dataclass holding them), each made
    read-only: what `BackgroundCache` keeps is shared by every caller. A far ground's grid (`_FarGroundNodes`)
    fills its rows as they are asked for: its own bytes, left writable."""
    if isinstance(value, _FarGroundNodes):
        return value.nbytes
    if isinstance(value, np.ndarray):
        value.setflags(write=False)
        return value.nbytes
    if isinstance(value, tuple):
        return sum(_frozen_bytes(item) for item in value)
    if hasattr(value, "__dataclass_fields__"):
        return sum(_frozen_bytes(getattr(value, name)) for name in value.__dataclass_fields__)
    return 0


def _region_key(view: View, region: tuple[int, int, int, int] | None) -> tuple[int, int, int, int]:
    return tuple(int(x) for x in region) if region is not None else (0, 0, view.width_px, view.height_px)


def _sky_interpolated(nodes: tuple, view: View, region: tuple[int, int, int, int] | None) -> np.ndarray:
    """The sky over `region` of `view` (None: all of it) from its grid `nodes` (`_sky_nodes`)."""
    us, vs, values = nodes
    return _grid_interpolated(values, us, vs, view, at=_region_axes(view, region))


def _sky_key(graph) -> tuple:
    """What the sky's radiance in a direction depends on: its type, luminance and the sun."""
    return getattr(graph, "sky", "uniform"), float(graph.sky_luminance_cd_m2), _bytes_of(graph.sun_direction)


def _bytes_of(values) -> bytes | None:
    return None if values is None else np.asarray(values, np.float64).tobytes()


def composite_background(
    graph, view: View, radiance: np.ndarray, coverage: np.ndarray, backgrounds: BackgroundCache | None = None
) -> Behind:
    """Fill in the background behind a draw's `radiance` (H, W, 3; in place) from the target's alpha
    `coverage` (H, W; `_Framebuffer.coverage`): the CIE sky (`sky_view`) or the far ground
    (`far_ground_radiance`) where it is 0, exactly, and where glass lies over the background
    (0 < alpha < 1), radiance += τ·(B − clear): the draw blended the panes over the clear colour (the
    uniform `sky_luminance_cd_m2`), which the background B replaces in the share τ = 1 − alpha of it
    that the glass transmits. Returns what fog needs (`fogged_radiance`). `backgrounds`: the sky and far
    ground of views drawn before (`BackgroundCache`; the same values, computed once).

    The sky and far ground are made over the rectangle of the open pixels only, and at the pixels behind
    glass one by one, each the whole view's value bit for bit: a turning head's new view each step made them
    over every pixel, where a site's own ground hides most (a 1408 × 812 turning sim step of the parking lot:
    466 → 433 ms of CPU; the same frames)."""
    if not (coverage < 1.0).any():  # opaque throughout (most crops of motion blur's sub-frames): nothing behind
        empty = np.zeros(0, np.int64)
        nothing = np.zeros(0, np.float32)
        return Behind(None, empty, empty.copy(), nothing, np.zeros((0, 3), np.float32), nothing.copy())
    cache = BackgroundCache(0) if backgrounds is None else backgrounds
    open_sky = coverage == 0.0
    rows, cols = np.nonzero((coverage > 0.0) & (coverage < 1.0))
    clear = np.float32(graph.sky_luminance_cd_m2)
    region = _bounding_rect(open_sky)  # the open pixels' rectangle: the sky and far ground are made there only
    any_background = bool(len(rows)) or region is not None
    if region is not None:
        x0, y0, x1, y1 = region
        opened, open_sky = radiance[y0:y1, x0:x1], open_sky[y0:y1, x0:x1]
    far_ground = getattr(graph, "far_ground", None) is not None and any_background
    below = None
    if far_ground and region is not None:
        ground_depth_m = cache.ground_depth_m(graph, view, region).copy()
        ground_depth_m[~open_sky] = np.inf
        below = np.isfinite(ground_depth_m)
    if getattr(graph, "sky", "uniform") != "uniform" and any_background:
        if region is not None:  # where the far ground does not lie over it
            skyward = open_sky if below is None else open_sky & ~below
            _fill_part(opened, skyward, lambda rect: cache.sky(graph, view, _moved_rect(rect, x0, y0)))
        behind = cache.sky_points(graph, view, rows, cols)
    else:
        behind = np.full((len(rows), 3), clear, np.float32)
    behind_depth_m = np.full(len(rows), np.inf, np.float32)
    open_depth_m = None
    if far_ground:
        behind_depth_m = _far_ground_depth_at(graph.far_ground, view, rows.astype(np.float64), cols.astype(np.float64))
        open_depth_m = np.full(coverage.shape, np.inf, np.float32)
        if region is not None:

            def ground(rect: tuple[int, int, int, int]) -> np.ndarray:
                a, b, c, d = rect
                return cache.ground_radiance(graph, view, below[b:d, a:c], _moved_rect(rect, x0, y0))

            _fill_part(opened, below, ground)
            open_depth_m[y0:y1, x0:x1] = ground_depth_m
        under = np.isfinite(behind_depth_m)
        if under.any():
            behind[under] = cache.ground_points(graph, view, rows[under], cols[under])
    transmittance = 1.0 - coverage[rows, cols]
    radiance[rows, cols] += transmittance[:, None] * (behind - clear)
    return Behind(open_depth_m, rows, cols, transmittance, behind, behind_depth_m)


def _fill_part(image: np.ndarray, mask: np.ndarray, make) -> None:
    """`image`'s pixels where `mask` holds, from `make(rect)`: the values over `mask`'s bounding rectangle (x0, y0,
    x1, y1) of `image`, made for those pixels only (the sky's or the far ground's: each pixel's value is the whole
    view's whatever the rectangle, `BackgroundCache`). The open pixels' rectangle of a view spans the sky above
    the horizon and the ground under it, and each was made over all of it; now each over its own part (a turning
    2816 × 1624 draw of ptz_follow: a rectangle of 2816 × 679, the sky's part 2816 × 258, the ground's 2816 × 421)."""
    rect = _bounding_rect(mask)
    if rect is None:
        return
    x0, y0, x1, y1 = rect
    part, where = image[y0:y1, x0:x1], mask[y0:y1, x0:x1]
    np.copyto(part, make(rect), where=where[..., None])


def _moved_rect(rect: tuple[int, int, int, int], dx: int, dy: int) -> tuple[int, int, int, int]:
    """`rect` (x0, y0, x1, y1) moved by (dx, dy)."""
    x0, y0, x1, y1 = rect
    return x0 + dx, y0 + dy, x1 + dx, y1 + dy


def _bounding_rect(mask: np.ndarray) -> tuple[int, int, int, int] | None:
    """(x0, y0, x1, y1) of the smallest rectangle holding every True of `mask` (x1, y1 exclusive), or None."""
    columns = np.flatnonzero(mask.any(axis=0))
    if not len(columns):
        return None
    rows = np.flatnonzero(mask[:, columns[0] : columns[-1] + 1].any(axis=1))
    return int(columns[0]), int(rows[0]), int(columns[-1]) + 1, int(rows[-1]) + 1


def ray_lengths(view: View) -> np.ndarray:
    """(H, W) float32 length of the ray through each pixel per metre of camera z, |K⁻¹(u, v, 1)|:
    distance = depth_m × this."""
    K = view.K_px
    y = ((np.arange(view.height_px) - K[1, 2]) / K[1, 1])[:, None]
    x = (np.arange(view.width_px)[None, :] - K[0, 2] - K[0, 1] * y) / K[0, 0]
    return np.sqrt(x * x + (y * y + 1.0)).astype(np.float32)


def horizon_airlight(graph, view: View) -> np.ndarray:
    """(3,) or (H, W, 3) airlight of the graph's fog (`camgen.world.fog`): the sky's radiance at the
    horizon in each pixel's azimuth; a uniform sky's one luminance."""
    if getattr(graph, "sky", "uniform") == "uniform":
        return np.full(3, graph.sky_luminance_cd_m2, np.float32)
    return _sky_on_grid(graph, view, horizontal=True)


def fogged_radiance(
    graph,
    view: View,
    radiance: np.ndarray,
    depth_m: np.ndarray,
    visibility_m: float,
    behind: Behind | None = None,
    backgrounds: BackgroundCache | None = None,
) -> np.ndarray:
    """`radiance` of `view` seen through the graph's fog (`camgen.world.fog.apply_fog`, Koschmieder 1924),
    the distance of each pixel from its depth (camera z, +inf for the sky).

    Where glass lies over the background (`behind`, from `composite_background`), fog lies both between
    the camera and the glass (d_g) and between the glass and the background (d_B), and the glass passes
    τ of what reaches it. With t_g = exp(−3.912 d_g / V), t_B = exp(−3.912 d_B / V) (0 for the sky),
    A the airlight, R the glass's own (reflected) radiance and B the background's: the light reaching the
    glass from behind is B·t_B/t_g + A·(1 − t_B/t_g) (Koschmieder over d_B − d_g), and the camera sees

        L = t_g·(R + τ·(B·t_B/t_g + A·(1 − t_B/t_g))) + (1 − t_g)·A
          = t_g·R + τ·(t_B·B + (t_g − t_B)·A) + (1 − t_g)·A.

    The composited pixel R + τ·B fogged as a surface at d_g gives t_g·(R + τ·B) + (1 − t_g)·A, so the
    pixel takes τ·(t_g − t_B)·(A − B) more. `backgrounds`: as `composite_background`'s."""
    from camgen.world.fog import apply_fog, transmittance

    cache = BackgroundCache(0) if backgrounds is None else backgrounds
    lengths, airlight = cache.ray_lengths(view), cache.airlight(graph, view)
    out = apply_fog(radiance, depth_m * lengths, airlight, visibility_m)
    if behind is not None and len(behind.rows):
        rows, cols = behind.rows, behind.cols
        t_glass = transmittance(depth_m[rows, cols] * lengths[rows, cols], visibility_m)
        t_behind = transmittance(behind.depth_m * lengths[rows, cols], visibility_m)
        air = airlight[rows, cols] if airlight.ndim == 3 else airlight
        share = (behind.transmittance * (t_glass - t_behind)).astype(np.float32)
        out[rows, cols] += share[:, None] * (air - behind.radiance)
    return out


SHADOW_MARGIN_M = 0.5
"""The fitted shadow box reaches this far beyond what the view and the scene's bounds require, m."""


def frustum_corners_m(view: View, near_m: float, far_m: float) -> np.ndarray:
    """(8, 3) world corners of a view's frustum between `near_m` and `far_m` (camera z)."""
    K_inv = np.linalg.inv(view.K_px)
    u = np.array([-0.5, view.width_px - 0.5])
    v = np.array([-0.5, view.height_px - 0.5])
    rays = np.array([K_inv @ (x, y, 1.0) for x in u for y in v])
    camera = np.concatenate([rays * near_m, rays * far_m])
    T = view.T_world_from_cam
    return camera @ T[:3, :3].T + T[:3, 3]


def seen_part_of_box_m(view: View, near_m: float, far_m: float, low_m, high_m) -> np.ndarray:
    """(N, 3) the vertices of the part of the box [low_m, high_m] inside the view's frustum (the
    intersection of two convex solids: of the points where three of their twelve bounding planes
    meet, those inside all twelve); the frustum's corners when the two do not meet."""
    corners = frustum_corners_m(view, near_m, far_m)
    camera = view.T_world_from_cam[:3, 3]
    # Frustum planes as a·x ≤ b: near, far, and the four sides through the camera centre.
    near, far = corners[:4], corners[4:]
    axis = view.T_world_from_cam[:3, 2]
    normals, offsets = [-axis, axis], [-axis @ near[0], axis @ far[0]]
    centre = corners.mean(axis=0)
    for a, b in ((0, 1), (1, 3), (3, 2), (2, 0)):  # near corners in order (u, v): 00, 01, 10, 11
        n = np.cross(near[a] - camera, near[b] - camera)
        n = n if n @ (centre - camera) < 0 else -n
        normals.append(n / np.linalg.norm(n))
        offsets.append(normals[-1] @ camera)
    for k in range(3):
        e = np.zeros(3)
        e[k] = 1.0
        normals += [e, -e]
        offsets += [float(high_m[k]), -float(low_m[k])]
    A, b = np.array(normals), np.array(offsets)
    triples = np.array([(i, j, k) for i in range(12) for j in range(i + 1, 12) for k in range(j + 1, 12)])
    M, rhs = A[triples], b[triples]
    solvable = np.abs(np.linalg.det(M)) > 1e-12
    points = np.linalg.solve(M[solvable], rhs[solvable][..., None])[..., 0]
    tolerance = 1e-6 * (1.0 + np.abs(b).max())
    inside = points[np.all(points @ A.T <= b + tolerance, axis=1)]
    return inside if len(inside) else corners


def directional_shadow_matrices(
    R_world_from_light: np.ndarray, scene_corners_m: np.ndarray, focus_m: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """(V, P): view and orthographic projection of a sun's shadow map (OpenGL conventions; the light
    looks down its −z axis, `R_world_from_light`'s third column pointing back towards the sun).

    Across the light, the box is the overlap of the scene's bounds and the points `focus_m` (the
    view's frustum), each as a rectangle in the light's x, y (so it holds every point the view sees
    and every caster whose shadow can reach one); along it, the whole scene, so casters outside the
    view still cast. A rectangle per axis, not a square: the texels are spent where they are seen."""
    V = np.eye(4)
    V[:3, :3] = R_world_from_light.T
    scene_light = scene_corners_m @ V[:3, :3].T
    low, high = scene_light.min(axis=0), scene_light.max(axis=0)
    if focus_m is not None:
        focus_light = np.asarray(focus_m) @ V[:3, :3].T
        seen_low, seen_high = np.maximum(low, focus_light.min(axis=0)), np.minimum(high, focus_light.max(axis=0))
        if np.all(seen_low[:2] < seen_high[:2]):
            low[:2], high[:2] = seen_low[:2], seen_high[:2]
    low, high = low - SHADOW_MARGIN_M, high + SHADOW_MARGIN_M
    left, bottom, right, top = low[0], low[1], high[0], high[1]
    near, far = -high[2], -low[2]  # the light looks down −z
    P = np.array(
        [
            [2 / (right - left), 0, 0, -(right + left) / (right - left)],
            [0, 2 / (top - bottom), 0, -(top + bottom) / (top - bottom)],
            [0, 0, -2 / (far - near), -(far + near) / (far - near)],
            [0, 0, 0, 1],
        ]
    )
    return V, P


SUN_CASCADES = 3
"""Shadow maps per sun, each over a slice of the fitted view's depth (cascaded shadow maps). One map over
the whole view left the sun's texels 4-30 output pixels wide on the ground nearest the example cameras (2-8
cm texels against 0.3-0.7 cm pixels at the image's bottom edge), the filter's 4-texel ramp a 12 cm blur at
a pedestrian's feet; the first of three cascades makes them 0.7-5 pixels (0.3-1.7 cm texels). The shader
(`linear_mesh.frag`, SUN_EXTRA_CASCADES) holds the other SUN_CASCADES - 1 maps. (Figures at the example cameras'
own sizes with 2048-texel maps; `shadow_map_size_texels` keeps them in pixels for smaller renders.)"""

SHADOW_MAP_TEXELS_PER_PX = 1.0
"""A shadow map has at least this many texels per side for each pixel on the larger side of the view it is
fitted to (`shadow_map_size_texels`). The example cameras' renders (their sensors and the plan's margin,
2004-4420 px across) have 0.46-1.02 with pyrender's 2048-texel maps; the cascades' texels were measured on
them (`SUN_CASCADES`)."""

SHADOW_MAP_MIN_TEXELS = 512
"""The smallest shadow map, texels per side. Smaller maps save nothing measurable (a 160×120 draw of the
parking lot: 126-128 ms of CPU at 256 and 512 texels, 156 ms at 2048; the passes cost their draw calls), while
the filter's 4-texel kernel grows in the world: at 256 texels (5 cm) it ate most of the light a car's windows
let onto the ground in a 160×120 view (tests/render/test_glass_background.py: 13 fully lit pixels, 36 at 512,
67 at 2048)."""


def shadow_map_size_texels(view: View) -> int:
    """Texels per side of every shadow map of draws whose shadows are fitted to `view`: the power of two
    that gives at least `SHADOW_MAP_TEXELS_PER_PX` per pixel of the view's larger side, from
    `SHADOW_MAP_MIN_TEXELS` to pyrender's `SHADOW_TEX_SZ` (any view over 1024 px across gets 2048, as before).

    A cascade's rectangle is fitted to what the view sees (`sun_cascade_matrices`), the same region of the
    world whatever the view's pixel count L (its larger side) for a given field of view; so its texel is
    that rectangle's width over N texels, while a pixel at distance d spans d / f_px with f_px ∝ L: the
    texel in pixels grows as L / N. So N ∝ L keeps a texel's width in pixels, hence a shadow's sharpness,
    no worse than the example cameras' at their own sizes; the filter's reach and the depth biases are in
    texels (`linear_mesh.frag`, which reads each map's size), so a shadow's soft edge keeps its width in
    pixels too. Draws sharing a `ShadowFit` share its view, hence their maps' size (a supersampled draw's
    samples share the output pixel's maps). Spot lights keep `SHADOW_TEX_SZ`: a spot's map spans its cone,
    whatever the view, so a small render zoomed in on a lamp's pool sees its texels as large as a large one
    does (a 160×120 view at 2.5 mm a pixel, tests/render/test_spot_shadows.py, has 2.8 cm texels at 2048)."""
    needed = SHADOW_MAP_TEXELS_PER_PX * max(view.width_px, view.height_px)
    size = 2 ** math.ceil(math.log2(needed))
    return int(min(SHADOW_TEX_SZ, max(SHADOW_MAP_MIN_TEXELS, size)))


CASCADE_SPLIT_LOG_WEIGHT = 0.75
"""Weight of the logarithmic split distance against the uniform one (Zhang et al. 2006, "Parallel-split
shadow maps for large-scale virtual environments", their practical split scheme: z_i = λ n (f/n)^(i/N) +
(1 − λ)(n + (f − n) i/N), with λ about 0.5-0.8)."""

CASCADE_NEAR_M = 1.0
"""The split scheme's nearest near distance, m (the draw's near plane is 5 cm, which would squeeze the
logarithmic splits against the lens; a fixed camera films nothing it needs shadows on nearer than this), and
the least depth its splits span (`sun_cascade_matrices`)."""

CASCADE_TEXEL_STEPS_PER_OCTAVE = 8
"""A cascade's texel is rounded up to 2^(k/8) m, and its rectangle snapped to whole texels, so that as a PTZ
camera pans its maps keep their texel grid fixed in the light's frame and shadow edges do not shimmer
(stable cascades: the texels move only when the view's extent crosses a step of 9 %)."""


def cascade_splits_m(near_m: float, far_m: float, count: int) -> np.ndarray:
    """(count + 1,) view depths, m, bounding each cascade's slice: Zhang et al.'s practical split scheme
    (`CASCADE_SPLIT_LOG_WEIGHT`) between `near_m` and `far_m`."""
    i = np.arange(count + 1) / count
    log = near_m * (far_m / near_m) ** i
    uniform = near_m + (far_m - near_m) * i
    return CASCADE_SPLIT_LOG_WEIGHT * log + (1.0 - CASCADE_SPLIT_LOG_WEIGHT) * uniform


def _texel_snapped(low: np.ndarray, high: np.ndarray, size_texels: int) -> tuple[np.ndarray, np.ndarray]:
    """A rectangle holding [low, high] (per axis) whose texels are on the ladder
    `CASCADE_TEXEL_STEPS_PER_OCTAVE` and whose corner sits on a whole texel of the light's frame."""
    steps = CASCADE_TEXEL_STEPS_PER_OCTAVE
    texel = 2.0 ** (np.ceil(np.log2((high - low) / (size_texels - 1)) * steps) / steps)
    snapped_low = np.floor(low / texel) * texel
    return snapped_low, snapped_low + size_texels * texel


def sun_cascade_scales(cascades: list[tuple[np.ndarray, np.ndarray]], size_texels: int) -> np.ndarray:
    """(SUN_CASCADES, 2) float32: for each cascade (V, P) of a sun (`sun_cascade_matrices`), the depth scale of
    its P·V (the length of the first three entries of its row 2: map depth units per metre, V a rotation) and
    its texel in metres (the coarser of its two axes': 2 / (size · the length of row 0's or row 1's first three
    entries)), which the shader's bias (`linear_mesh.frag` shadow_calc_ortho) reads; worked out in float32 as
    the shader did at every pixel from the matrix it was sent."""
    scales = np.empty((len(cascades), 2), dtype=np.float32)
    for k, (V, P) in enumerate(cascades):
        rows = (np.asarray(P, np.float64) @ np.asarray(V, np.float64)).astype(np.float32)[:3, :3]
        lengths = np.sqrt((rows * rows).sum(axis=1, dtype=np.float32), dtype=np.float32)
        size = np.float32(size_texels)
        texel_m = max(np.float32(2.0) / (size * lengths[0]), np.float32(2.0) / (size * lengths[1]))
        scales[k] = (lengths[2], texel_m)
    return scales


def sun_cascade_matrices(
    R_world_from_light: np.ndarray,
    box_m: tuple[np.ndarray, np.ndarray],
    view: View,
    near_m: float,
    far_m: float,
    size_texels: int,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """`SUN_CASCADES` (V, P) pairs of a sun's shadow maps, finest first: each `directional_shadow_matrices`
    fitted to the part of the box [low, high] (every caster) that `view` sees between two split depths
    (`cascade_splits_m`, over the depths of the part of the box it sees, from its nearest, but no nearer than
    `CASCADE_NEAR_M`), its rectangle snapped to whole texels (`_texel_snapped`). The last slice ends at the
    farthest seen point, so every seen point lies in one of the maps; the shader takes the first map that
    holds a point with its filter's reach, the finest where each slice sees part of the box (a camera above
    every caster sees none of it nearer than its height over them; splits from 1 m there left the nearer
    slices empty, fitted to the frustum's corners in the air, and the ground was read from those)."""
    low_m, high_m = box_m
    corners = box_corners(low_m, high_m, np.eye(4))
    seen = seen_part_of_box_m(view, near_m, far_m, low_m, high_m)
    T_cam_from_world = np.linalg.inv(view.T_world_from_cam)
    depths = seen @ T_cam_from_world[:3, :3].T + T_cam_from_world[:3, 3]
    farthest = float(np.clip(depths[:, 2].max(), near_m, far_m))
    nearest = max(near_m, CASCADE_NEAR_M, float(depths[:, 2].min()))
    splits = cascade_splits_m(nearest, max(farthest, nearest + CASCADE_NEAR_M), SUN_CASCADES)
    splits[0] = near_m  # the first slice holds everything nearer too
    matrices = []
    for k in range(SUN_CASCADES):
        focus = seen_part_of_box_m(view, splits[k], splits[k + 1], low_m, high_m)
        V, P = directional_shadow_matrices(R_world_from_light, corners, focus)
        left, right = (-1 - P[0, 3]) / P[0, 0], (1 - P[0, 3]) / P[0, 0]
        bottom, top = (-1 - P[1, 3]) / P[1, 1], (1 - P[1, 3]) / P[1, 1]
        (left, bottom), (right, top) = _texel_snapped(np.array([left, bottom]), np.array([right, top]), size_texels)
        P = P.copy()
        P[0, 0], P[0, 3] = 2 / (right - left), -(right + left) / (right - left)
        P[1, 1], P[1, 3] = 2 / (top - bottom), -(top + bottom) / (top - bottom)
        matrices.append((V, P))
    return matrices


def _upload_deformed(graph, staged: weakref.WeakKeyDictionary | None = None) -> None:
    """Copy the vertices of primitives that moved since their last upload into their vertex buffer
    (pyrender uploads a primitive once, each vertex's attributes interleaved in this order: position,
    normal, tangent, TEXCOORD_0, TEXCOORD_1, COLOR_0).

    `staged`: per primitive, its interleaved rows as last uploaded and the attributes after the normals they
    were made with; a placement changes positions and normals only, so while those others are the same
    arrays their columns stand and only the positions' and normals' are written (`Renderer`'s: the vehicles' texture
    coordinates and colours were stacked again at every placement; the intersection's 58 deformed primitives, 101 k
    vertices, 1.8 → 1.4 ms an upload). The same bytes as stacking every column anew."""
    deformed = getattr(graph, "deformed", set())
    for primitive in deformed:
        if primitive._vaid is None:  # not in the context yet: its first upload takes the new vertices
            continue
        moving = [column for column in (primitive.positions, primitive.normals) if column is not None]
        fixed = tuple(
            column
            for column in (primitive.tangents, primitive.texcoord_0, primitive.texcoord_1, primitive.color_0)
            if column is not None
        )
        shapes = tuple(column.shape for column in moving)
        kept = None if staged is None else staged.get(primitive)
        if (
            kept is not None
            and kept[1] == shapes
            and len(kept[0]) == len(fixed)
            and all(map(operator.is_, kept[0], fixed))
        ):
            data = kept[2]
            width = 0
            for column in moving:
                data[:, width : width + column.shape[1]] = column
                width += column.shape[1]
        else:
            data = np.ascontiguousarray(np.hstack([*moving, *fixed]), dtype=np.float32)
            if staged is not None:
                staged[primitive] = (fixed, shapes, data)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, primitive._buffers[0])
        GL.glBufferSubData(GL.GL_ARRAY_BUFFER, 0, data.nbytes, data)
    GL.glBindBuffer(GL.GL_ARRAY_BUFFER, 0)
    deformed.clear()


def _destroy_context(display, context) -> None:
    from OpenGL import EGL

    EGL.eglMakeCurrent(display, EGL.EGL_NO_SURFACE, EGL.EGL_NO_SURFACE, EGL.EGL_NO_CONTEXT)
    EGL.eglDestroyContext(display, context)


def _scene_clip_range_m(scene, T_world_from_cam: np.ndarray) -> tuple[float, float]:
    """Near and far clipping distances: far just beyond the farthest corner of the scene's bounds."""
    corners = box_corners(*scene.bounds, np.eye(4))
    return clip_planes_m(float(np.max(np.linalg.norm(corners - T_world_from_cam[:3, 3], axis=1))))


def clip_planes_m(farthest_m: float) -> tuple[float, float]:
    """Near and far planes for geometry no farther than `farthest_m`: far a little beyond it."""
    return NEAR_CLIP_M, max(2.0 * NEAR_CLIP_M, farthest_m * 1.01 + 1.0)


__all__ = [
    "PASSES",
    "Passes",
    "Renderer",
    "ShadowFit",
    "View",
    "gl_camera_pose",
    "gl_projection",
    "shadow_map_size_texels",
]
