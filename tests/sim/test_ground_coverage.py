"""camgen.sim.ground_coverage: the network's ground coverage per frame, checked against camgen.coverage's
own home views (an independent path: the profile's K and the mount, not the simulation's state), and
a turning head moving its share."""

from __future__ import annotations

import numpy as np
import pytest

from camgen.config import load_scene
from camgen.coverage.network import camera_coverage
from camgen.coverage.views import home_view
from camgen.sim import ContinuousMove, Observations, Simulation
from camgen.sim.ground_coverage import GroundCoverage
from tests.sim.scenes import write_world

pytestmark = pytest.mark.opengl


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    return write_world(tmp_path_factory.mktemp("coverage_world"), duration_s=0.8)


def test_frame_zero_covers_what_the_home_views_cover(world, renderer):
    loaded = load_scene(world)
    tracker = GroundCoverage(loaded, cell_m=0.5)
    with Simulation(loaded, renderer=renderer) as sim:
        observed = sim.reset(0)
    expected = np.zeros(tracker.grid.shape, bool)
    for camera in loaded.scene.cameras:
        alone = Observations(0, 0.0, {camera.name: observed[camera.name]})
        home = camera_coverage(tracker.grid, home_view(camera, loaded.profile_models[camera.name]), tracker.occluders)
        reference = (home.dori >= 1) & tracker.site
        assert reference.sum() > 20
        assert np.array_equal(tracker.covered(alone), reference), camera.name
        expected |= reference
    assert tracker.add(observed) == pytest.approx(expected.sum() * 0.25)


def test_a_turning_head_moves_its_share(world, renderer):
    loaded = load_scene(world)
    tracker = GroundCoverage(loaded, cell_m=0.5)
    with Simulation(loaded, renderer=renderer, cameras=["dome"]) as sim:
        tracker.add(sim.reset(0))
        for _ in range(7):
            tracker.add(sim.step({"dome": ContinuousMove(pan=1.0)}))
    first, last = tracker.per_frame_m2[0], tracker.per_frame_m2[-1]
    assert first > 0 and last > 0
    # The head turned tens of degrees: the union of the frames is larger than any one of them.
    assert tracker.union_m2 > 1.3 * max(tracker.per_frame_m2)
    assert tracker.union_m2 <= tracker.site_m2
