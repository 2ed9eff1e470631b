"""Per-frame camera states as a long sequence's plan builds them: the frames of one view share their
lens and pose (copies of the view's first state), so the states must be exactly what validation makes,
frame by frame, and survive the job file's round trip with the same content hash."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.job import CameraState, Job
from camgen.plan import compile_scene
from camgen.plan.camera_state import camera_state, lens_state
from tests.conftest import REPO


@pytest.fixture(scope="module", params=["ptz_follow", "eptz_follow"])
def job(request) -> Job:
    return compile_scene(load_scene(REPO / f"scenes/{request.param}.yaml"))


def test_every_state_is_what_validation_makes(job: Job):
    for camera in job.cameras:
        for state in camera.states:
            assert CameraState.model_validate(state.model_dump()) == state
            assert type(state.frame) is int and type(state.time_s) is float
            assert all(type(x) is float for row in state.T_world_from_cam for x in row)


def test_states_equal_camera_state_built_from_their_own_values(job: Job):
    """Every 7th frame's state against `camera_state` (the sim's path) given the frame's head, lens
    and pose: the copies carry no field of another frame."""
    for camera in job.cameras:
        apply = any(d.stage == "optics.distortion" and d.included for d in camera.decisions)
        virtual = camera.output_size_px is not None
        for state in camera.states[::7]:
            rebuilt = camera_state(
                frame=state.frame,
                time_s=state.time_s,
                pan_deg=state.pan_deg,
                tilt_deg=state.tilt_deg,
                zoom_x=state.zoom_x,
                lens=lens_state(camera.profile, state.focal_length_mm),
                T_world_from_cam_=np.array(state.T_world_from_cam),
                focus_distance_m=state.focus_distance_m,
                exposure_time_s=state.exposure_time_s,
                gain_db=state.gain_db,
                apply_distortion=apply,
                eptz_sizes_px=((camera.width_px, camera.height_px), camera.output_size_px) if virtual else None,
                pan_deg_s=state.pan_deg_s,
                tilt_deg_s=state.tilt_deg_s,
                log_zoom_per_s=state.log_zoom_per_s,
                ptz_mode=state.ptz_mode,
                follow_target=state.follow_target,
            )
            assert rebuilt.model_copy(update={"night_mode": state.night_mode}) == state


def test_frames_differ_where_the_head_moves_and_share_their_view(job: Job):
    for camera in job.cameras:
        states = camera.states
        assert [s.frame for s in states] == list(range(job.frame_count))
        assert np.all(np.diff([s.time_s for s in states]) > 0)
        views = {(s.pan_deg, s.tilt_deg, s.focal_length_mm) for s in states}
        if job.scene_name == "ptz_follow":
            assert len(views) > 10  # the head follows the walker
        if camera.output_size_px is not None:
            continue  # a virtual PTZ's window moves within a view: each state is built whole
        # One pose object per view, shared by its frames (a long sequence's memory), whatever the frame count.
        poses = {id(s.T_world_from_cam) for s in states}
        assert len(poses) <= len(views)
        if job.scene_name != "ptz_follow":
            assert len(poses) == 1


def test_the_job_file_round_trip_keeps_states_and_hash(job: Job):
    again = Job.from_json(job.to_json())
    assert again == job
    assert again.content_hash() == job.job_id
