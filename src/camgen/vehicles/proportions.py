"""A car's side view measured from its built shell, and the ranges real cars of each body type span.

A car reads as a saloon, a hatchback or an MPV mostly by where its greenhouse stands over its wheels: a front-engined
car's bonnet reaches back to a cowl (the windscreen's foot) near or behind the front wheel's rear edge (the designers'
"dash-to-axle" distance: from the front axle to the windscreen's base in a side view, Hagerty, "Car Design
Fundamentals: Dash to axle ratio"), its windscreen is raked about 25-30 degrees from the horizontal, and its roof ends
where the body type says: over the rear wheels' axle on a saloon, whose rear window falls to a boot lid behind it, and
at the tail on a hatchback, estate or SUV, whose tailgate glass stands steeply over the rear bumper.

`side_stations` measures those stations from the shell (`camgen.vehicles.body.shell`) along its centreline, in metres
from the axles and ends that anchor them on real cars; `SIDE_STATION_RANGES` holds, per body type, the range of each
station spanned by that segment's representative models (the same models `camgen.vehicles.look.BODY_TYPES` takes its
dimensions from).

Sources and estimates:

- Overall dimensions (length, wheelbase, height) of the representative models, from makers' published figures as
  reported by the press at their launches: VW Golf 8 4,284 mm long, 1,456 mm high, wheelbase 2,636 mm (bvz.at,
  November 2019; motor1 Italy, May 2022); Toyota Corolla saloon 4.63 m, 1.43 m, 2.70 m (webmotors.com.br); Skoda
  Octavia Combi (4th generation) 4.69-4.70 m, wheelbase 2.68-2.69 m (ntz.de; red-live.it, which gives the Passat
  Variant's 2.79 m); Toyota RAV4 (5th generation) 4.60 m long, its wheelbase 30 mm longer than the 4th generation's
  2.66 m (businessday.ng, de.motor1.com; a 2012 Los Angeles show report on yo-mardeemociones.blogspot.com); Ford
  Ranger about 5.35 m long and 1.85 m high (aol.co.uk, 2011); and `camgen.vehicles.look`'s sources. A typical
  saloon's front and rear overhangs, 0.9 and 1.0 m of a 4.7 m car with a 2.8 m wheelbase (MathWorks, Automated
  Driving Toolbox, `vehicleDimensions`), are near the sedans' here (0.99-1.07 and 0.91-0.99 m, from
  `look.BODY_TYPES`' overhang share, unchanged here).
- The stations (`SIDE_STATION_RANGES`): no published table of cowl, header or roof-end positions was found (makers
  publish overall dimensions, overhangs and angles of approach, not greenhouse stations), nor of windscreen angles.
  The ranges are estimates from the named models' side views (not measured from drawings in this change), as
  distances from the anchors real cars keep across a segment: the cowl from the front axle (a transverse engine and
  its gearbox fill 0.35-0.7 m behind the axle's line on a front-wheel-drive hatchback, 0.45-0.85 m on a saloon or
  estate and more on a pickup's longitudinal engine), the windscreen's rake as its chord from the cowl to the header
  (25-30 degrees from the horizontal on saloons and hatchbacks, the figure of camgen's realism review, a few degrees
  steeper on SUVs and pickups, 10-15 steeper on vans), a saloon's roof end and rear window base from the rear axle,
  a hatchback's, estate's or SUV's roof end and tailgate glass base from the vehicle's tail. They are wide enough for
  the segment (a Fiat 500 to a Golf), and narrow enough to fail the earlier profiles, whose greenhouses stood
  0.3-0.6 m too far forward with windscreens raked 35-48 degrees (cars) and 54-58 degrees (vans, whose windscreens
  then started 0.44-0.66 m ahead of their front axles).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from camgen.vehicles.look import VehicleLook

CENTRE_BAND_M = 0.25
"""The glass faces whose centres lie within this distance of the centreline are those measured, m (a windscreen is
curved in plan: its edge at the pillars lies further back than at the middle)."""
SCREEN_NORMAL_X = 0.3
"""A glass face belongs to the windscreen (rear window) where its outward normal points this much forward (back)."""


@dataclass(frozen=True)
class SideStations:
    """Where a vehicle's side-view stations are, m (x along the vehicle from the anchor each name gives: positive
    behind a front axle or ahead of a rear axle or tail; z over the road) and its screens' rakes, degrees from the
    horizontal. The rear ones are None on a vehicle without a rear window facing back and up (a van's glazed doors)."""

    cowl_behind_front_axle_m: float
    """The windscreen's foot (its lowest glass at the centreline): the designers' dash-to-axle distance."""
    cowl_z_m: float
    screen_top_behind_front_axle_m: float
    """The windscreen's top (the roof's front, the header)."""
    screen_top_z_m: float
    screen_rake_deg: float
    """The windscreen's chord from its foot to its top, from the horizontal."""
    bonnet_z_at_front_axle_m: float
    """The bonnet's height over the front axle (the profile's top line there)."""
    belt_z_m: float
    """The beltline: the side windows' lower edge."""
    roof_end_ahead_of_rear_axle_m: float | None
    """The roof's rear end (the rear window's top) ahead of the rear axle (negative behind it)."""
    roof_end_ahead_of_tail_m: float | None
    """The same station ahead of the vehicle's rear end."""
    rear_glass_base_ahead_of_rear_axle_m: float | None
    """The rear window's foot (a saloon's boot lid starts there; a tailgate's glass ends there)."""
    rear_glass_base_ahead_of_tail_m: float | None
    rear_glass_rake_deg: float | None
    """The rear window's chord from its foot to its top, from the horizontal."""


def side_stations(look: VehicleLook) -> SideStations:
    """The side-view stations of the vehicle of `look`, measured from its shell's glass along its centreline."""
    from camgen.vehicles.body import PROFILES, _interp_top, shell

    vertices, faces, _, kind = shell(look)
    corners = vertices[faces]
    centre = corners.mean(axis=1)
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    middle = (kind == 1) & (np.abs(centre[:, 1]) < CENTRE_BAND_M)
    front_x, rear_x, tail_x = look.front_axle_x_m, look.rear_axle_x_m, -look.length_m / 2

    def ends(chosen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(the foremost, the rearmost) corner of the chosen faces: (x, z)."""
        points = corners[chosen].reshape(-1, 3)
        return points[np.argmax(points[:, 0])][[0, 2]], points[np.argmin(points[:, 0])][[0, 2]]

    screen = middle & (normal[:, 0] > SCREEN_NORMAL_X) & (centre[:, 0] > rear_x)
    if not screen.any():
        raise ValueError(f"a {look.body_type} has no sloped windscreen to measure")
    foot, top = ends(screen)
    rake = np.degrees(np.arctan2(top[1] - foot[1], foot[0] - top[0]))
    profile = PROFILES[look.body_type]
    bonnet = float(_interp_top(profile, np.array([front_x / look.length_m + 0.5]))[0]) * look.height_m
    rear = middle & (normal[:, 0] < -SCREEN_NORMAL_X) & (normal[:, 2] > 0.05) & (centre[:, 0] < front_x)
    roof_end = base = rear_rake = None
    if rear.any():
        upper, lower = ends(rear)
        roof_end, base = upper[0], lower[0]
        rear_rake = float(np.degrees(np.arctan2(upper[1] - lower[1], upper[0] - lower[0])))
    return SideStations(
        cowl_behind_front_axle_m=float(front_x - foot[0]),
        cowl_z_m=float(foot[1]),
        screen_top_behind_front_axle_m=float(front_x - top[0]),
        screen_top_z_m=float(top[1]),
        screen_rake_deg=float(rake),
        bonnet_z_at_front_axle_m=bonnet,
        belt_z_m=profile.belt * look.height_m,
        roof_end_ahead_of_rear_axle_m=None if roof_end is None else float(roof_end - rear_x),
        roof_end_ahead_of_tail_m=None if roof_end is None else float(roof_end - tail_x),
        rear_glass_base_ahead_of_rear_axle_m=None if base is None else float(base - rear_x),
        rear_glass_base_ahead_of_tail_m=None if base is None else float(base - tail_x),
        rear_glass_rake_deg=rear_rake,
    )


SIDE_STATION_RANGES: dict[str, dict[str, tuple[float, float]]] = {
    "hatchback": {
        "cowl_behind_front_axle_m": (0.35, 0.70),
        "screen_top_behind_front_axle_m": (1.05, 1.55),
        "screen_rake_deg": (24.0, 32.0),
        "bonnet_z_at_front_axle_m": (0.78, 0.95),
        "belt_z_m": (0.88, 1.02),
        "roof_end_ahead_of_tail_m": (0.10, 0.40),
        "rear_glass_base_ahead_of_tail_m": (0.0, 0.30),
        "rear_glass_rake_deg": (40.0, 65.0),
    },
    "sedan": {
        "cowl_behind_front_axle_m": (0.45, 0.85),
        "screen_top_behind_front_axle_m": (1.30, 1.80),
        "screen_rake_deg": (22.0, 30.0),
        "bonnet_z_at_front_axle_m": (0.80, 0.95),
        "belt_z_m": (0.88, 1.02),
        "roof_end_ahead_of_rear_axle_m": (0.15, 0.65),
        "rear_glass_base_ahead_of_rear_axle_m": (-0.40, 0.10),
        "rear_glass_rake_deg": (18.0, 32.0),
    },
    "estate": {
        "cowl_behind_front_axle_m": (0.45, 0.85),
        "screen_top_behind_front_axle_m": (1.30, 1.80),
        "screen_rake_deg": (23.0, 31.0),
        "bonnet_z_at_front_axle_m": (0.80, 0.95),
        "belt_z_m": (0.88, 1.02),
        "roof_end_ahead_of_tail_m": (0.05, 0.35),
        "rear_glass_base_ahead_of_tail_m": (0.0, 0.25),
        "rear_glass_rake_deg": (50.0, 80.0),
    },
    "suv": {
        "cowl_behind_front_axle_m": (0.40, 0.85),
        "screen_top_behind_front_axle_m": (1.10, 1.70),
        "screen_rake_deg": (26.0, 36.0),
        "bonnet_z_at_front_axle_m": (0.92, 1.18),
        "belt_z_m": (0.98, 1.18),
        "roof_end_ahead_of_tail_m": (0.10, 0.40),
        "rear_glass_base_ahead_of_tail_m": (0.0, 0.30),
        "rear_glass_rake_deg": (50.0, 80.0),
    },
    "pickup": {
        "cowl_behind_front_axle_m": (0.60, 1.00),
        "screen_top_behind_front_axle_m": (1.35, 1.90),
        "screen_rake_deg": (27.0, 36.0),
        "bonnet_z_at_front_axle_m": (1.10, 1.32),
        "belt_z_m": (1.10, 1.25),
        "roof_end_ahead_of_rear_axle_m": (0.30, 0.70),
        "rear_glass_rake_deg": (70.0, 90.0),
    },
    "van": {
        "cowl_behind_front_axle_m": (-0.15, 0.40),
        "screen_top_behind_front_axle_m": (0.70, 1.55),
        "screen_rake_deg": (30.0, 45.0),
        "bonnet_z_at_front_axle_m": (0.95, 1.35),
    },
}
"""Per body type, station name (`SideStations`) → (low, high), m or degrees: the range the segment's representative
models span (the module's sources: estimates from their side views). Hatchback: Fiat 500, VW Polo, VW Golf 8,
Ford Focus. Sedan: Toyota Corolla saloon, VW Passat saloon, Toyota Camry. Estate: Skoda Octavia Combi, VW Passat
Variant. SUV: Peugeot 2008, VW Tiguan, Toyota RAV4, BMW X5. Pickup: Toyota Hilux and Ford Ranger double cabs (the cab's
back, its upright rear window, 0.3-0.7 m ahead of the rear axle, where a 1.5-1.6 m load bed ahead of the tail starts).
Van: Ford Transit Custom, VW Transporter T6.1, Mercedes Sprinter (a short bonnet: the windscreen's foot near the
front axle's line, raked more steeply than a car's)."""
