"""Side-view proportions (`camgen.vehicles.proportions`): each car body type's and the van's greenhouse stations,
measured from the built shell, lie in the ranges their segment's real models span, over many identity seeds.

The earlier profiles failed these: their cowls stood 0.10-0.33 m behind the front axle (a saloon's 0.1 m: an MPV's
short nose), windscreens were raked 35-48 degrees (cars) and 54-58 degrees (vans, whose windscreens began 0.44-0.66 m
ahead of the front axle, over a roof-high nose), and a saloon's roof ended 0.9 m ahead of its rear axle.
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np
import pytest

from camgen.vehicles.look import draw_look
from camgen.vehicles.proportions import SIDE_STATION_RANGES, side_stations

CLASS_OF = {"van": "truck"}
SEEDS = range(100)


@pytest.mark.parametrize("body", sorted(SIDE_STATION_RANGES))
def test_side_stations_lie_in_the_segments_ranges(body):
    ranges = SIDE_STATION_RANGES[body]
    measured = {key: [] for key in ranges}
    for seed in SEEDS:
        stations = asdict(side_stations(draw_look(seed, CLASS_OF.get(body, "car"), pinned={"body_type": body})))
        for key in ranges:
            assert stations[key] is not None, (body, seed, key)
            measured[key].append(stations[key])
    for key, (low, high) in ranges.items():
        values = np.array(measured[key])
        assert low <= values.min() and values.max() <= high, (body, key, values.min(), values.max(), (low, high))


def test_a_saloons_roof_ends_over_its_rear_axle_and_a_hatchbacks_at_its_tail():
    """The body types differ where real ones do: a saloon's rear window falls to a boot lid about its rear axle, a
    hatchback's tailgate glass stands at its tail; a pickup's cab ends ahead of its load bed over the rear axle."""
    sedan = side_stations(draw_look(5, "car", pinned={"body_type": "sedan"}))
    hatchback = side_stations(draw_look(5, "car", pinned={"body_type": "hatchback"}))
    pickup = side_stations(draw_look(5, "car", pinned={"body_type": "pickup"}))
    assert sedan.roof_end_ahead_of_tail_m > 1.0 and abs(sedan.rear_glass_base_ahead_of_rear_axle_m) < 0.5
    assert hatchback.roof_end_ahead_of_tail_m < 0.4 and hatchback.rear_glass_rake_deg > 2 * sedan.rear_glass_rake_deg
    assert pickup.rear_glass_rake_deg > 70 and pickup.roof_end_ahead_of_tail_m > 1.3


def test_stations_follow_the_shell_not_the_profile_alone():
    """The measurement reads the built glass: a windscreen's foot lies on the bonnet's line (its z the top line's
    there), its top on the roof, and the rake is the chord between them."""
    look = draw_look(3, "car", pinned={"body_type": "sedan"})
    s = side_stations(look)
    assert s.cowl_z_m < s.screen_top_z_m <= look.height_m
    run = s.screen_top_behind_front_axle_m - s.cowl_behind_front_axle_m
    assert np.degrees(np.arctan2(s.screen_top_z_m - s.cowl_z_m, run)) == pytest.approx(s.screen_rake_deg)
    assert s.belt_z_m < s.screen_top_z_m


def test_a_vehicle_without_a_sloped_windscreen_is_refused_with_a_reason():
    with pytest.raises(ValueError, match="windscreen"):
        side_stations(draw_look(1, "bus", pinned={"body_type": "bus"}))


@pytest.mark.parametrize(("body", "cls"), [("sedan", "car"), ("hatchback", "car"), ("pickup", "car"), ("van", "truck")])
def test_the_whole_windscreen_has_the_windscreens_transmittance(body, cls):
    """A windscreen raked as a real one reaches back past the vehicle's middle on a saloon: every outer glass face
    facing forward (the windscreen's) lets WINDSCREEN_T through, not the side windows' (their glass never faces
    forward that much)."""
    from camgen.vehicles.body import build_vehicle
    from camgen.vehicles.cabin import WINDSCREEN_T

    look = draw_look(2, cls, pinned={"body_type": body})
    glass = next(part for part in build_vehicle(look).parts if part.name == "body_glass")
    centre = glass.vertices_m[glass.faces].mean(axis=1)
    forward = glass.normals[glass.faces].mean(axis=1)[:, 0] > 0.35
    transmittance = 1.0 - glass.colours[glass.faces[:, 0], 3]
    assert forward.sum() > 50
    assert np.allclose(transmittance[forward], WINDSCREEN_T), (
        body,
        centre[forward][~np.isclose(transmittance[forward], WINDSCREEN_T)][:3],
    )
    if body == "sedan":
        assert centre[forward, 0].min() < 0.0  # the raked screen's top lies behind the middle
