"""Per-frame optical flow and scene flow of one camera, from the scene graph's known motion
(`camgen.annotate.flow` does the geometry).

Each output pixel of frame t (on the stream: after the lens and a virtual PTZ's crop) sees the surface
of its instance id at its depth; its displacement until t + 1 is

- zero for the still environment and the sky;
- the pose change of an actor whose node moves (a rigid shape: its pose at t + 1 times the inverse of
  that at t), exact;
- for an actor whose mesh is posed in the world instead (a person or glTF character, skinned; a
  procedural vehicle) or a tree or bush swaying in the wind (`camgen.props.sway`), the barycentric blend of
  the corner motions of the posed triangle the point lies on (`mesh_displacement_m`): exact for a point on
  the mesh.

The camera at t + 1 is the plan's state of that frame: its pose (a PTZ head's pan and tilt), zoom,
distortion and, for a virtual PTZ, the stream's camera matrix. Depth comes from the nearest render
pixel through the lens (as the depth output's), so within a pixel a surface's slope shifts the point
slightly along the ray; on a rotation the flow does not depend on depth at all.
"""

from __future__ import annotations

import numpy as np

from camgen.annotate.flow import (
    forward_flow_px,
    mesh_displacement_m,
    rigid_displacement_m,
    surface_points_m,
)
from camgen.job import CameraState
from camgen.optics.projection import undistort_points
from camgen.optics.remap import output_grid_px
from camgen.plan.lens_stages import LensStages
from camgen.render.renderer import Passes
from camgen.render.sequence import CameraRenderer


def stream_camera(state: CameraState) -> tuple[np.ndarray, tuple[float, ...]]:
    """Camera matrix and distortion of the image the camera delivers (a virtual PTZ's stream: its
    `output_K_px`, with the sensor's distortion)."""
    return np.array(state.K_px if state.output_K_px is None else state.output_K_px), tuple(state.distortion)


class FlowField:
    """Forward optical flow and scene flow of one camera's frames; keeps each lens geometry's rays."""

    def __init__(self, drawer: CameraRenderer, lens: LensStages):
        self.drawer, self.lens, self.graph = drawer, lens, drawer.graph
        camera = drawer.camera
        self.size_px = camera.output_size_px or (camera.width_px, camera.height_px)
        self.grid_px = output_grid_px(*self.size_px)
        self._rays_key = None
        self._rays = None

    def rays(self, state: CameraState) -> np.ndarray:
        """Undistorted normalised ray (H, W, 2) of each stream pixel."""
        K, distortion = stream_camera(state)
        key = (K.tobytes(), distortion)
        if key == self._rays_key:
            return self._rays
        if state.window_px is None and "optics.remap" in self.lens.stages:
            rays = self.lens.maps(state).undistorted_normalized  # the remap's own inverse
        else:
            undistorted = undistort_points(self.grid_px, K, distortion) if any(distortion) else self.grid_px
            homogeneous = np.concatenate([undistorted, np.ones((*undistorted.shape[:2], 1))], axis=-1)
            rays = (homogeneous @ np.linalg.inv(K).T)[..., :2]
        self._rays_key, self._rays = key, rays
        return rays

    def _poses(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Each moving node's pose and its mesh's vertices in the world, as the graph stands (the actors, then
        the swaying props: `SceneGraph.moving_nodes`)."""
        graph, poses = self.graph, []
        for node in graph.moving_nodes:
            pose = np.array(graph.scene.get_pose(node), dtype=np.float64)
            local = np.concatenate([np.asarray(p.positions, dtype=np.float64) for p in node.mesh.primitives])
            poses.append((pose, local @ pose[:3, :3].T + pose[:3, 3]))
        return poses

    @staticmethod
    def _faces(node) -> np.ndarray:
        """Triangles (F, 3) of a node's mesh over its primitives' concatenated vertices."""
        faces, offset = [], 0
        for primitive in node.mesh.primitives:
            count = len(primitive.positions)
            # Flat-shaded meshes are drawn unindexed: consecutive vertex triplets are the triangles.
            indices = np.arange(count) if primitive.indices is None else np.asarray(primitive.indices, dtype=np.int64)
            faces.append(indices.reshape(-1, 3) + offset)
            offset += count
        return np.concatenate(faces)

    def displacement_m(self, state: CameraState, next_time_s: float, passes: Passes) -> np.ndarray:
        """World displacement (H, W, 3) m of each stream pixel's surface point from the frame to
        `next_time_s`; NaN where no surface is seen. Leaves the graph's actors at `next_time_s`."""
        graph = self.graph
        graph.place_actors(state.time_s)
        now = self._poses()
        graph.place_actors(next_time_s)
        later = self._poses()
        depth, rays = passes.depth_m, self.rays(state)
        displacement = np.zeros((*depth.shape, 3))
        displacement[~np.isfinite(depth)] = np.nan
        T = np.array(state.T_world_from_cam)
        # Each moving node's pixels, found with one sort of the frame's pixels of moving nodes (not a pass each).
        moving = graph.moving_nodes
        actor_ids = np.array([graph.instance_ids[node] for node in moving], dtype=np.int64)
        ids = passes.instance_id.ravel().astype(np.int64)
        pixels = np.flatnonzero(np.isin(ids, actor_ids))
        pixels = pixels[np.argsort(ids[pixels], kind="stable")]
        starts = np.searchsorted(ids[pixels], actor_ids, side="left")
        ends = np.searchsorted(ids[pixels], actor_ids, side="right")
        flat_rays, flat_depth = rays.reshape(-1, 2), depth.ravel()
        flat_displacement = displacement.reshape(-1, 3)
        for k, node in enumerate(moving):
            seen = pixels[starts[k] : ends[k]]
            if len(seen) == 0:
                continue
            (pose, vertices), (pose_next, vertices_next) = now[k], later[k]
            points = surface_points_m(flat_rays[seen], flat_depth[seen], T)
            if not np.array_equal(pose, pose_next) or len(vertices) != len(vertices_next):
                flat_displacement[seen] = rigid_displacement_m(points, pose, pose_next)
            else:  # a mesh posed in the world (or at rest), or a swaying prop: its vertices carry the motion
                flat_displacement[seen] = mesh_displacement_m(
                    points, vertices, vertices_next, self._faces(node), long_triangles=k >= len(graph.actor_nodes)
                )
        return displacement

    def flow(self, state: CameraState, next_state: CameraState, passes: Passes) -> tuple[np.ndarray, np.ndarray]:
        """Forward flow (H, W, 2) float32 px and scene flow (H, W, 3) m from `state`'s frame to
        `next_state`'s. `passes`: the frame's stream passes (depth_m, instance_id)."""
        displacement = self.displacement_m(state, next_state.time_s, passes)
        K_next, distortion_next = stream_camera(next_state)
        flow = forward_flow_px(
            self.grid_px,
            self.rays(state),
            passes.depth_m,
            displacement,
            np.array(state.T_world_from_cam),
            np.array(next_state.T_world_from_cam),
            K_next,
            distortion_next,
        )
        return flow, displacement
