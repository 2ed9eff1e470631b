"""`camgen.render.renderer.copies_images`: a sun's kept caster depths are copied with glCopyImageSubData (OpenGL
4.3 or GL_ARB_copy_image); an OpenGL 4.0–4.2 that `check_gl_features` accepts draws every caster instead of
failing at its second shadow draw with PyOpenGL's NullFunctionError."""

from __future__ import annotations

import pytest

from camgen.render.renderer import check_gl_features, copies_images


def test_copies_images_from_opengl_4_3_or_with_the_extension():
    assert copies_images((4, 5), set())
    assert copies_images((4, 3), set())
    assert copies_images((4, 1), {"GL_ARB_copy_image"})
    assert not copies_images((4, 2), {"GL_ARB_texture_gather"})
    assert not copies_images((3, 3), {"GL_ARB_texture_gather"})
    check_gl_features((4, 2), set(), "an OpenGL 4.2 driver")  # accepted: it must then draw every caster


@pytest.mark.opengl
def test_a_renderer_keeps_still_casters_where_its_opengl_copies_images(renderer):
    assert renderer._renderer.keep_still_casters  # llvmpipe's 4.5 and every current GPU driver
