"""The renderer's answers kept per draw call's question (`_LinearProgramCache`'s programs, `_compute_max_n_lights`)
are the ones asked for afresh."""

from __future__ import annotations

import pyrender
import pytest
from pyrender.constants import RenderFlags

pytestmark = pytest.mark.opengl


def test_programs_are_kept_per_question_and_light_kinds(renderer):
    renderer._make_current()
    cache = renderer._renderer._program_cache
    defines = {"USE_MATERIAL": 1, "HAS_NORMALS": 1}
    cache.absent_lights = ()
    lit = cache.get_program("mesh.vert", "mesh.frag", defines=defines)
    assert cache.get_program("mesh.vert", "mesh.frag", defines=dict(defines)) is lit
    cache.absent_lights = ("NO_SPOT_LIGHTS",)
    without_spots = cache.get_program("mesh.vert", "mesh.frag", defines=defines)
    assert without_spots is not lit  # another program: compiled without the spot lights' loop
    assert without_spots.defines.get("NO_SPOT_LIGHTS") == 1 and "NO_SPOT_LIGHTS" not in lit.defines
    cache.absent_lights = ()
    assert cache.get_program("mesh.vert", "mesh.frag", defines=defines) is lit
    # What pyrender's own cache answers (its key sorts the defines) is the kept program.
    assert (
        pyrender.shader_program.ShaderProgramCache.get_program(
            cache, str(cache_path(cache, "mesh.vert")), str(cache_path(cache, "mesh.frag")), None, defines
        )
        is lit
    )


def cache_path(cache, name):
    from camgen.render.renderer import SHADER_DIR

    return SHADER_DIR / cache.OURS[name]


def test_light_room_is_kept_per_flags(renderer):
    """The kept room equals the room worked out afresh (OpenGL asked again), for each kind of shadow."""
    renderer._make_current()
    passes = renderer._renderer
    for flags in (
        RenderFlags.NONE,
        RenderFlags.SHADOWS_DIRECTIONAL,
        RenderFlags.SHADOWS_SPOT,
        RenderFlags.SHADOWS_DIRECTIONAL | RenderFlags.SHADOWS_SPOT,
    ):
        kept = passes._compute_max_n_lights(flags)
        kept.append(-1)  # a caller's change of the list it got does not reach the kept one
        passes._max_n_lights.clear()
        assert passes._compute_max_n_lights(flags) == kept[:3]
        assert passes._compute_max_n_lights(flags) == kept[:3]
