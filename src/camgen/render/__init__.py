"""Rendering through pyrender, headless over EGL.

This is the only package that touches OpenGL. `PYOPENGL_PLATFORM` must be set before PyOpenGL is first
imported, so it is set here, and pyrender is only ever imported through `camgen.render.gl`.
"""
