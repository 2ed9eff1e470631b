"""Building pyrender meshes from scene shapes: what cannot be drawn is refused with a clear error."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from camgen.config.scene import FileMesh
from camgen.errors import ConfigError

pytestmark = pytest.mark.opengl


def test_a_point_cloud_file_is_refused(tmp_path):
    from camgen.render.scene_graph import build_mesh

    trimesh.PointCloud(np.random.default_rng(0).random((20, 3))).export(tmp_path / "cloud.ply")
    shape = FileMesh.model_validate({"type": "file", "name": "cloud", "path": "cloud.ply"})
    with pytest.raises(ConfigError, match="holds no triangles"):
        build_mesh(shape, tmp_path.joinpath)
