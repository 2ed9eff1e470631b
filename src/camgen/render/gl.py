"""pyrender, imported headless (EGL) and patched for NumPy 2 — the one place either happens.

pyrender 0.1.45 still uses ``np.infty``, which NumPy 2.0 removed; it is the same object as
``np.inf``. Mesa's llvmpipe provides EGL on machines without a GPU; an NVIDIA driver is used where
one is present. pyrender imports its viewer, and so pyglet's window module, which by default loads X11's
libraries (libXrender …) that a GPU server without a desktop lacks; pyglet's headless option (EGL, no X)
spares them. camgen never opens a window.
"""

from __future__ import annotations

import os

import numpy as np

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
os.environ.setdefault("PYGLET_HEADLESS", "true")
if not hasattr(np, "infty"):
    np.infty = np.inf  # noqa: NPY201 — the NumPy-2 shim pyrender 0.1.45 needs

import pyrender  # imported after the platform and the shim are set

__all__ = ["pyrender"]
