"""A vehicle's shapes: a lofted body shell with glass, wheels, lamps and plates, in the vehicle's frame.

The vehicle's frame: x forward, y left, z up, origin on the ground at the middle of its footprint.

The shell is a loft: a side profile per body type (the roof line from the rear, u = 0, to the front, u = 1, as
heights over the vehicle's height; `PROFILES`) sampled at stations along the length, each station a closed
cross-section — a superellipse (exponent `SECTION_EXPONENT`: a rounded box, so shoulders and sills are
rounded; a van's or box truck's a flat-sided box with a rounded bottom edge, `Profile.sill_radius_m`) under the
beltline and, over it, the greenhouse: a squarer arc (`GREENHOUSE_EXPONENT`) whose sides
rise from the belt and lean in (the tumblehome) and round into the roof, its rows of points split between the
sides and the roof alike at every station (`GREENHOUSE_SIDE_QUADS`, `ROOF_EDGE_ROW_M`), so that the side glass
reaches up to the roof's rails and a windscreen spans the roof's width between thin pillars. In plan the ends
are rounded at the four corners. The underside follows the ground clearance and rises in an arch over each
wheel. Both ends are closed by ladder-triangulated caps, so the shell is one closed, consistently wound
surface (watertight). Its faces are split by position and normal into paint and glass (side windows between
the pillars, windscreen, rear window; a bus's and a van's glazed ends), one primitive each, sharing the
shell's vertices: together they stay watertight. Each window of the tube is then redrawn as whole rows of
section points over its stations (`_window_rows`), so that its outline runs along the mesh's rows and
stations, as the beltline does, instead of stepping between rows from one station to the next.

Wheels are a tyre (a closed cylinder, `WHEEL_SECTIONS` sides) and a rim (hub, five spokes and the rim's
outer ring at the rim's diameter, `RIM_SHARE`, standing proud of the tyre's sidewall, so that a turning
wheel shows it) in the wheel's own frame (axle along y); a bus rolls on steel disc wheels instead (a disc
with hand holes and a hub of ten nuts, `steel_disc_wheel_meshes`) and shows its route on an LED
destination display over the windscreen (`destination_sign`, `camgen.vehicles.sign`) and carries its
air-conditioning unit on the roof (`roof_unit`). Lamps are thin boxes half sunk into the shell's ends, in lamp
units at the corners (`_lamp_housings`: a clear headlamp unit reaching back over the nose, a red rear cluster with
a clear reversing lamp; a van's upright on its rear pillars); plates are quads 5 mm in front of them. A van's rear
overhang clears its departure angle (`Profile.departure_angle_deg`) under a black plastic rear bumper with a step; a
box truck's load floor is raised from its cab's back (`Profile.rear_floor_m`) over its wheels, side guards
(`_side_guards`) and an underrun guard (`_underrun_guard`). Exterior mirrors (`door_mirrors`) stand out of
the outline at the front side windows' lower corners (a bus's on arms ahead of its front). What a car shows from
above over the shell (`camgen.vehicles.roof`): a glass roof (the shell's own roof quads as glass, `_glass_roof`),
roof rails, a shark-fin antenna, the cowl and wipers at the windscreen's foot and the bonnet's shut lines.

Underneath: the shell's faces that face the ground are the underbody (`UNDERBODY_RGB`: underseal and
plastic undertrays, not the paint), and the ground under the whole footprint, which sees the sky only
through the gaps under the sills and bumpers, is drawn dark (`ground_shade`): a uniform ambient term would
otherwise light the ground under a car as brightly as the open road, and a car under an overcast sky, or
seen from behind, would stand on no shadow at all.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
import trimesh

from camgen.vehicles.look import VehicleLook
from camgen.vehicles.plate import PLATE_SIZE_M, UK_PLATE_PATTERN

UPPER_POINTS = 15
LOWER_POINTS = 15
"""Points of each cross-section above and below its beltline (odd: see `_sections`)."""
SECTION_EXPONENT = 5.0
"""Superellipse exponent of the cross-section: 2 an ellipse, large a sharp box; 5 gives shoulders
rounded over about a fifth of the half-width."""
ARCH_EXPONENT_GAIN = 8.0
"""The most a section's exponent grows over a wheel arch (`shell`): a cap, not a setting: the squashed section over
a wheel of every body type here is at most about 3.7 times shallower than it would be without the arch, so it does
not bind today; it keeps an unforeseen, nearly flat section from an exponent that rounds to a box."""
STATION_SPACING_M = 0.08
WHEEL_SECTIONS = 32
"""Sides of a tyre's cylinder: at 32 a 0.63 m tyre's outline departs from a circle by 1.5 mm."""
ARCH_GAP_M = 0.04
"""Clearance between a tyre and its wheel arch, m."""
TYRE_WIDTH_SHARE = 0.115
"""Tyre section over the vehicle's width (205 mm of a 1.8 m car; 275 mm of a 2.55 m bus)."""
RIM_SHARE = {
    "hatchback": 381.0 / 621.5,
    "sedan": 406.4 / 631.9,
    "estate": 406.4 / 631.9,
    "suv": 431.8 / 724.3,
    "pickup": 431.8 / 776.3,
    "van": 406.4 / 685.9,
    "box_truck": 444.5 / 767.0,
    "bus": 571.5 / 956.5,
}
"""The rim's diameter over the tyre's outer diameter for each body type's tyre (`camgen.vehicles.look`:
ETRTO designations, outer diameter = rim × 25.4 mm + 2 × section × aspect): 185/65 R15 381 of 621.5 mm,
205/55 R16 406.4 of 631.9, 225/65 R17 431.8 of 724.3, 265/65 R17 431.8 of 776.3, 215/65 R16C 406.4 of
685.9, 215/75 R17.5 444.5 of 767, 275/70 R22.5 571.5 of 956.5: the rim fills 0.56–0.64 of the wheel."""
RIM_LIP_SHARE = 0.08
"""Radial width of the rim's visible outer ring (flange and lip, about 25 mm on a 16-inch rim), as a
share of the tyre's radius."""


@dataclass(frozen=True)
class Profile:
    """A body type's side view and where its glass is, as shares of length (u, rear 0 → front 1) and
    height (z over the vehicle's height)."""

    top: tuple[tuple[float, float], ...]
    """(u, z) of the roof line from the rear to the front."""
    belt: float
    """Beltline: the lower edge of the side windows."""
    side_glass: tuple[float, float]
    pillars: tuple[tuple[float, float], ...] = ()
    """u-bands of paint that interrupt the side glass (B, C pillars)."""
    windscreen: tuple[float, float] = (0.0, 0.0)
    rear_window: tuple[float, float] = (0.0, 0.0)
    doors: tuple[tuple[float, float], ...] = ()
    """u-bands of glazed doors on the nearside (the kerb's side: `nearside_sign`), glass from
    `door_glass_bottom` up to the side windows' top, whatever the beltline and pillars."""
    door_glass_bottom: float = 0.2
    front_cap_glass: tuple[float, float] | None = None
    """z-band of the front end that is glass (a bus's or a truck cab's upright windscreen)."""
    rear_cap_glass: tuple[float, float] | None = None
    clearance_m: float = 0.15
    """Height of the sill above the ground, m (cars 0.13–0.2 m)."""
    end_lift: float = 0.18
    """Height of the bumpers' lower edge at both ends, as a share of the vehicle's height."""
    tumblehome: float = 0.22
    """How much narrower the roof is than the body at the beltline, as a share of the width: a car's roof
    over its rails is about 0.7 of its width (a Golf 8's about 1.25 m of 1.79 m; side glass leaning in about
    20–25° from the vertical), so 0.22 with the roof's rounded edges (`GREENHOUSE_EXPONENT`); a van's sides
    are near upright, a bus's and a box truck's upright."""
    corner_share: float = 0.06
    """Length of the rounded corners in plan, as a share of the length."""
    end_width: float = 0.78
    """Width of the flat end faces, as a share of the width."""
    section_exponent: float = SECTION_EXPONENT
    """Superellipse exponent of the body under the belt: a car's rounded sides and sills, a bus's or a box body's
    flat sides coming straight down to a skirt (10: corners rounded over about a tenth of the half-width)."""
    sill_radius_m: float | None = None
    """With a radius, the body under the belt is a flat-sided box instead of a superellipse: upright flat sides
    down to a rounded bottom edge of this radius, m (`_rounded_lower_arc`). Over a wheel the edge is the arch's
    lip, the same radius at every station, so the side's paint ends on a round cut-out a fixed height over the
    arch, as a van's or a truck's pressed steel side does round its wheel. A van's 0.08 m and a box truck's 0.05 m
    are estimates from makers' side and rear views (a Transit's or Sprinter's side panel rolls under over a few
    centimetres above its sill; a box body's panels and its cab's meet their skirts at a nearly sharp edge)."""
    departure_angle_deg: float | None = None
    """With an angle, the underside behind the rear axle stays over the departure line: the line at this angle to
    the road that touches the rear tyres (`departure_line_m`), so the rear bumper's lower edge is as high as the
    maker's departure angle and rear overhang put it (`end_lift` then sets the front end alone where the line is
    higher)."""
    rear_floor_m: float | None = None
    """With a height, m, the underside from `floor_start_u` back is a load floor this high over the road: a box
    truck's body sits on its chassis frame behind its cab, and under it the road shows between the wheels, past the
    side guards (`_side_guards`) and under the rear overhang past the underrun guard (`UNDERRUN_GUARD_BODIES`), not a
    skirt down to the sills."""
    floor_start_u: float = 0.0
    """Where the load floor (`rear_floor_m`) starts, as a share of the length (rear 0 → front 1): the box body's
    front, over the cab's back."""


VAN_DEPARTURE_ANGLE_DEG = 20.0
"""A panel van's departure angle, unladen: makers' dimension sheets put large vans' at about 18-23 deg (Ford
Transit 2014- van, Mercedes Sprinter 907, VW Crafter 2017; figures recalled from the sheets, not rechecked in this
change: an estimate). With the vans' rear overhangs here (0.95-1.13 m, half of `look.BODY_TYPES`' overhangs; a
Sprinter L2's 1.27 m) it puts the rear bumper's lower edge 0.32-0.39 m over the road (`departure_line_m`), where a
Transit's or Sprinter's black rear bumper ends, 0.35-0.45 m up in makers' rear views: seen from behind, the rear
tyres show under it. The earlier `end_lift` alone put it 0.20-0.27 m up, a departure angle of about 11-14 deg."""

BOX_FLOOR_M = 1.05
"""Height of a box truck's load floor over the road, m: a 7.5 t rigid's box body stands on its chassis frame (about
0.85-0.9 m up) and a subframe, its floor 1.0-1.2 m up, as high as a tail lift's platform rises (bodybuilders' data
for MAN TGL and Iveco Eurocargo box bodies; an estimate)."""
FLOOR_STEP_M = 0.01
"""The step up to a load floor (`Profile.rear_floor_m`) at the cab's back, m: one station from the cab's underside to
the floor's."""

PROFILES: dict[str, Profile] = {
    "sedan": Profile(
        top=((0, 0.50), (0.02, 0.64), (0.06, 0.70), (0.13, 0.72), (0.28, 0.96), (0.31, 1.0), (0.45, 1.0),
             (0.486, 0.95), (0.654, 0.68), (0.97, 0.55), (1, 0.46)),
        belt=0.66, side_glass=(0.25, 0.645), pillars=((0.425, 0.455),), windscreen=(0.465, 0.675),
        rear_window=(0.12, 0.30),
    ),
    "hatchback": Profile(
        top=((0, 0.52), (0.02, 0.70), (0.055, 0.92), (0.10, 1.0), (0.42, 1.0), (0.463, 0.95), (0.663, 0.665),
             (0.97, 0.53), (1, 0.44)),
        belt=0.64, side_glass=(0.055, 0.655), pillars=((0.055, 0.15), (0.385, 0.415)), windscreen=(0.44, 0.685),
        rear_window=(0.015, 0.075),
    ),
    "estate": Profile(
        top=((0, 0.52), (0.015, 0.70), (0.03, 0.93), (0.06, 1.0), (0.45, 1.0), (0.488, 0.95), (0.66, 0.665),
             (0.97, 0.55), (1, 0.46)),
        belt=0.64, side_glass=(0.03, 0.65), pillars=((0.03, 0.07), (0.25, 0.28), (0.43, 0.46)),
        windscreen=(0.465, 0.685), rear_window=(0.01, 0.05),
    ),
    "suv": Profile(
        top=((0, 0.52), (0.015, 0.70), (0.035, 0.94), (0.07, 1.0), (0.475, 1.0), (0.514, 0.95), (0.66, 0.69),
             (0.97, 0.60), (1, 0.50)),
        belt=0.66, side_glass=(0.035, 0.66), pillars=((0.035, 0.11), (0.435, 0.465)), windscreen=(0.49, 0.69),
        rear_window=(0.01, 0.06), clearance_m=0.19,
    ),
    "pickup": Profile(
        top=((0, 0.56), (0.02, 0.58), (0.29, 0.58), (0.305, 0.96), (0.32, 1.0), (0.50, 1.0), (0.529, 0.95),
             (0.672, 0.70), (0.97, 0.62), (1, 0.52)),
        belt=0.64, side_glass=(0.32, 0.662), pillars=((0.45, 0.48),), windscreen=(0.515, 0.69),
        rear_window=(0.29, 0.315), clearance_m=0.22,
    ),
    "van": Profile(
        top=((0, 0.96), (0.015, 1.0), (0.55, 1.0), (0.587, 0.93), (0.79, 0.49), (0.97, 0.44), (1, 0.39)),
        belt=0.52, side_glass=(0.55, 0.785), windscreen=(0.56, 0.80), rear_cap_glass=(0.62, 0.90),
        clearance_m=0.18, end_lift=0.10, tumblehome=0.05, corner_share=0.03, end_width=0.85, sill_radius_m=0.08,
        departure_angle_deg=VAN_DEPARTURE_ANGLE_DEG,
    ),
    "box_truck": Profile(
        top=((0, 0.99), (0.005, 1.0), (0.76, 1.0), (0.765, 0.80), (0.80, 0.81), (0.95, 0.80), (0.985, 0.74),
             (1, 0.40)),
        belt=0.44, side_glass=(0.86, 0.975), windscreen=(0.955, 1.0), clearance_m=0.45, end_lift=0.12,
        tumblehome=0.0, corner_share=0.01, end_width=0.92, section_exponent=10.0, sill_radius_m=0.05,
        rear_floor_m=BOX_FLOOR_M, floor_start_u=0.76,
    ),
    "bus": Profile(
        top=((0, 0.885), (0.01, 0.92), (0.02, 0.935), (0.98, 0.935), (0.99, 0.92), (1, 0.895)),
        belt=0.43, side_glass=(0.025, 0.975), pillars=tuple((0.025 + 0.105 * k, 0.037 + 0.105 * k) for k in range(10)),
        doors=((0.47, 0.58), (0.87, 0.985)), door_glass_bottom=0.2,
        front_cap_glass=(0.33, 0.77), rear_cap_glass=(0.55, 0.85), clearance_m=0.30, end_lift=0.10,
        tumblehome=0.02, corner_share=0.012, end_width=0.90, section_exponent=10.0,
    ),
}  # fmt: skip
"""The cars' and the van's side views put their greenhouses where real ones stand over the wheels: the windscreen's foot
(the cowl, where the bonnet ends) 0.48-0.67 m behind the front axle on cars (0.75-0.82 m on the pickup's long bonnet,
0.15-0.28 m on the van's short one), windscreens raked 25-32 degrees from the horizontal (the van's 40-45), a
saloon's roof ending 0.42-0.51 m ahead of its rear axle over a rear window raked 25 degrees down to a boot lid, a
hatchback's, estate's and SUV's 0.24-0.33 m from the tail over a steep tailgate glass, a double-cab pickup's cab
ending 0.48-0.54 m ahead of its rear axle: each station within the range its segment's real models span, for every
seed (`camgen.vehicles.proportions`, which measures them from the shell and cites the models;
tests/vehicles/test_proportions.py). The knots are shares of the length: with the overhangs a fixed share of what the
wheelbase leaves (`camgen.vehicles.look.BODY_TYPES`), a station's distance from the front axle varies by a few
centimetres over a segment's sizes. The van's profile scales with its height, so a high-roofed van (2.69 m, a
Sprinter L2H2) has a taller cab and windscreen than its maker's, whose high roof rises over a cab of the low-roofed
van's height.

The bus is a two-door low-floor city bus after Mercedes-Benz's "The Citaro: Technical Information"
(Citaro 628.083, 2 doors): 11,950 mm long, 3,076 mm high with its air conditioning, floor 370 mm above
the road and the waistline (the side windows' lower edge) 950 mm above the floor, so the beltline is
1,320 mm up, 0.43 of the height; front overhang 2,705 mm with door 1 (1,250 mm clear) in it ahead of
the front wheel, door 2 between the axles (here centred on the wheelbase, an estimate), both glazed
leaves on the nearside. The roof is 0.2 m under the height, which the air-conditioning unit on it reaches
(`roof_unit`). The windscreen's glass ends at 0.77 of the height, under the destination display
(`destination_sign`) that fills the top of a city bus's front."""


@dataclass
class Part:
    """One primitive of a vehicle: triangles in the vehicle's frame, or, for a wheel part, in the
    frame of the wheel each vertex belongs to (`wheel`: 0 front left, 1 front right, 2 rear left,
    3 rear right; −1 the body)."""

    name: str
    surface: str
    """Which material draws it: paint, glass (its opacity per vertex), gear (tyres, rims and plate
    backings, coloured per vertex), cabin (the interior lining and the driver, coloured per vertex),
    plates (the front plate's image over the rear's), head, tail, brake, indicator_left,
    indicator_right, cycle_head, cycle_tail, destination (a bus's lit LED dots), shade (the shaded
    ground under the vehicle, coloured per vertex, background in the instance pass)."""
    vertices_m: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    wheel: np.ndarray
    texcoords: np.ndarray | None = None
    colours: np.ndarray | None = None
    """(V, 3) linear albedo per vertex (the gear's rubber, alloy and black plastic), or (V, 4) with the
    opacity 1 − transmittance (glass)."""


@dataclass
class VehicleModel:
    """Everything drawn of one vehicle, at rest, and where its wheels and plates are."""

    look: VehicleLook
    parts: list[Part]
    wheel_centres_m: np.ndarray
    """(4, 3) wheel centres in the vehicle's frame: front left, front right, rear left, rear right."""
    plate_corners_m: dict[str, np.ndarray] = field(default_factory=dict)
    """"front" / "rear" → (4, 3) corners of the plate in the vehicle's frame, in the plate image's
    order: top left, top right, bottom right, bottom left (as one reads the plate)."""

    @property
    def appearance(self) -> VehicleLook:
        """The look (named like a person model's appearance, whose `attributes()` the annotations read)."""
        return self.look


def _interp_top(profile: Profile, u: np.ndarray) -> np.ndarray:
    points = np.array(profile.top, dtype=np.float64)
    return np.interp(u, points[:, 0], points[:, 1])


def _stations(look: VehicleLook, axles_x: tuple[float, float], arch_radius_m: float) -> np.ndarray:
    """Station positions along x, m: even spacing, denser over the wheel arches, every profile knot."""
    L = look.length_m
    profile = PROFILES[look.body_type]
    even = np.linspace(-L / 2, L / 2, max(8, round(L / STATION_SPACING_M)) + 1)
    xs = [(np.array([u for u, _ in profile.top]) - 0.5) * L]
    c = profile.corner_share * L
    xs.append(-L / 2 + c * (1 - np.cos(np.linspace(0, np.pi / 2, 7))))
    xs.append(L / 2 - c * (1 - np.cos(np.linspace(0, np.pi / 2, 7))))
    for x0 in axles_x:
        xs.append(x0 + arch_radius_m * np.sin(np.linspace(-np.pi / 2, np.pi / 2, 17)))
    if profile.rear_floor_m is not None:
        xs.append([floor_start_x_m(look), floor_start_x_m(look) - FLOOR_STEP_M])
    kept = np.concatenate(xs)
    # An even station within an eighth of a spacing of a kept one (a profile knot's) would make a sliver of quads whose
    # rows kink across it (a window's outline steps there, a shut line leaves the side).
    near = np.abs(even[:, None] - kept[None, :]).min(axis=1) < STATION_SPACING_M / 8
    x = np.unique(np.round(np.clip(np.concatenate([kept, even[~near | (np.abs(even) >= L / 2)]]), -L / 2, L / 2), 6))
    x[0], x[-1] = -L / 2, L / 2
    return x


def _bottom_m(look: VehicleLook, x: np.ndarray, axles_x, arch_radius_m: float) -> np.ndarray:
    """Height of the underside at `x`: the clearance, rising to the bumpers at both ends and arching
    over the wheels."""
    profile = PROFILES[look.body_type]
    L, H = look.length_m, look.height_m
    end = profile.end_lift * H
    ramp = 0.08 * L
    d = np.minimum(x + L / 2, L / 2 - x)
    bottom = profile.clearance_m + (end - profile.clearance_m) * np.clip(1 - d / ramp, 0, 1) ** 2
    if profile.departure_angle_deg is not None:
        # The rear overhang's lowest point is the bumper's lower rear edge, half the bumper's depth behind the end
        # face (`REAR_BUMPER_M`): the shell's underside keeps the line's height that far behind each station, so the
        # bumper's lower edge lies on the line and is the end face's lower edge, with nothing under it.
        reach_m = REAR_BUMPER_M[0] / 2 if look.body_type in REAR_BUMPER_BODIES else 0.0
        bottom = np.maximum(bottom, departure_line_m(look, x - reach_m))
    r = look.wheel_radius_m
    for x0 in axles_x:
        inside = np.abs(x - x0) < arch_radius_m
        arch = r + np.sqrt(np.maximum(arch_radius_m**2 - (x - x0) ** 2, 0.0))
        bottom = np.where(inside, np.maximum(bottom, arch), bottom)
    if profile.rear_floor_m is not None:  # over the wheels too: they run under the floor, not in arches
        behind = x <= floor_start_x_m(look) - FLOOR_STEP_M + 1e-9
        bottom = np.where(behind, np.maximum(bottom, profile.rear_floor_m), bottom)
    return bottom


def floor_start_x_m(look: VehicleLook) -> float:
    """Where a load floor (`Profile.rear_floor_m`) starts along the vehicle, m: the cab's back."""
    return (PROFILES[look.body_type].floor_start_u - 0.5) * look.length_m


def departure_line_m(look: VehicleLook, x_m: np.ndarray) -> np.ndarray:
    """Height over the road at `x_m` of the departure line (`Profile.departure_angle_deg`), m, 0 ahead of its foot.

    The line at angle theta to the road tangent to a rear tyre of radius r meets the road r tan(theta / 2) behind
    the rear axle (the tangent's distance to the wheel's centre is r), so at a distance s behind the axle it is
    (s - r tan(theta / 2)) tan(theta) up: a rear overhang's lowest point on it makes the departure angle theta."""
    theta = np.radians(PROFILES[look.body_type].departure_angle_deg)
    behind_m = look.rear_axle_x_m - np.asarray(x_m, dtype=np.float64)
    return np.maximum(behind_m - look.wheel_radius_m * np.tan(theta / 2), 0.0) * np.tan(theta)


SECTION_DENSE = 128
"""Points of each arc of the dense superellipse that a section's points are spaced evenly along."""
GREENHOUSE_EXPONENT = 10.0
"""Superellipse exponent of the greenhouse over the belt (side glass, pillars and roof): its sides rise
straight from the belt (then lean in by `Profile.tumblehome`) and round into the roof over about a tenth of
its half-width, as a car's roof rails do (cf. `SECTION_EXPONENT`'s body, rounded over about a fifth)."""
GREENHOUSE_SIDE_QUADS = 4
"""Rows of the section's upper arc up each side of a greenhouse, from the belt to the roof's edge; the
others span the roof (`_sections`)."""
SILL_SIDE_QUADS = 5
"""Rows of the section's lower arc down each side, from the belt to the bottom's corner; the others span the floor
(`_sections`)."""
ROOF_EDGE_ROW_M = 0.09
"""Width of the section's first row over each roof edge, m: a windscreen's A-pillars (current cars' are
about 0.08–0.15 m thick, `_screen_pillars`)."""
BELT_REACH = (-0.95, 0.85)
"""Where a section's belt points may lie, as heights over its half height about its centre: a station
whose roof is below the beltline (a bonnet) keeps an upper arc at its top."""


SILL_CORNER_QUADS = 3
"""Of a flat-sided body's `SILL_SIDE_QUADS` rows down each side (`Profile.sill_radius_m`), those round its bottom
edge (30° each); the others run down its flat side."""


def _rounded_lower_arc(
    half_width_m: np.ndarray, half_height_m: np.ndarray, belt_z_m: np.ndarray, radius_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """(y, z − centre) of a flat-sided body's lower arc (S, `LOWER_POINTS`), in `_sections`' order: from the belt on
    the −y side straight down the flat side, round the bottom edge (a quarter circle of `radius_m`, in
    `SILL_CORNER_QUADS` rows), across the floor and back up the +y side, the last point's mirror image the +y belt
    point. The radius shrinks to half the side's height under the belt or half the half-width where they are less
    (a bumper's station low over its end), so every station keeps a flat side."""
    hw, hz, zb = (np.asarray(a, dtype=np.float64)[:, None] for a in (half_width_m, half_height_m, belt_z_m))
    rc = np.minimum(radius_m, 0.5 * np.minimum(zb + hz, hw))
    flat = SILL_SIDE_QUADS - SILL_CORNER_QUADS
    floor = LOWER_POINTS - 2 * SILL_SIDE_QUADS
    t = np.arange(flat + 1)[None, :] / flat  # down the flat side, the corner's first point last
    side_y, side_z = np.broadcast_to(-hw, (len(hw), flat + 1)), zb + (rc - hz - zb) * t
    a = np.pi + np.pi / 2 * np.arange(1, SILL_CORNER_QUADS + 1)[None, :] / SILL_CORNER_QUADS
    corner_y, corner_z = -hw + rc + rc * np.cos(a), -hz + rc + rc * np.sin(a)
    f = np.arange(1, floor)[None, :] / floor  # the floor's inner points (its ends are the corners' last)
    floor_y, floor_z = (-hw + rc) * (1 - 2 * f), np.broadcast_to(-hz, (len(hw), floor - 1))
    half_y = np.concatenate([side_y, corner_y], axis=1)
    half_z = np.concatenate([side_z, corner_z], axis=1)
    # The +y side: the −y side's points mirrored, from the floor's far corner up to the point under the belt.
    y = np.concatenate([half_y, floor_y, -half_y[:, :0:-1]], axis=1)
    z = np.concatenate([half_z, floor_z, half_z[:, :0:-1]], axis=1)
    return y, z


def _sections(
    half_width_m: np.ndarray,
    half_height_m: np.ndarray,
    belt_rel: np.ndarray,
    exponent: np.ndarray,
    sill_radius_m: float | None = None,
):
    """(y, z − centre) of each station's section points (S, N) and each point's mirror image (N,).

    The points run counter-clockwise about +x: `UPPER_POINTS` from the belt on the +y side over the roof
    (the first exactly at the belt), then `LOWER_POINTS` from the belt on the −y side under the floor. The
    lower arc is the body's superellipse (its exponent per station), `SILL_SIDE_QUADS` rows down each side to the
    bottom's corners and the rest across the floor, evenly spaced along it between; the upper arc is the greenhouse's
    squarer one (`GREENHOUSE_EXPONENT`), `GREENHOUSE_SIDE_QUADS` rows up each side, a `ROOF_EDGE_ROW_M` row
    over each roof edge and the rest evenly across the roof, at every station alike (a bonnet's and a boot's
    too, where the "belt" is clamped under their top: `BELT_REACH`). So every station has a row of points on
    its beltline (`belt_rel`: the belt's height over the half height, about the centre), where the windows end. Both
    counts are odd, so no point lies on the vertical; point k's mirror image (y → −y) is `mirror[k]`. With
    `sill_radius_m` the lower arc is a flat-sided box's instead (`_rounded_lower_arc`), its belt point on the flat
    side."""
    e = 2 / np.asarray(exponent, dtype=np.float64)
    b = np.clip(belt_rel, *BELT_REACH)
    phi_belt = np.arcsin(np.sign(b) * np.abs(b) ** (1 / e))
    # Over the belt the greenhouse is its own squarer arc: from the belt's point straight up, round the roof's
    # edges, over the roof (`BELT_REACH` keeps some room over a bonnet's or boot's clamped belt).
    belt_y = half_width_m * np.abs(np.cos(phi_belt)) ** e if sill_radius_m is None else half_width_m
    belt_z = half_height_m * b
    room_m = half_height_m - belt_z
    g = 2 / GREENHOUSE_EXPONENT
    ys, zs = [], []
    arcs = ((phi_belt, np.pi - phi_belt, UPPER_POINTS), (np.pi - phi_belt, 2 * np.pi + phi_belt, LOWER_POINTS))
    for upper, (lo, hi, count) in zip((True, False), arcs, strict=True):
        if not upper and sill_radius_m is not None:
            arc_y, arc_z = _rounded_lower_arc(half_width_m, half_height_m, belt_z, sill_radius_m)
            ys.append(arc_y)
            zs.append(arc_z)
            continue
        if upper:  # the greenhouse, from the belt's point on the +y side to its mirror image
            psi = np.linspace(0.0, np.pi, SECTION_DENSE + 1)[None, :]
            cg, sg = np.cos(psi), np.sin(psi)
            y = belt_y[:, None] * np.sign(cg) * np.abs(cg) ** g
            z = belt_z[:, None] + room_m[:, None] * np.abs(sg) ** g
        else:  # the body, from the belt's point on the −y side under the floor and back
            phi = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, SECTION_DENSE + 1)[None, :]
            c, s = np.cos(phi), np.sin(phi)
            y = half_width_m[:, None] * np.sign(c) * np.abs(c) ** e[:, None]
            z = half_height_m[:, None] * np.sign(s) * np.abs(s) ** e[:, None]
        along = np.concatenate([np.zeros((len(y), 1)), np.cumsum(np.hypot(np.diff(y), np.diff(z)), axis=1)], axis=1)
        k = np.arange(count)
        arc_y, arc_z = np.empty((len(y), count)), np.empty((len(y), count))
        for i in range(len(y)):
            if upper:
                # `GREENHOUSE_SIDE_QUADS` rows up each side to the roof's edge (ψ = π/4), the rest across the
                # roof: every station's rows then mean the same, the side glass's and the screens' alike.
                # The first row over each edge is `ROOF_EDGE_ROW_M` wide: where a screen meets the side glass it
                # is the A- or C-pillar (`_screen_pillars`).
                corner = SECTION_DENSE // 4
                side, roof_edge = along[i, corner], along[i, SECTION_DENSE - corner]
                edge = min(ROOF_EDGE_ROW_M, (roof_edge - side) / (count - 2 * GREENHOUSE_SIDE_QUADS))
                knots_k = [0, GREENHOUSE_SIDE_QUADS, GREENHOUSE_SIDE_QUADS + 1]
                knots_k += [count - GREENHOUSE_SIDE_QUADS - 1, count - GREENHOUSE_SIDE_QUADS, count]
                knots_m = [0.0, side, side + edge, roof_edge - edge, roof_edge, along[i, -1]]
                at = np.interp(k, knots_k, knots_m)
            else:
                # `SILL_SIDE_QUADS` rows down each side to the bottom's corner (the superellipse's point on its box's
                # diagonal), the rest across the floor: a row of points on each corner, so that no facet chamfers it
                # (the paint's edge to the underbody follows the sill and a wheel arch's lip).
                corners_m = np.interp((5 * np.pi / 4, 7 * np.pi / 4), phi[i], along[i])
                knots_k = [0, SILL_SIDE_QUADS, count - SILL_SIDE_QUADS, count]
                knots_m = [0.0, max(corners_m[0], 1e-6), min(corners_m[1], along[i, -1] - 1e-6), along[i, -1]]
                at = np.interp(k, knots_k, knots_m)
            arc_y[i] = np.interp(at, along[i], y[i])
            arc_z[i] = np.interp(at, along[i], z[i])
        if not upper:  # its first point is the −y side's belt point exactly (sin(π − φ) rounds near π)
            arc_y[:, 0], arc_z[:, 0] = -belt_y, belt_z
        ys.append(arc_y)
        zs.append(arc_z)
    upper, lower = np.arange(UPPER_POINTS), np.arange(LOWER_POINTS)
    mirror = np.concatenate([np.where(upper == 0, UPPER_POINTS, (UPPER_POINTS - upper) % UPPER_POINTS),
                             UPPER_POINTS + np.where(lower == 0, -UPPER_POINTS, LOWER_POINTS - lower)])  # fmt: skip
    return np.concatenate(ys, axis=1), np.concatenate(zs, axis=1), mirror


def shell(look: VehicleLook) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The body shell: (vertices (V, 3) m, faces (F, 3), per-vertex normals (V, 3), face kind (F,) 0
    paint, 1 glass, 2 black trim (`_black_pillars`), 3 a glass roof (`_glass_roof`: glass of its own
    transmittance, `camgen.vehicles.cabin.ROOF_GLASS_T`)), closed and wound counter-clockwise seen from outside."""
    profile = PROFILES[look.body_type]
    L, W, H = look.length_m, look.width_m, look.height_m
    axles = (look.front_axle_x_m, look.rear_axle_x_m)
    arch_radius = look.wheel_radius_m + ARCH_GAP_M
    x = _stations(look, axles, arch_radius)
    u = x / L + 0.5
    top = _interp_top(profile, u) * H
    bottom = np.minimum(_bottom_m(look, x, axles, arch_radius), top - 0.05)
    # Plan view: flat ends `end_width` wide, quarter-ellipse corners `corner_share` long.
    c = profile.corner_share * L
    d = np.minimum(x + L / 2, L / 2 - x)
    t = np.clip(d / c, 0.0, 1.0)
    half_width = W / 2 * (profile.end_width + (1 - profile.end_width) * np.sqrt(1 - (1 - t) ** 2))
    zc, hz = (top + bottom) / 2, (top - bottom) / 2
    belt = profile.belt * H
    # Over a wheel the section is squashed to the arch's top: its exponent grows as its height shrinks, so that
    # its sides stay upright down to the arch and round under it as tightly as elsewhere (the arch's edge a clean
    # arc in a side view, the underbody only its roof).
    plain_hz = (top - np.minimum(_bottom_m(look, x, (), arch_radius), top - 0.05)) / 2
    exponent = profile.section_exponent * np.clip(plain_hz / hz, 1.0, ARCH_EXPONENT_GAIN)
    Y, Z, mirror = _sections(half_width, hz, (belt - zc) / hz, exponent, profile.sill_radius_m)
    Z = Z + zc[:, None]
    above = np.clip((Z - belt) / np.maximum(top[:, None] - belt, 1e-6), 0.0, 1.0)
    Y = Y * (1 - profile.tumblehome * above)
    X = np.broadcast_to(x[:, None], Z.shape)
    S, N = Z.shape
    vertices = np.stack([X, Y, Z], axis=-1).reshape(-1, 3)
    index = np.arange(S * N).reshape(S, N)
    a, b = index[:-1], np.roll(index[:-1], -1, axis=1)
    c_, d_ = np.roll(index[1:], -1, axis=1), index[1:]
    # Points run counter-clockwise about +x (y then z): seen from outside, (a, c, d) turns outward.
    tube = np.concatenate([np.stack([a, c_, d_], -1).reshape(-1, 3), np.stack([a, b, c_], -1).reshape(-1, 3)])
    # Ends: a ladder between each point on the left (y > 0), bottom to top, and its mirror image.
    left = sorted((k for k in range(N) if Y[0, k] > 0), key=lambda k: Z[0, k])
    # A flat floor (`Profile.sill_radius_m`) has several points on one line: the ladder's rungs across it would be
    # triangles of no area, so the floor's points are fanned to the lowest point over it on the left instead.
    floor = [k for k in left if Z[0, k] - Z[0, left[0]] < 1e-9] if profile.sill_radius_m is not None else left[:1]
    chain = sorted(floor + [mirror[k] for k in floor], key=lambda k: Y[0, k])
    caps = []
    for station, sign in ((0, -1), (S - 1, 1)):
        p = index[station]
        faces_here = []
        if len(floor) > 1:
            apex = left[len(floor)]
            faces_here += [(p[k0], p[k1], p[apex]) for k0, k1 in itertools.pairwise(chain)]
            faces_here.append((p[mirror[apex]], p[chain[0]], p[apex]))
        for k0, k1 in itertools.pairwise(left if len(floor) == 1 else left[len(floor) :]):
            m0, m1 = mirror[k0], mirror[k1]
            faces_here += [(p[k0], p[k1], p[m1]), (p[k0], p[m1], p[m0])]
        caps += faces_here if sign > 0 else [tuple(reversed(f)) for f in faces_here]
    faces = np.concatenate([tube, np.array(caps)])
    normals = _vertex_normals(vertices, faces[: len(tube)], len(vertices))
    if profile.sill_radius_m is not None:
        # A flat side's rows, the belt's to the bottom edge's first, take their normals from the flat side alone:
        # the edge's first facet would tilt the lowest row's (over a wheel arch's steep ends, where the lip faces
        # fore or aft, by up to 28°) and streak the flat paint above it up to the next row, and the greenhouse's
        # lean would tilt the belt's by more where the side under it is shorter (over an arch). The flat side's
        # true normal is the edge's too where the two meet.
        flat = SILL_SIDE_QUADS - SILL_CORNER_QUADS
        quads = UPPER_POINTS + np.concatenate([np.arange(flat), LOWER_POINTS - flat + np.arange(flat)])
        rows = np.concatenate(
            [UPPER_POINTS + np.arange(flat + 1), (UPPER_POINTS + LOWER_POINTS - np.arange(flat + 1)) % N]
        )
        on_flat = np.isin(np.tile(np.arange(N), S - 1), quads)
        flat_normals = _vertex_normals(vertices, tube[np.concatenate([on_flat, on_flat])], len(vertices))
        at = index[:, rows].ravel()
        normals[at] = flat_normals[at]
    kind = _glass(profile, look, vertices, faces, len(tube) // 2)
    return vertices, faces, normals, kind


def _vertex_normals(vertices: np.ndarray, faces: np.ndarray, count: int) -> np.ndarray:
    """Area-weighted smooth normals of the tube (the caps' flat faces do not bend its rim)."""
    cross = np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]], vertices[faces[:, 2]] - vertices[faces[:, 0]])
    normals = np.zeros((count, 3))
    for k in range(3):
        np.add.at(normals, faces[:, k], cross)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return normals / np.where(length > 0, length, 1.0)


def _glass(profile: Profile, look: VehicleLook, vertices, faces, quads: int) -> np.ndarray:
    """1 for each face of glass (3 of a glass roof), 0 for paint, 2 for black trim. The tube's two triangles of a
    quad (faces k and k + `quads`) are judged together, by the quad's centre and normal (`_glass_by_quad`); then each
    window of the tube (side windows, windscreen, rear window) is made to follow rows of section points
    (`_window_rows`), so that its outline runs along the mesh's edges instead of stepping between rows
    from one station to the next."""
    glass, windows = _glass_by_quad(profile, look, vertices, faces, quads)
    count = UPPER_POINTS + LOWER_POINTS
    grid = lambda flags: flags[:quads].reshape(-1, count)  # noqa: E731  (station, quad of the section)
    side, *screens = (_window_rows(grid(window)) for window in windows)
    # Where a windscreen or rear window goes on past the side windows' end, the side window's end would
    # leave a notch of paint under the screen's edge. Over such a stretch either the screen keeps above
    # the side windows' top row (its edge runs on from theirs) or, where the whole stretch has its
    # beltline (no bonnet), the side windows' rows are glass too (the screen reaches down to it),
    # whichever leaves the glass's area nearer the per-quad judgement's.
    corners = vertices[faces[:quads]]
    area = grid(np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1))
    k = np.arange(count)
    rows = side.any(axis=0)
    top_row = np.flatnonzero(rows[: (UPPER_POINTS + 1) // 2])
    above = (np.minimum(k, UPPER_POINTS - 1 - k) > (top_row.max() if top_row.size else -1)) & (k < UPPER_POINTS)
    belt = np.abs(vertices[::count, 2][: quads // count + 1] - profile.belt * look.height_m) < 1e-9
    belted = belt[:-1] & belt[1:]
    tube = side.copy()
    for screen, judged in zip(screens, windows[1:], strict=True):
        judged = grid(judged) | grid(windows[0])
        for start, stop in _runs(screen.any(axis=1)):
            here = slice(start, stop)
            if not side[max(start - 1, 0) : stop + 1].any():
                tube[here] |= screen[here]
                continue
            beyond = ~side[here].any(axis=1)
            cut = screen[here] & (~beyond[:, None] | above[None, :])
            fill = screen[here] | rows[None, :]
            want = (area[here] * judged[here]).sum()
            options = (cut, fill) if belted[here].all() else (cut,)
            tube[here] |= min(options, key=lambda option: abs((area[here] * (option | side[here])).sum() - want))
    tube &= ~_screen_pillars(tube, top_row.max() if top_row.size else -1)
    doors = grid(glass) & ~np.any([grid(w) for w in windows], axis=0)  # a bus's doors reach below the belt
    tube |= doors
    glass_roof = _glass_roof(look, vertices, faces, quads, tube)
    side_top = top_row.max() if top_row.size else -1
    black = _black_pillars(profile, look, vertices, faces, quads, tube | glass_roof, side_top)
    kind = glass.astype(np.int8)
    for half in (slice(0, quads), slice(quads, 2 * quads)):
        kind[half] = np.where(black, 2, np.where(glass_roof, 3, tube)).reshape(-1)
    return kind


def _glass_roof(look: VehicleLook, vertices, faces, quads: int, tube: np.ndarray) -> np.ndarray:
    """(S − 1, N) bool: the glass roof's quads (`camgen.vehicles.roof.glass_roof_rows`), the roof's quads between its
    edge rows over its longest run of stations that face up at the roof's height and hold no other glass, where the
    vehicle has one."""
    from camgen.vehicles.roof import glass_roof_rows, roof_quads, roof_rows_up

    count = UPPER_POINTS + LOWER_POINTS
    roof = roof_quads(UPPER_POINTS, GREENHOUSE_SIDE_QUADS)
    grid = vertices[: len(vertices) // count * count].reshape(-1, count, 3)
    up = roof_rows_up(look, grid, UPPER_POINTS, GREENHOUSE_SIDE_QUADS) & ~tube[:, roof].any(axis=1)
    rows = glass_roof_rows(look, grid[:, 0, 0], up)
    out = np.zeros_like(tube)
    out[np.ix_(rows, roof)] = True
    return out


BLACK_PILLAR_SHARE = 0.04
"""Pillar bands (`Profile.pillars`) at most this share of the length wide are black where they part the side
windows: a car's B-pillar (and an estate's narrow C-pillar), covered with gloss black trim on most current
cars, and a city bus's window pillars, hidden behind its flush bonded glazing's black-printed edges. Wider
bands (a hatchback's or SUV's D-pillar) stay in the paint."""


def _black_pillars(profile: Profile, look: VehicleLook, vertices, faces, quads: int, tube, side_top: int):
    """(S − 1, N) bool: the quads of the narrow pillar bands (`BLACK_PILLAR_SHARE`) in the side windows' rows
    that are not glass."""
    narrow = [band for band in profile.pillars if band[1] - band[0] <= BLACK_PILLAR_SHARE]
    if not narrow or side_top < 0:
        return np.zeros_like(tube)
    u = (vertices[faces[:quads]].mean(axis=1)[:, 0] / look.length_m + 0.5).reshape(tube.shape)
    in_band = np.any([(u > lo) & (u < hi) for lo, hi in narrow], axis=0)
    k = np.arange(tube.shape[1])
    rows = (k < UPPER_POINTS) & (np.minimum(k, UPPER_POINTS - 1 - k) <= side_top)
    return in_band & rows[None, :] & ~tube


def _screen_pillars(tube: np.ndarray, side_top: int) -> np.ndarray:
    """(S − 1, N) bool: the A-pillars (beside a windscreen) and C-pillars (beside a rear window) as paint: at
    every station of a screen's run of stations (glass above the row over `side_top`, counted from the belt)
    where one of its bands also holds side-window glass (rows up to `side_top`), the row just above the side
    windows' top row, on both sides: the pillar runs on beyond the side windows down to the screen's lower
    corner (the cowl), so that the screen keeps one lower edge row. Without them a
    screen and the side windows under its edges are one pane wrapping round the corner, as no car's glass
    is. The row follows the screen's edge down the slope (a sloped screen's stations are lower towards the
    bonnet, and every section's rows are spread evenly over its upper arc), as a real pillar does. Its
    width is the mesh's row: 0.13–0.17 m on the cars across the pillar (seeds 1–3; 0.09 m at a hatchback's
    low front stations), 0.16–0.23 m on vans and 0.17–0.30 m on box trucks' cabs. Current cars' A-pillars
    are about 0.08–0.15 m thick (UN Regulation 125, formerly Directive 77/649/EEC, caps each A-pillar's
    binocular obscuration of the driver's view at 6°, and pillars have grown towards that limit since the
    1990s), so the cars' pillars are about right and the commercial vehicles' a little broad.
    Where no side window reaches the belt's rows (`side_top` < 0), nothing."""
    pillars = np.zeros_like(tube)
    if side_top < 0:
        return pillars
    k = np.arange(tube.shape[1])
    near = np.where(k < UPPER_POINTS, np.minimum(k, UPPER_POINTS - 1 - k), UPPER_POINTS)
    side_rows = tube & (near <= side_top)[None, :]
    screen_rows = tube & ((near > side_top + 1) & (near < UPPER_POINTS))[None, :]
    both = side_rows.any(axis=1) & screen_rows.any(axis=1)
    for start, stop in _runs(screen_rows.any(axis=1)):
        if both[start:stop].any():
            pillars[start:stop] = (near == side_top + 1)[None, :]
    return pillars & tube


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of each run of True in `flags`."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], flags.astype(np.int8), [0]])))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


def _window_rows(window: np.ndarray) -> np.ndarray:
    """(S − 1, N) bool: the quads of one window (`window`, judged per quad), redrawn as whole rows. Each
    station's band that holds any of the window keeps it; the window spans, on both sides alike, the
    rows of the upper arc from its lowest to its highest row that most of those bands span (the median),
    mirror images about the roof's centre (quad k of the upper arc mirrors quad `UPPER_POINTS` − 1 − k).
    Section points are evenly spaced along each upper arc (`_sections`), so a row's points run smoothly
    along the vehicle: its edges become lines of the mesh (the beltline already is one)."""
    upper = window[:, :UPPER_POINTS]
    bands = upper.any(axis=1)
    if not bands.any():
        return np.zeros_like(window)
    k = np.arange(UPPER_POINTS)
    near = np.minimum(k, UPPER_POINTS - 1 - k)  # rows counted from the belt on either side
    first = np.where(upper, near[None, :], UPPER_POINTS).min(axis=1)[bands]
    last = np.where(upper & (k < (UPPER_POINTS + 1) // 2)[None, :], k[None, :], -1).max(axis=1)[bands]
    lo, hi = int(np.median(first)), int(np.median(last))
    rows = (near >= lo) & (np.minimum(k, UPPER_POINTS - 1 - k) <= hi)
    out = np.zeros_like(window)
    out[:, :UPPER_POINTS] = bands[:, None] & rows[None, :]
    return out


def _glass_by_quad(profile: Profile, look: VehicleLook, vertices, faces, quads: int):
    """(glass (F,) bool, [side windows, windscreen and rear window (F,) bool]): each quad judged by its
    centre and normal."""
    L, H = look.length_m, look.height_m
    corners = vertices[faces]
    centre = corners.mean(axis=1)
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    pair = np.arange(2 * quads)
    partner = np.where(pair < quads, pair + quads, pair - quads)
    centre[: 2 * quads] = (centre[pair] + centre[partner]) / 2
    n[: 2 * quads] = n[pair] + n[partner]
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    u = centre[:, 0] / L + 0.5
    z = centre[:, 2] / H
    top = _interp_top(profile, np.clip(u, 0, 1))
    glass = np.zeros(len(faces), dtype=bool)
    within = lambda band: (u > band[0]) & (u < band[1])  # noqa: E731
    above_belt = (z > profile.belt + 0.02) & (z < top - 0.03)
    side = np.abs(n[:, 1]) > 0.75
    pillar = np.zeros(len(faces), dtype=bool)
    for band in profile.pillars:
        pillar |= within(band)
    side_windows = above_belt & side & within(profile.side_glass) & ~pillar
    upper = (np.abs(n[:, 1]) < 0.45) & (z > profile.belt + 0.02)
    screens = [upper & within(profile.windscreen), upper & within(profile.rear_window)]
    glass |= side_windows | screens[0] | screens[1]
    if profile.doors:
        door = np.zeros(len(faces), dtype=bool)
        for band in profile.doors:
            door |= within(band)
        nearside = n[:, 1] * nearside_sign(look) > 0.75
        glass |= door & nearside & (z > profile.door_glass_bottom) & (z < top - 0.03)
    cap = np.arange(len(faces)) >= 2 * quads
    for band, front in ((profile.front_cap_glass, True), (profile.rear_cap_glass, False)):
        if band is None:
            continue
        end = cap & ((centre[:, 0] > 0) == front)
        glass |= end & (z > band[0]) & (z < band[1])
    return glass, [side_windows, *screens]


def nearside_sign(look: VehicleLook) -> float:
    """+1 when the kerb side is the vehicle's left (+y: driven on the left, a UK-format plate,
    `camgen.vehicles.plate`), −1 when it is its right."""
    return 1.0 if UK_PLATE_PATTERN.match(look.plate_text) else -1.0


def _box(size_m, centre_m) -> trimesh.Trimesh:
    box = trimesh.creation.box(extents=size_m)
    box.apply_translation(centre_m)
    return box


def _flat(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unshared vertices and face normals (flat shading) of a mesh: (vertices, normals, faces)."""
    vertices = np.asarray(mesh.vertices)[np.asarray(mesh.faces)].reshape(-1, 3)
    normals = np.repeat(np.asarray(mesh.face_normals), 3, axis=0)
    return vertices, normals, np.arange(len(vertices)).reshape(-1, 3)


def _part(name: str, surface: str, meshes: list[tuple[trimesh.Trimesh, int]], smooth: bool = False) -> Part:
    vertices, normals, faces, wheel, offset = [], [], [], [], 0
    for mesh, wheel_index in meshes:
        if smooth:
            v, nrm, f = np.asarray(mesh.vertices), np.asarray(mesh.vertex_normals), np.asarray(mesh.faces)
        else:
            v, nrm, f = _flat(mesh)
        vertices.append(v)
        normals.append(nrm)
        faces.append(f + offset)
        wheel.append(np.full(len(v), wheel_index, dtype=np.int8))
        offset += len(v)
    return Part(
        name, surface, np.concatenate(vertices), np.concatenate(normals), np.concatenate(faces), np.concatenate(wheel)
    )


def _merge(name: str, surface: str, parts: list[Part]) -> Part:
    """Parts concatenated into one (their vertices in order, faces renumbered)."""
    offsets = np.cumsum([0] + [len(p.vertices_m) for p in parts[:-1]])
    optional = lambda key: (  # noqa: E731
        None if getattr(parts[0], key) is None else np.concatenate([getattr(p, key) for p in parts])
    )
    return Part(
        name,
        surface,
        np.concatenate([p.vertices_m for p in parts]),
        np.concatenate([p.normals for p in parts]),
        np.concatenate([p.faces + o for p, o in zip(parts, offsets, strict=True)]),
        np.concatenate([p.wheel for p in parts]),
        optional("texcoords"),
        optional("colours"),
    )


def _coloured_part(name: str, surface: str, pieces: list[tuple[trimesh.Trimesh, tuple[float, float, float]]]) -> Part:
    """One body part (`Part.wheel` −1) of flat-shaded meshes, each coloured with its own linear albedo per vertex."""
    part = _part(name, surface, [(mesh, -1) for mesh, _ in pieces])
    # `_part` gives each face its own three vertices, in the pieces' order.
    part.colours = np.repeat([rgb for _, rgb in pieces], [3 * len(mesh.faces) for mesh, _ in pieces], axis=0)
    return part


TYRE_RGB = (0.025, 0.025, 0.025)
"""Linear albedo of tyre rubber (carbon-black filled: about 2–3 %)."""
RIM_RGB = (0.45, 0.45, 0.46)
"""Linear albedo of a painted alloy wheel (silver)."""
TRIM_RGB = (0.03, 0.03, 0.03)
"""Linear albedo of black plastic trim."""
UNDERBODY_RGB = (0.04, 0.04, 0.04)
"""Linear albedo of a car's underside: black PVC underbody protection and plastic undertrays (3–5 %,
like black trim), not the body colour: the paint shop sprays the underbody with underseal."""
UNDERBODY_NORMAL_Z = -0.5
"""Shell faces whose outward normal points further down than this (more than 30° below the horizontal)
are underbody."""
GROUND_SHADE_RGB = (0.008, 0.008, 0.008)
"""Linear albedo the ground under the floor is drawn with: a road's 0.1–0.25 times the share of the sky
it still sees through the gap under the sills. A point d inside a gap of height c sees the sky up to an
elevation α = atan(c / d); the 2-D view factor of a horizontal strip element to a band between angles
φ1 and φ2 from its normal is (sin φ2 − sin φ1) / 2 (Howell, *A Catalog of Radiation Heat Transfer
Configuration Factors*), so to the sky band up to α, (1 − cos α) / 2: 0.15 at d = c, 0.03 at d = 3c and,
with both sides open, 0.014 under the middle of a car (c 0.15 m, 0.9 m to either sill). The ground under
the floor is lit by a few per cent of what lights the open road."""
GROUND_SHADE_Z_M = 0.02
"""Height of the shaded ground under a vehicle, m: above every example scene's road planes (z 0–0.011 m)
and below any vehicle's sill."""


def wheel_meshes(
    radius_m: float, width_m: float, rim_share: float = RIM_SHARE["sedan"]
) -> tuple[trimesh.Trimesh, list[trimesh.Trimesh]]:
    """A tyre (a closed cylinder) and its rim (hub, five spokes and the rim's outer ring
    `RIM_LIP_SHARE` wide at `rim_share` of the tyre's radius, 8 mm proud of both sidewalls), in the
    wheel's frame: axle along y, centred on the origin."""
    to_y = trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0))
    tyre = trimesh.creation.cylinder(radius=radius_m, height=width_m, sections=WHEEL_SECTIONS)
    tyre.apply_transform(to_y)
    proud = width_m + 0.016
    hub = trimesh.creation.cylinder(radius=0.22 * radius_m, height=proud, sections=16)
    hub.apply_transform(to_y)
    rim_m = rim_share * radius_m
    ring = trimesh.creation.annulus(
        r_min=rim_m - RIM_LIP_SHARE * radius_m, r_max=rim_m, height=proud, sections=WHEEL_SECTIONS
    )
    ring.apply_transform(to_y)
    rim = [hub, ring]
    for k in range(5):
        spoke = _box((rim_m - 0.01 * radius_m, proud - 0.004, 0.11 * radius_m), (rim_m / 2, 0.0, 0.0))
        spoke.apply_transform(trimesh.transformations.rotation_matrix(2 * np.pi * k / 5, (0, 1, 0)))
        rim.append(spoke)
    return tyre, rim


STEEL_DISC_BODIES = ("bus",)
"""Body types on steel disc wheels (`steel_disc_wheel_meshes`) instead of a car's five-spoke alloy."""
STUD_COUNT = 10
STUD_CIRCLE_M = 0.335
"""A 22.5-inch commercial vehicle's disc wheel (ISO 4107, the ISO 10-stud fitting): ten M22 studs on a
335 mm pitch circle round a 281 mm centre bore."""
HAND_HOLES = 10
"""Round holes in the wheel's disc between the studs' ring and the rim (hand holes for the valve of the
inner of a pair of twin tyres and for cooling), dark: the brake drum and the inner wheel behind. Ten of up
to 70 mm across (makers' 22.5 × 8.25 disc wheels show 8–10 such holes; an estimate from their drawings)."""


def steel_disc_wheel_meshes(radius_m: float, width_m: float, rim_share: float) -> tuple[list, list]:
    """A commercial vehicle's steel disc wheel in the wheel's frame (axle along y): ([the disc with the rim's
    outer ring, the hub and its `STUD_COUNT` nuts on `STUD_CIRCLE_M`], [its `HAND_HOLES` dark holes]), each
    piece proud of the tyre's sidewalls as the alloy rim's (`wheel_meshes`). A bus's or truck's wheel shows
    a flat disc with a ring of round holes and a hub of nuts, not a car's spokes."""
    to_y = trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0))
    rim_m = rim_share * radius_m
    proud = width_m + 0.016

    def disc(r: float, height: float, sections: int = WHEEL_SECTIONS, at=(0.0, 0.0)) -> trimesh.Trimesh:
        piece = trimesh.creation.cylinder(radius=r, height=height, sections=sections)
        piece.apply_transform(to_y)
        piece.apply_translation((at[0], 0.0, at[1]))
        return piece

    bright = [disc(rim_m, proud), disc(0.14, proud + 0.06, 16)]
    for k in range(STUD_COUNT):
        angle = 2 * np.pi * (k + 0.5) / STUD_COUNT
        at = (STUD_CIRCLE_M / 2 * np.cos(angle), STUD_CIRCLE_M / 2 * np.sin(angle))
        bright.append(disc(0.016, proud + 0.05, 6, at))
    hole_ring_m = (STUD_CIRCLE_M / 2 + 0.03 + rim_m - RIM_LIP_SHARE * radius_m) / 2
    hole_m = min(0.035, (rim_m - RIM_LIP_SHARE * radius_m - STUD_CIRCLE_M / 2 - 0.03) / 2)
    dark = []
    for k in range(HAND_HOLES):
        angle = 2 * np.pi * k / HAND_HOLES
        dark.append(disc(hole_m, proud + 0.004, 12, (hole_ring_m * np.cos(angle), hole_ring_m * np.sin(angle))))
    return bright, dark


def wheel_centres(look: VehicleLook) -> np.ndarray:
    """(4, 3): front left, front right, rear left, rear right, m."""
    r, t = look.wheel_radius_m, look.track_m / 2
    f, b = look.front_axle_x_m, look.rear_axle_x_m
    return np.array([(f, t, r), (f, -t, r), (b, t, r), (b, -t, r)])


LAMP_DEPTH_M = 0.06
"""Lamps are boxes this deep, half sunk into the shell's end face."""


def _end_heights(look: VehicleLook) -> tuple[tuple[float, float], tuple[float, float]]:
    """(bottom, top) of the rear and front end faces, m."""
    profile = PROFILES[look.body_type]
    axles = (look.front_axle_x_m, look.rear_axle_x_m)
    ends = np.array([-look.length_m / 2, look.length_m / 2])
    bottom = _bottom_m(look, ends, axles, look.wheel_radius_m + ARCH_GAP_M)
    top = _interp_top(profile, np.array([0.0, 1.0])) * look.height_m
    return (float(bottom[0]), float(top[0])), (float(bottom[1]), float(top[1]))


VAN_REAR_CLUSTER_M = (0.20, 0.60)
"""Width and height of a van's rear lamp cluster, m: a panel van's rear lamps are upright clusters on the rear
pillars beside the rear doors (Ford Transit 2014-, VW Crafter 2017-, Mercedes Sprinter 907), about 0.2 m wide and
0.5-0.7 m tall in makers' rear views (an estimate), the tail, stop, indicator and reversing lamps stacked."""
VAN_REAR_CLUSTER_TOP_M = 1.35
"""Height of a van's rear clusters' tops over the road, m (a Transit's about 1.3-1.4 m, at the rear doors' middle
height, in makers' rear views; an estimate)."""


def _rear_lamps_m(
    look: VehicleLook, tail_z_m: float, rear_high_m: float
) -> dict[str, tuple[float, float, float, float]]:
    """Where the rear lamps lie on the rear face: name → (distance of its centre in from the face's side, height of
    its centre, width, height), m, for the lit "tail", "brake" and "indicator" lenses, the "reversing" lamp and the
    "cluster" round them (`_lamp_housings`): a car's cluster lies across each corner under the rear's top; a van's
    stands upright on each rear pillar (`VAN_REAR_CLUSTER_M`), its lamps stacked from the tail lamp down."""
    if look.body_type == "van":
        width, height = VAN_REAR_CLUSTER_M
        top = min(VAN_REAR_CLUSTER_TOP_M, rear_high_m - 0.3)
        lens = width - 0.04
        return {
            "cluster": (width / 2, top - height / 2, width, height),
            "tail": (width / 2, top - 0.08, lens, 0.10),
            "brake": (width / 2, top - 0.21, lens, 0.10),
            "indicator": (width / 2, top - 0.34, lens, 0.08),
            "reversing": (width / 2, top - 0.47, lens, 0.08),
        }
    rear_w, rear_h = REAR_CLUSTER_M
    rear_top = min(tail_z_m + 0.07, rear_high_m - 0.02)
    return {
        "cluster": (rear_w / 2, rear_top - rear_h / 2, rear_w, rear_h),
        "tail": (0.13, tail_z_m, 0.22, 0.10),
        "brake": (0.33, tail_z_m, 0.16, 0.07),
        "indicator": (0.13, tail_z_m - 0.09, 0.14, 0.05),
        "reversing": (0.33, tail_z_m - 0.085, 0.12, 0.04),
    }


def _rear_plate_z_m(look: VehicleLook, rear_low_m: float) -> float:
    """Height of the rear plate's centre, m: over the bumper's lower edge, or on the rear doors 3 cm over a van's
    rear bumper (`REAR_BUMPER_BODIES`)."""
    ph = PLATE_SIZE_M[1]
    if look.body_type in REAR_BUMPER_BODIES:
        return rear_low_m + REAR_BUMPER_M[1] + 0.03 + ph / 2
    return max(rear_low_m + 0.12 + ph / 2, 0.45)


def lamps_and_plates(
    look: VehicleLook, shell_m: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
) -> tuple[list[Part], dict[str, np.ndarray], list[Part], Part]:
    """Lamp parts (head, tail, brake, indicators), the plates' corners, the plates' part and the plates'
    backings. With the shell (`shell_m`: its vertices, normals and faces, `shell`), the headlamp units reach back
    over the nose (`_headlamp_tops`)."""
    L, W = look.length_m, look.width_m
    (rear_low, rear_high), (front_low, front_high) = _end_heights(look)
    half = W / 2 * PROFILES[look.body_type].end_width
    head_z = float(np.clip(front_high - 0.10, front_low + 0.12, 1.0))
    tail_z = float(np.clip(rear_high - 0.12, rear_low + 0.25, 1.2))
    xf, xr = L / 2, -L / 2
    lamp = lambda x, y, z, w, h: _box((LAMP_DEPTH_M, w, h), (x, y, z))  # noqa: E731
    head = [(lamp(xf, s * (half - 0.19), head_z, 0.26, 0.09), -1) for s in (1, -1)]
    rear_lamps = _rear_lamps_m(look, tail_z, rear_high)
    tail = [(lamp(xr, s * (half - rear_lamps["tail"][0]), *rear_lamps["tail"][1:]), -1) for s in (1, -1)]
    brake = [(lamp(xr, s * (half - rear_lamps["brake"][0]), *rear_lamps["brake"][1:]), -1) for s in (1, -1)]
    lamps = [
        _part("head_lamps", "head", head),
        _part("tail_lamps", "tail", tail),
        _part("brake_lamps", "brake", brake),
    ]
    for name, s in (("left", 1), ("right", -1)):  # each side flashes on its own
        front = lamp(xf, s * (half - 0.035), head_z, 0.05, 0.07)
        rear = lamp(xr, s * (half - rear_lamps["indicator"][0]), *rear_lamps["indicator"][1:])
        lamps.append(_part(f"indicators_{name}", f"indicator_{name}", [(front, -1), (rear, -1)]))
    pw, ph = PLATE_SIZE_M
    plates, corners, backings = [], {}, []
    for side, x, z, sign in (
        ("front", xf + 0.005 + LAMP_DEPTH_M / 2, front_low + 0.10 + ph / 2, 1.0),
        ("rear", xr - 0.005 - LAMP_DEPTH_M / 2, _rear_plate_z_m(look, rear_low), -1.0),
    ):
        # Read from outside: a viewer facing the front plate looks along −x, its left is −y; behind the
        # vehicle the viewer's left is +y.
        left = -sign * pw / 2
        quad = np.array([(x, left, z + ph / 2), (x, -left, z + ph / 2), (x, -left, z - ph / 2), (x, left, z - ph / 2)])
        corners[side] = quad
        # pyrender flips the image on upload: OpenGL's t = 1 is the image's row 0 (its top).
        texcoords = np.array([(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)])
        faces = np.array([(0, 3, 2), (0, 2, 1)])  # counter-clockwise seen from outside (normal ±x)
        normals = np.tile((sign, 0.0, 0.0), (4, 1))
        plates.append(Part(f"plate_{side}", "plates", quad, normals, faces, np.full(4, -1, np.int8), texcoords))
        backing = _box((LAMP_DEPTH_M / 2, pw + 0.02, ph + 0.02), (x - sign * LAMP_DEPTH_M / 4 - sign * 0.002, 0, z))
        backings.append((backing, -1))
    # One primitive for both plates: the front plate's image is the top half of the texture, the rear's
    # the bottom half (OpenGL's t runs up from the image's last row).
    front, rear = plates
    front.texcoords = front.texcoords * [1.0, 0.5] + [0.0, 0.5]
    rear.texcoords = rear.texcoords * [1.0, 0.5]
    backings += [(box, -1) for box in _black_trim(look, head_z)]
    housings = _lamp_housings(look, head_z, tail_z, shell_m)
    if housings is not None:
        lamps.append(housings)
    return lamps, corners, [_merge("plates", "plates", [front, rear])], _part("plate_backings", "trim", backings)


HOUSING_BODIES = ("hatchback", "sedan", "estate", "suv", "pickup", "van")
"""Body types whose lamps sit in lamp units: a clear-covered headlamp unit at each front corner and a red rear
cluster at each rear corner (a bus's and a box truck's lamps are separate units on the panel or the chassis)."""
HEADLAMP_UNIT_M = (0.48, 0.15)
"""Width and height of a headlamp unit's face, m: current cars' units are 0.45–0.6 m wide and 0.12–0.2 m tall
(makers' front views: a Golf 8's about 0.55 × 0.15 m, a Corolla's 0.5 × 0.16 m), most of it a clear
polycarbonate cover over chrome reflectors and black bezels; the lit lens (`lamps_and_plates`) is a part of it."""
REAR_CLUSTER_M = (0.42, 0.18)
"""Width and height of a rear lamp cluster's face, m (a Golf 8's about 0.45 × 0.17 m, a Focus's 0.4 × 0.2 m):
red lenses round the lit tail, stop and indicator lamps, and a clear reversing lamp."""
HEADLAMP_UNIT_RGB = (0.32, 0.32, 0.33)
"""Linear albedo of an unlit headlamp unit: chrome reflectors and black bezels seen through a clear cover, which
by day look light grey (sRGB about 150; an estimate; its gloss, roughness 0.1, adds the sun's highlight)."""
REAR_LENS_RGB = (0.22, 0.008, 0.01)
"""Linear albedo of an unlit red rear lens (ECE R48 red over a metallised reflector: sRGB about (130, 20, 25);
an estimate, as `camgen.render.scene_graph.VEHICLE_SURFACES`' tail lamp)."""
REVERSING_LENS_RGB = (0.30, 0.30, 0.31)
"""Linear albedo of an unlit reversing lamp: a clear lens over a chrome reflector (an estimate)."""
HOUSING_DEPTH_M = 0.05
"""Lamp units are boxes this deep, half sunk into the end face: the lit lenses (`LAMP_DEPTH_M`) stand 5 mm
proud of them."""


def _lamp_housings(
    look: VehicleLook,
    head_z_m: float,
    tail_z_m: float,
    shell_m: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> Part | None:
    """The lamp units round the lit lamps (`HOUSING_BODIES`): a headlamp unit at each front corner and a rear
    cluster with a reversing lamp at each rear corner, flush with the end faces' corners (each headlamp unit
    reaching back over the nose, `_headlamp_tops`, given the shell), one primitive of
    per-vertex colours (surface "lens"). Seen by day, a car's ends are told by these units, not by the small
    lit lenses."""
    if look.body_type not in HOUSING_BODIES:
        return None
    L, W = look.length_m, look.width_m
    (_, rear_high), (_, front_high) = _end_heights(look)
    half = W / 2 * PROFILES[look.body_type].end_width
    pieces = []
    head_w, head_h = HEADLAMP_UNIT_M
    head_top = min(head_z_m + head_h / 2, front_high - 0.02)
    rear_lamps = _rear_lamps_m(look, tail_z_m, rear_high)
    in_c, z_c, rear_w, rear_h = rear_lamps["cluster"]
    in_r, z_r, w_r, h_r = rear_lamps["reversing"]
    for s in (1, -1):
        head = _box((HOUSING_DEPTH_M, head_w, head_h), (L / 2, s * (half - head_w / 2), head_top - head_h / 2))
        rear = _box((HOUSING_DEPTH_M, rear_w, rear_h), (-L / 2, s * (half - in_c), z_c))
        reversing = _box((HOUSING_DEPTH_M + 0.008, w_r, h_r), (-L / 2, s * (half - in_r), z_r))
        pieces += [(head, HEADLAMP_UNIT_RGB), (rear, REAR_LENS_RGB), (reversing, REVERSING_LENS_RGB)]
    if shell_m is not None:
        pieces += [(top, HEADLAMP_UNIT_RGB) for top in _headlamp_tops(look, shell_m, half - head_w)]
    return _coloured_part("lamp_units", "lens", pieces)


HEADLAMP_TOP_DEPTH_M = 0.18
"""How far a headlamp unit reaches back over the nose from the front face, m: a current car's headlamps sit at the
bonnet's front corners and wrap up and back over the nose and onto the wing (a VW Golf 8's about 0.2 m in plan,
measured on the maker's top-view drawing; an estimate for the fleet)."""
HEADLAMP_TOP_WIDTH_M = 0.42
"""The most a headlamp unit's top spans across, from the shoulder inwards, m (the same drawing: about 0.4 m each,
the grille's width between them; an estimate for the fleet)."""
HEADLAMP_TOP_OFFSET_M = 0.004
"""How far out along the shell's normals a headlamp unit's top lies, m."""
HEADLAMP_TOP_NORMAL_Z = 0.5
"""The unit's top covers the shell's rows whose normals point up more than this (within 60° of the vertical): it
stops at the shoulder, where the surface turns down the side."""


def _headlamp_tops(
    look: VehicleLook, shell_m: tuple[np.ndarray, np.ndarray, np.ndarray], inner_m: float
) -> list[trimesh.Trimesh]:
    """Each headlamp unit's top: the shell's own faces over the nose at each front corner (`shell_m`: its vertices,
    normals and faces, `shell`), from the front face back `HEADLAMP_TOP_DEPTH_M`, across the rows that face up
    (`HEADLAMP_TOP_NORMAL_Z`) from the shoulder in by `HEADLAMP_TOP_WIDTH_M` but not past `inner_m` (the face's
    unit's inner edge), chosen at the patch's middle station so that its edges run along the mesh's rows and
    stations; lifted `HEADLAMP_TOP_OFFSET_M` along the normals. Its faces are the shell's, so no part of it dips
    under the paint."""
    vertices, normals, faces = shell_m
    count = UPPER_POINTS + LOWER_POINTS
    station_x = vertices[::count, 0]
    front = np.flatnonzero(station_x >= look.length_m / 2 - HEADLAMP_TOP_DEPTH_M)
    middle = front[np.argmin(np.abs(station_x[front] - (look.length_m - HEADLAMP_TOP_DEPTH_M) / 2))]
    at = vertices[middle * count : (middle + 1) * count]
    up = normals[middle * count : (middle + 1) * count, 2] > HEADLAMP_TOP_NORMAL_Z
    tops = []
    for side in (1.0, -1.0):
        y = side * at[:, 1]
        outer = y[up].max()
        rows = np.flatnonzero(up & (y >= max(inner_m, outer - HEADLAMP_TOP_WIDTH_M)))
        inside = np.isin(faces // count, front) & np.isin(faces % count, rows)
        patch = faces[inside.all(axis=1)]
        used, remapped = np.unique(patch, return_inverse=True)
        lifted = vertices[used] + HEADLAMP_TOP_OFFSET_M * normals[used]
        tops.append(trimesh.Trimesh(lifted, remapped.reshape(-1, 3), process=False))
    return tops


GRILLE_BODIES = ("hatchback", "sedan", "estate", "suv", "pickup", "van", "box_truck")
"""Body types with a radiator grille and a lower air intake at the front (a city bus's front is its
windscreen and a flat panel)."""
DIFFUSER_BODIES = ("hatchback", "sedan", "estate", "suv", "pickup")
"""Body types with a black lower rear bumper (a diffuser or valance: black grained plastic on most cars
since the 2010s, and a van's or truck's is a step or a bare chassis)."""
GRILLE_HEIGHT_M = 0.10
"""The upper grille's height between the head lamps, m; the lower intake runs from `INTAKE_BOTTOM_M` over the
bumper's lower edge up past the front plate (estimates from makers' front views: a Golf 8's upper grille
is a 0.1 m black band between its lamps, its lower intake about 0.2 m tall behind the plate)."""
INTAKE_BOTTOM_M = 0.04
INTAKE_SHARE = 0.70
"""The lower intake's width as a share of the front end's flat face."""
DIFFUSER_HEIGHT_M = 0.10
"""Height of the black lower rear bumper over the bumper's lower edge, m."""
UNDERRUN_GUARD_BODIES = ("box_truck",)
"""Body types with a rear underrun guard under a raised load floor (`Profile.rear_floor_m`): a horizontal bar on two
brackets from the chassis frame's two rails, black steel (UN Regulation No. 58)."""
GUARD_LOWER_EDGE_M = 0.50
"""Height of the underrun guard's lower edge over the road, unladen, m: UN R58 allows at most 550 mm (its 03 series
lowers the limit for some categories; 0.50 m is an estimate inside it)."""
GUARD_BAR_M = (0.08, 0.12)
"""Depth and height of the guard's bar, m (UN R58: a section at least 100 mm high; the depth an estimate)."""
GUARD_SETBACK_M = 0.15
"""How far the guard's rear face lies ahead of the rear end, m (UN R58: at most 400 mm, less in its 03 series)."""
GUARD_TYRE_INSET_M = 0.05
"""How far inside the rear tyres' outer faces the guard's ends lie, m (UN R58: at most 100 mm on each side)."""
FRAME_RAIL_M = (0.85, 0.07, 0.22)
"""A box truck's chassis frame under its floor: the two rails' outer width apart, each rail's width and depth, m (a
light truck's frame about 0.85 m wide and 0.2 m deep; an estimate)."""
REAR_BUMPER_BODIES = ("van",)
"""Body types with a rear bumper of unpainted black plastic across the rear end, a step in its top: a panel van's
(Transit, Sprinter, Crafter, Transporter: grained black polypropylene on the fleet trims, painted on a few top trims
only), its lower edge the rear end's lower edge (`Profile.departure_angle_deg`)."""
REAR_BUMPER_M = (0.10, 0.20)
"""Depth (half sunk, like the lamps) and height of a van's rear bumper, m (a Transit's or Sprinter's about 0.2 m
tall in makers' rear views; an estimate)."""
REAR_STEP_M = (0.20, 0.90, 0.04)
"""Depth, width and thickness of the step on a van's rear bumper's top, m: a tread across the middle standing out
0.05 m past the bumper's face, 0.10 m past the body (a Transit's or Sprinter's integrated step, about 0.9 m wide;
the 2015 Transit's "step bumper big enough for adult shoes", Ford Transit walk-around, foxcharlevoix.com; the
sizes an estimate)."""


def _black_trim(look: VehicleLook, head_z_m: float) -> list[trimesh.Trimesh]:
    """Black plastic on the ends, half sunk like the lamps: the radiator grille between the head lamps and the
    lower air intake round the front plate (`GRILLE_BODIES`), and the lower rear bumper under the rear plate
    (`DIFFUSER_BODIES`). Seen from ahead or behind, a car's ends show these dark bands, not one colour."""
    L, W = look.length_m, look.width_m
    (rear_low, _), (front_low, front_high) = _end_heights(look)
    half = W / 2 * PROFILES[look.body_type].end_width
    pieces = []
    if look.body_type in GRILLE_BODIES:
        grille_w = 2 * (half - 0.35)
        top = min(head_z_m + GRILLE_HEIGHT_M / 2, front_high - 0.02)
        pieces.append(_box((LAMP_DEPTH_M / 2, grille_w, GRILLE_HEIGHT_M), (L / 2, 0.0, top - GRILLE_HEIGHT_M / 2)))
        intake_top = min(front_low + 0.10 + PLATE_SIZE_M[1] + 0.04, top - GRILLE_HEIGHT_M - 0.04)
        bottom = front_low + INTAKE_BOTTOM_M
        if intake_top > bottom + 0.05:
            size = (LAMP_DEPTH_M / 2, INTAKE_SHARE * 2 * half, intake_top - bottom)
            pieces.append(_box(size, (L / 2, 0.0, (intake_top + bottom) / 2)))
    if look.body_type in DIFFUSER_BODIES:
        size = (LAMP_DEPTH_M / 2, 2 * (half - 0.04), DIFFUSER_HEIGHT_M)
        pieces.append(_box(size, (-L / 2, 0.0, rear_low + 0.01 + DIFFUSER_HEIGHT_M / 2)))
    if look.body_type in UNDERRUN_GUARD_BODIES:
        pieces += _underrun_guard(look) + _side_guards(look)
    if look.body_type in REAR_BUMPER_BODIES:
        depth, height = REAR_BUMPER_M
        step_depth, step_width, step_thickness = REAR_STEP_M
        # Its lower edge is the end face's (on the departure line at its rear face: `_bottom_m`).
        pieces.append(_box((depth, 2 * half, height), (-L / 2, 0.0, rear_low + height / 2)))
        step_z = rear_low + height - step_thickness / 2
        pieces.append(_box((step_depth, step_width, step_thickness), (-L / 2, 0.0, step_z)))
    return pieces


def _underrun_guard(look: VehicleLook) -> list[trimesh.Trimesh]:
    """A box truck's rear underrun guard and the frame that carries it under the raised floor
    (`UNDERRUN_GUARD_BODIES`): the two chassis rails from the cab's back to the guard, a bracket down from each
    to the guard's bar, and the bar across the rear tyres' span, its lower edge `GUARD_LOWER_EDGE_M` up."""
    L = look.length_m
    floor_m = PROFILES[look.body_type].rear_floor_m
    bar_depth, bar_height = GUARD_BAR_M
    frame_width, rail_width, rail_depth = FRAME_RAIL_M
    rail_y = frame_width / 2 - rail_width / 2
    bar_x = -L / 2 + GUARD_SETBACK_M + bar_depth / 2
    half_m = look.track_m / 2 + TYRE_WIDTH_SHARE * look.width_m / 2 - GUARD_TYRE_INSET_M
    bar_top = GUARD_LOWER_EDGE_M + bar_height
    front = floor_start_x_m(look)
    pieces = [_box((bar_depth, 2 * half_m, bar_height), (bar_x, 0.0, GUARD_LOWER_EDGE_M + bar_height / 2))]
    for side in (1, -1):
        rail_length = front - (bar_x - bar_depth / 2)
        pieces.append(
            _box(
                (rail_length, rail_width, rail_depth),
                (front - rail_length / 2, side * rail_y, floor_m + 0.01 - rail_depth / 2),
            )
        )
        bracket = floor_m - rail_depth - bar_top + 0.02
        pieces.append(_box((bar_depth, rail_width, bracket), (bar_x, side * rail_y, bar_top - 0.01 + bracket / 2)))
    return pieces


SIDE_GUARD_RAILS_M = ((0.45, 0.10), (0.75, 0.10))
"""A box truck's side guards (UN Regulation No. 73, lateral protection of N2 and N3 goods vehicles): each rail's
lower edge over the road and height, m. R73 asks the lower edge at most 550 mm up, rails at most 300 mm apart and
at least 50 mm high on an N2 vehicle (a 7.5 t truck), and the upper edge at most 350 mm under the body's structure
(here the floor, `BOX_FLOOR_M`): 0.45 m, 0.20 m apart, 0.10 m high, the upper edge 0.20 m under the floor (figures of
the Regulation as recalled, not rechecked here; the rails' sizes an estimate from bodybuilders' aluminium
guards)."""
SIDE_GUARD_DEPTH_M = 0.03
"""A side guard rail's depth across the vehicle, m (an aluminium extrusion; an estimate)."""
SIDE_GUARD_INSET_M = 0.08
"""How far inside the body's side the rails' outer faces lie, m (UN R73: at most 120 mm)."""
SIDE_GUARD_TYRE_GAP_M = 0.20
"""How far from the tyres ahead and behind the guards' ends lie, m (UN R73: at most 300 mm for an N2 vehicle)."""
SIDE_GUARD_POSTS = 3
"""Posts carrying each side's rails from the floor's cross members (evenly along them)."""
MUDGUARD_M = (0.25, 0.06, 0.02, 0.08)
"""A box truck's rear mudguards over the tyres under its floor: length beyond the tyre's diameter, width beyond the
tyre's, thickness, and height over the tyre's top, m (black plastic wings on brackets; an estimate from makers'
pictures of MAN TGL and Iveco Eurocargo box trucks)."""


def _side_guards(look: VehicleLook) -> list[trimesh.Trimesh]:
    """A box truck's lateral protection under its floor (`SIDE_GUARD_RAILS_M`): on each side two rails between the
    front and rear tyres on `SIDE_GUARD_POSTS` posts up to the floor, and a mudguard over each rear tyre."""
    floor_m = PROFILES[look.body_type].rear_floor_m
    r = look.wheel_radius_m
    front_m = look.front_axle_x_m - r - SIDE_GUARD_TYRE_GAP_M
    rear_m = look.rear_axle_x_m + r + SIDE_GUARD_TYRE_GAP_M
    outer_m = look.width_m / 2 - SIDE_GUARD_INSET_M
    y_m = outer_m - SIDE_GUARD_DEPTH_M / 2
    lowest_m = SIDE_GUARD_RAILS_M[0][0]
    tyre_m = TYRE_WIDTH_SHARE * look.width_m
    extra_length, extra_width, thickness, over = MUDGUARD_M
    pieces = []
    for side in (1, -1):
        for bottom, height in SIDE_GUARD_RAILS_M:
            size = (front_m - rear_m, SIDE_GUARD_DEPTH_M, height)
            pieces.append(_box(size, ((front_m + rear_m) / 2, side * y_m, bottom + height / 2)))
        for x in np.linspace(rear_m + 0.05, front_m - 0.05, SIDE_GUARD_POSTS):
            size = (0.05, SIDE_GUARD_DEPTH_M, floor_m + 0.01 - lowest_m)
            pieces.append(_box(size, (x, side * (y_m - SIDE_GUARD_DEPTH_M), (floor_m + 0.01 + lowest_m) / 2)))
        mudguard = (2 * r + extra_length, tyre_m + extra_width, thickness)
        pieces.append(_box(mudguard, (look.rear_axle_x_m, side * look.track_m / 2, 2 * r + over + thickness / 2)))
    return pieces


DESTINATION_SIGN_BODIES = ("bus",)
SIGN_PANEL_MARGIN_M = 0.03
"""Black border of the destination display's panel around its lit area, m."""


def destination_sign(look: VehicleLook) -> tuple[Part, Part]:
    """A bus's front destination display (`camgen.vehicles.sign`): (its black panel, half sunk into the
    front end like a plate's backing, surface "trim"; its lit LED dots, one quad per run of lit dots along
    a row, 5 mm in front of the panel, surface "destination"). The panel's top is the front end's
    `SIGN_TOP_SHARE` of the height, over the windscreen (`Profile.front_cap_glass`, which ends under it)."""
    from camgen.vehicles.sign import MATRIX_COLUMNS, MATRIX_ROWS, SIGN_SIZE_M, destination_text, lit_runs, matrix

    width_m, height_m = SIGN_SIZE_M
    top_m = SIGN_TOP_SHARE * look.height_m
    centre_z = top_m - SIGN_PANEL_MARGIN_M - height_m / 2
    x = look.length_m / 2
    panel = _box(
        (LAMP_DEPTH_M / 2, width_m + 2 * SIGN_PANEL_MARGIN_M, height_m + 2 * SIGN_PANEL_MARGIN_M),
        (x, 0.0, centre_z),
    )
    runs = lit_runs(matrix(*destination_text(look.identity_seed)))
    pitch_y, pitch_z = width_m / MATRIX_COLUMNS, height_m / MATRIX_ROWS
    gap_y, gap_z = (1 - DOT_FILL_SHARE) * pitch_y / 2, (1 - DOT_FILL_SHARE) * pitch_z / 2
    # Column 0 is the display's left as one reads it from in front: the vehicle's right (−y).
    y0 = -width_m / 2 + runs[:, 1] * pitch_y + gap_y
    y1 = -width_m / 2 + runs[:, 2] * pitch_y - gap_y
    z1 = centre_z + height_m / 2 - runs[:, 0] * pitch_z - gap_z
    z0 = z1 - pitch_z + 2 * gap_z
    front = x + LAMP_DEPTH_M / 4 + 0.005
    corners = np.stack([np.stack([np.full_like(y0, front), y, z], axis=1)
                        for y, z in ((y0, z0), (y1, z0), (y1, z1), (y0, z1))], axis=1)  # fmt: skip
    vertices = corners.reshape(-1, 3)
    faces = 4 * np.arange(len(runs))[:, None, None] + np.array([[0, 1, 2], [0, 2, 3]])  # counter-clockwise from +x
    dots = Part("destination_dots", "destination", vertices, np.tile((1.0, 0.0, 0.0), (len(vertices), 1)),
                faces.reshape(-1, 3), np.full(len(vertices), -1, np.int8))  # fmt: skip
    return _part("destination_panel", "trim", [(panel, -1)]), dots


SIGN_TOP_SHARE = 0.88
"""The destination display's top edge as a share of a bus's height: under the front end's rounded top
(`PROFILES["bus"]`: 0.895 at the front, 0.92 a hundredth of the length behind it), where the section is still
wide enough for the display."""
DOT_FILL_SHARE = 0.8
"""Share of a dot's pitch that its LED lights (the dark gaps between a matrix's dots)."""


SHADE_MARGIN_M = 0.03
"""How far inside the body's plan outline the shaded ground stops, m."""
SHADE_STATIONS = 24
"""Stations of the shaded ground along the vehicle (its outline follows the plan's rounded corners)."""


def plan_half_width_m(look: VehicleLook, x_m: np.ndarray) -> np.ndarray:
    """The body's half-width in plan at `x_m` (the vehicle's frame), m: the full half-width, narrowing to the
    flat ends' `end_width` over the rounded corners (`corner_share`; the shell's own plan, `shell`)."""
    profile = PROFILES[look.body_type]
    L, W = look.length_m, look.width_m
    d = np.minimum(x_m + L / 2, L / 2 - x_m)
    t = np.clip(d / (profile.corner_share * L), 0.0, 1.0)
    return W / 2 * (profile.end_width + (1 - profile.end_width) * np.sqrt(1 - (1 - t) ** 2))


def ground_shade(look: VehicleLook) -> Part:
    """The ground under the vehicle as the vehicle shades it (`GROUND_SHADE_RGB`): the whole footprint,
    `SHADE_MARGIN_M` inside the body's plan outline (`plan_half_width_m`), `GROUND_SHADE_Z_M` up, facing up,
    colours per vertex, surface "shade". Seen from behind or ahead, the ground under the overhangs shows
    below the bumper, and a real car's is dark there too: the floor and the bumper above it hide most of the
    sky. That ground is not the vehicle: the renderer writes it into the instance pass as background
    (`camgen.render.scene_graph.ShadeMaterial`), and the vehicle's box in an image leaves it out
    (`camgen.vehicles.VehicleRig.box_vertices_m`), so boxes and masks stay the body's and wheels'. It lies
    inside the plan outline, so the vehicle's extent in its own frame is the same with it or without."""
    L, r = look.length_m, look.wheel_radius_m
    inside_tyres = look.track_m / 2 - TYRE_WIDTH_SHARE * look.width_m / 2 - SHADE_MARGIN_M
    # Over each tyre's length the shade stops at the tyres' inner faces: 2 cm up, it would otherwise hide
    # the tyres' lowest 2 cm in a view from behind or ahead. Each end of a tyre's stretch is a station taken
    # twice, the shade's edge stepping there.
    spans = [(x0 - r - SHADE_MARGIN_M, x0 + r + SHADE_MARGIN_M) for x0 in (look.rear_axle_x_m, look.front_axle_x_m)]
    stations = np.linspace(-L / 2 + SHADE_MARGIN_M, L / 2 - SHADE_MARGIN_M, SHADE_STATIONS + 1)
    stations = np.unique(np.concatenate([stations, np.ravel(spans)]))
    xs, ys = [], []
    for x_m, plan_m in zip(stations, plan_half_width_m(look, stations) - SHADE_MARGIN_M, strict=True):
        inner_m = min(plan_m, inside_tyres)
        if any(np.isclose(x_m, start) for start, _ in spans):
            xs += [x_m, x_m]
            ys += [plan_m, inner_m]
        elif any(np.isclose(x_m, stop) for _, stop in spans):
            xs += [x_m, x_m]
            ys += [inner_m, plan_m]
        else:
            xs.append(x_m)
            ys.append(inner_m if any(start < x_m < stop for start, stop in spans) else plan_m)
    x, y = np.array(xs), np.maximum(np.array(ys), 0.0)
    z = np.full_like(x, GROUND_SHADE_Z_M)
    vertices = np.concatenate([np.stack([x, -y, z], axis=1), np.stack([x, y, z], axis=1)])
    n = len(x)
    k = np.arange(n - 1)
    # Counter-clockwise seen from above: (right k, right k + 1, left k + 1) and (right k, left k + 1, left k).
    faces = np.concatenate([np.stack([k, k + 1, n + k + 1], 1), np.stack([k, n + k + 1, n + k], 1)])
    return Part("ground_shade", "shade", vertices, np.tile((0.0, 0.0, 1.0), (len(vertices), 1)), faces,
                np.full(len(vertices), -1, np.int8), colours=np.tile(GROUND_SHADE_RGB, (len(vertices), 1)))  # fmt: skip


def underbody_faces(vertices_m: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F,) bool: which of `faces` face the ground (their normal's z below `UNDERBODY_NORMAL_Z`)."""
    corners = vertices_m[faces]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return n[:, 2] < UNDERBODY_NORMAL_Z * np.maximum(np.linalg.norm(n, axis=1), 1e-12)


ROOF_UNIT_BODIES = ("bus",)
"""Body types with an air-conditioning unit on the roof: every current city bus (Mercedes-Benz's Citaro: 3,076 mm
high with it, its roof about 0.2 m lower)."""
ROOF_UNIT_SPAN = (0.55, 0.80)
"""Where the unit lies along the roof, as shares of the length (rear 0, front 1): a Citaro's sits over the front
half, about 3 m long, over and behind the front axle (an estimate from makers' side views)."""
ROOF_UNIT_WIDTH_SHARE = 0.72
"""The unit's width over the vehicle's (about 1.8 m of a 2.55 m bus)."""


def roof_unit(look: VehicleLook) -> Part | None:
    """A bus's air-conditioning unit (`ROOF_UNIT_BODIES`): a box in the body's paint on the roof, from just under
    the roof (sunk 2 cm) up to the vehicle's height. Seen from above, a bus's roof shows it, not one flat colour."""
    if look.body_type not in ROOF_UNIT_BODIES:
        return None
    L, H = look.length_m, look.height_m
    roof_m = float(_interp_top(PROFILES[look.body_type], np.array([0.5]))[0]) * H
    (lo, hi), low_m = ROOF_UNIT_SPAN, roof_m - 0.02
    box = _box(
        ((hi - lo) * L, ROOF_UNIT_WIDTH_SHARE * look.width_m, H - low_m),
        (((lo + hi) / 2 - 0.5) * L, 0.0, (H + low_m) / 2),
    )
    box.update_faces(box.face_normals[:, 2] > -0.5)  # its bottom lies inside the roof: no paint faces the ground
    box.remove_unreferenced_vertices()
    return _part("roof_unit", "paint", [(box, -1)])


@dataclass(frozen=True)
class MirrorSpec:
    """A body type's exterior rear-view mirrors: how far each head reaches past the body's width, m, the
    head's height (z) and depth (x, fore and aft), m, and whether its housing is in the body's paint."""

    reach_m: float
    height_m: float
    depth_m: float
    painted: bool


MIRRORS: dict[str, MirrorSpec] = {
    **dict.fromkeys(("hatchback", "sedan", "estate", "suv", "pickup"), MirrorSpec(0.142, 0.15, 0.10, True)),
    "van": MirrorSpec(0.207, 0.32, 0.11, False),
    "box_truck": MirrorSpec(0.22, 0.36, 0.11, False),
    "bus": MirrorSpec(0.20, 0.38, 0.07, False),
}
"""Door mirrors by body type. A car's reach is a Volkswagen Golf 8's (width 1,789 mm, 2,073 mm with its
mirrors: 142 mm a side; makers' technical data), its head about 0.15 m tall and 0.1 m deep, in the body's paint
(most cars'); a large van's is a Ford Transit's (2,059 mm, 2,474 mm with mirrors: 207 mm a side), its head the
taller two-glass head of a commercial vehicle, black; a box truck's the same with a little more reach (an
estimate). A city bus carries its mirrors on arms ahead of the front corners, the heads hanging beside the
windscreen's upper half ("rabbit-ear" mirrors, as a Citaro's; reach and size are estimates from makers'
pictures). Widths without mirrors are `camgen.vehicles.look.BODY_TYPES`'."""
MIRROR_GLASS_RGB = (0.22, 0.23, 0.25)
"""Linear albedo the mirror glass is drawn with: a silvered glass reflects about half of what lies behind the
vehicle and to its side (ground and sky by day); drawn as a mid grey of the running gear (an estimate)."""
MIRROR_EXPONENT = 4.0
"""Superellipsoid exponent of a mirror's head: a box with rounded edges and corners."""
MIRROR_STALK_M = (0.05, 0.06)
"""Height and reach out of the door of the black stalk that carries a car's or van's mirror head, m (an estimate)."""
MIRROR_OVER_BELT_M = 0.03
"""A car's or van's mirror head's lower edge over the beltline, m (an estimate from makers' side views)."""
MIRROR_GLASS_SHARE = (0.82, 0.78)
"""The glass's share of the head's width and height seen from behind (the housing's rim round it; an estimate)."""
BUS_MIRROR_HEAD_WIDTH_M = 0.22
"""Width of a bus's mirror head across the bus, m (an estimate from makers' pictures)."""
BUS_MIRROR_DROP_M = 0.10
"""How far under the windscreen's top a bus's mirror head ends, m (an estimate from makers' pictures)."""
BUS_MIRROR_AHEAD_M = 0.30
"""How far ahead of a bus's front face its mirror heads hang, m (an estimate from makers' pictures)."""


def _rounded_box(size_m, centre_m, exponent: float = MIRROR_EXPONENT) -> trimesh.Trimesh:
    """A superellipsoid |x/a|ⁿ + |y/b|ⁿ + |z/c|ⁿ = 1 of the box `size_m` (2a, 2b, 2c) at `centre_m`: an icosphere's
    points pushed out along their directions onto it."""
    sphere = trimesh.creation.icosphere(subdivisions=2)
    d = np.asarray(sphere.vertices)
    r = np.sum(np.abs(d) ** exponent, axis=1) ** (-1.0 / exponent)
    vertices = d * r[:, None] * (np.asarray(size_m) / 2) + np.asarray(centre_m)
    return trimesh.Trimesh(vertices, np.asarray(sphere.faces), process=False)


def _side_skin_m(vertices_m: np.ndarray, x_m: float, z_m: float) -> float:
    """The shell's half-width at height `z_m` at the station nearest `x_m`, m: its section's points on the +y side,
    by height, interpolated (the section is convex, so its +y half is one width per height)."""
    stations = vertices_m[:, 0]
    nearest = stations[np.argmin(np.abs(stations - x_m))]
    side = vertices_m[(stations == nearest) & (vertices_m[:, 1] > 0)]
    order = np.argsort(side[:, 2])
    return float(np.interp(z_m, side[order, 2], side[order, 1]))


def door_mirrors(look: VehicleLook, vertices_m: np.ndarray) -> tuple[Part | None, Part | None]:
    """The exterior mirrors (`MIRRORS`): (the heads' housings in the body's paint, or None where they are black;
    the black housings, stalks and bus mirrors' arms and every mirror's glass as one part coloured per vertex, for
    the running gear); (None, None) for a body type without them. A car's or van's head sits at the front side
    window's lower front corner, its lower inner edge on the door's top (`vertices_m`, the shell's), out to
    `reach_m` past the body's width, carried by a black stalk from inside the door, its glass facing back; a bus's
    hangs on an arm ahead of each front corner. Seen from above, ahead or behind, the heads stand out of a
    vehicle's outline at the shoulders."""
    spec = MIRRORS.get(look.body_type)
    if spec is None:
        return None, None
    profile = PROFILES[look.body_type]
    L, W, H = look.length_m, look.width_m, look.height_m
    arms = []
    if look.body_type == "bus":
        x_m = L / 2 + BUS_MIRROR_AHEAD_M
        z_m = profile.front_cap_glass[1] * H - spec.height_m / 2 - BUS_MIRROR_DROP_M
        inner_m = W / 2 + spec.reach_m - BUS_MIRROR_HEAD_WIDTH_M
    else:
        x_m = (profile.side_glass[1] - 0.5) * L - spec.depth_m
        z_m = profile.belt * H + MIRROR_OVER_BELT_M + spec.height_m / 2
        # The head's lower inner edge on the door's top at the belt; a stalk of black plastic from inside the door
        # carries it (over the belt the side glass and the A-pillar lean in, away from the head, as on real cars).
        bottom_m = z_m - spec.height_m / 2
        door_m = _side_skin_m(vertices_m, x_m, bottom_m)
        inner_m = door_m - 0.02
        stalk = (0.06, MIRROR_STALK_M[1] + 0.06, MIRROR_STALK_M[0])  # from 6 cm inside the door's skin
        for s in (1, -1):
            arms.append(_box(stalk, (x_m, s * (door_m - 0.06 + stalk[1] / 2), bottom_m + 0.01)))
    outer_m = W / 2 + spec.reach_m
    housings, glass = [], []
    for s in (1, -1):
        centre = (x_m, s * (inner_m + outer_m) / 2, z_m)
        housings.append(_rounded_box((spec.depth_m, outer_m - inner_m, spec.height_m), centre))
        pane = (0.004, MIRROR_GLASS_SHARE[0] * (outer_m - inner_m), MIRROR_GLASS_SHARE[1] * spec.height_m)
        glass.append(_box(pane, (x_m - spec.depth_m / 2 - 0.001, centre[1], z_m)))
        if look.body_type == "bus":  # from the front face near its top, forward and out to the head's top
            start = (L / 2 - 0.05, s * (W / 2 - 0.25), SIGN_TOP_SHARE * H - 0.05)
            end = (x_m, centre[1], z_m + spec.height_m / 2 - 0.02)
            arms.append(trimesh.creation.cylinder(radius=0.025, segment=(start, end), sections=8))
    dark = [(mesh, MIRROR_GLASS_RGB) for mesh in glass] + [(mesh, TRIM_RGB) for mesh in arms]
    if not spec.painted:
        dark += [(mesh, TRIM_RGB) for mesh in housings]
    gear = _coloured_part("mirror_gear", "gear", dark)
    painted = _part("mirrors", "paint", [(mesh, -1) for mesh in housings], smooth=True) if spec.painted else None
    return painted, gear


def _windscreen_foot_m(vertices_m: np.ndarray, glass_faces: np.ndarray) -> float | None:
    """Where the windscreen's glass ends at the bonnet: the largest x of the glass faces ahead of the middle that face
    forward and up (a sloped windscreen, not an upright glazed front end), m; None without one."""
    corners = vertices_m[glass_faces]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    screen = (n[:, 0] > 0.35) & (n[:, 2] > 0.2) & (corners.mean(axis=1)[:, 0] > 0)
    return float(corners[screen][:, :, 0].max()) if screen.any() else None


def build_vehicle(look: VehicleLook, driver: bool = False) -> VehicleModel:
    """The vehicle of `look`, at rest in its own frame; `driver`: with its driver seated at the wheel
    (`camgen.vehicles.cabin`). The glass lets the cabin (its dark lining, and the driver) show through."""
    from camgen.vehicles.cabin import (
        bus_interior_part,
        bus_passengers_part,
        driver_part,
        glass_part,
        inner_glass_part,
        lining_part,
        seats_part,
    )
    from camgen.vehicles.panels import door_shut_lines, rear_details
    from camgen.vehicles.roof import roof_details

    vertices, faces, normals, kind = shell(look)
    paint = faces[kind == 0]
    below = underbody_faces(vertices, paint)
    used, remapped = np.unique(paint[~below], return_inverse=True)
    parts = [
        Part("body_paint", "paint", vertices[used], normals[used], remapped.reshape(-1, 3),
             np.full(len(used), -1, np.int8))
    ]  # fmt: skip
    unit = roof_unit(look)
    if unit is not None:
        parts.append(unit)
    painted_mirrors, mirror_gear = door_mirrors(look, vertices)
    if painted_mirrors is not None:
        parts.append(painted_mirrors)
    # The underbody and the black pillars: black plastic alike (`UNDERBODY_RGB`), one piece of the running gear.
    used, remapped = np.unique(np.concatenate([paint[below], faces[kind == 2]]), return_inverse=True)
    underbody = Part("underbody", "gear", vertices[used], normals[used], remapped.reshape(-1, 3),
                     np.full(len(used), -1, np.int8), colours=np.tile(UNDERBODY_RGB, (len(used), 1)))  # fmt: skip
    glazed = (kind == 1) | (kind == 3)
    if glazed.any():
        glass = glass_part(look, vertices, normals, faces[glazed], roof=kind[glazed] == 3)
        parts += [inner_glass_part(glass), glass]  # the far panes first (the renderer keeps the order)
    cabin = [lining_part(vertices, normals, faces[~glazed])]
    if look.body_type == "bus":  # its seats, and its passengers when it is in service (driven)
        cabin += [bus_interior_part(look)] + ([bus_passengers_part(look)] if driver else [])
    seats = seats_part(look)
    cabin += [seats] if seats is not None else []
    cabin += [driver_part(look)] if driver else []
    parts.append(_merge("cabin", "cabin", cabin))
    width_m = TYRE_WIDTH_SHARE * look.width_m
    tyre, rim = wheel_meshes(look.wheel_radius_m, width_m, RIM_SHARE[look.body_type])
    dark = [(tyre, w) for w in range(4)]
    if look.body_type in STEEL_DISC_BODIES:
        rim, holes = steel_disc_wheel_meshes(look.wheel_radius_m, width_m, RIM_SHARE[look.body_type])
        dark += [(hole, w) for w in range(4) for hole in holes]
    tyres = _merge("tyres", "gear", [_part("tyres", "gear", dark[:4], smooth=True)]
                   + ([_part("holes", "gear", dark[4:])] if len(dark) > 4 else []))  # fmt: skip
    rims = _part("rims", "gear", [(piece, w) for w in range(4) for piece in rim])
    lamps, plate_corners, plates, backings = lamps_and_plates(look, (vertices, normals, faces))
    if look.body_type in DESTINATION_SIGN_BODIES:
        panel, dots = destination_sign(look)
        backings = _merge("plate_backings", "trim", [backings, panel])
        lamps.append(dots)
    for piece, rgb in ((tyres, TYRE_RGB), (rims, RIM_RGB), (backings, TRIM_RGB)):
        piece.colours = np.tile(rgb, (len(piece.vertices_m), 1))
    # Each primitive costs a draw call per pass (the renderer's per-draw overhead dominates a vehicle's):
    # tyres, rims, plate backings and the underbody share one.
    gear = [tyres, rims, backings, underbody] + ([mirror_gear] if mirror_gear is not None else [])
    # What a car shows from above over its shell (`camgen.vehicles.roof`): its dark and silver pieces join the
    # running gear's draw; a body-coloured shark fin is a piece of paint of its own.
    details = roof_details(
        look, (vertices, normals, faces), _windscreen_foot_m(vertices, faces[kind == 1]),
        UPPER_POINTS, GREENHOUSE_SIDE_QUADS, UPPER_POINTS + LOWER_POINTS,
    )  # fmt: skip
    painted_fin = details.pop("fin_paint")
    dark_details = [piece for pieces in details.values() for piece in pieces]
    count = UPPER_POINTS + LOWER_POINTS
    dark_details += door_shut_lines(look, (vertices, normals, faces), count, UPPER_POINTS, GREENHOUSE_SIDE_QUADS)
    dark_details += rear_details(look, vertices, faces[kind == 1], count)
    if dark_details:
        gear.append(_coloured_part("roof_gear", "gear", dark_details))
    if painted_fin:
        parts.append(_part("roof_fin", "paint", [(mesh, -1) for mesh, _ in painted_fin], smooth=True))
    parts.append(_merge("running_gear", "gear", gear))
    parts += lamps + plates + [ground_shade(look)]
    return VehicleModel(look=look, parts=parts, wheel_centres_m=wheel_centres(look), plate_corners_m=plate_corners)
