"""A car's, van's, truck's or bus's cabin: the dark interior seen through its glass, the glass's
transmittance, and a seated driver.

Glass (`glass_transmittance`): the share of visible light each pane passes at normal incidence. In the UK
the windscreen must let at least 75 % of the light through and the front side windows at least 70 %
(GOV.UK, "Tinted vehicle windows: the law", under the Road Vehicles (Construction and Use) Regulations
1986); UN ECE Regulation 43 asks at least 70 % of the glazing the driver needs to see ahead. Clear
laminated windscreens pass about 78 % (78 % here), toughened side glass about 72 % (72 %). Behind the
driver no minimum applies: SUVs and vans usually carry factory "privacy" glass passing 20–30 % (25 %
here; makers' privacy glass is quoted at 15–26 %, e.g. engineerfix.com, "What percent tint do cars come with
from the factory"); other cars' rear glass is the side glass's. A glass roof (`ROOF_GLASS_T`) is darker still:
laminated with a tinted interlayer (Sekisui's S-LEC roof interlayers come in greys for any visible
transmittance a maker asks), it is the darkest glass of a car. The renderer draws glass (`glass_part`; its inner
faces, `inner_glass_part`, for a view through two panes) as the reflection its material gives plus the
transmitted share (1 − F) × T of what lies behind it, F the Fresnel reflectance (about 4 % per surface
at normal incidence, rising to 1 at grazing), so that the dark cabin lets the reflection dominate
(`camgen.render.scene_graph.GLASS_RGB`, the shader's TRANSMISSIVE_MATERIAL path).

Interior (`lining_part`): the shell's painted faces again, facing inwards, in a dark trim colour
(`INTERIOR_RGB`): the roof lining, door cards and floor as one dark surface, so that the glass shows a cabin
rather than the road through the car. It lies just inside the shell and faces inwards, so the vehicle's silhouette,
depth and instance mask are the shell's. In it stand a car's front seats and rear bench and a van's cab seats
(`seats_part`), their backs and head restraints seen through the side windows and from above.

Driver (`driver_part`): a procedural person (`camgen.actors`) drawn from the vehicle's identity seed,
always an adult without a bag, seated by `camgen.actors.driving` at the seat of the body type's package
(`SEATS`), on the right for a right-hand-drive vehicle (`drive_side`: a UK-format plate), decimated to
`DRIVER_FACES` triangles and rigid with the body (its vertices belong to the body, `Part.wheel` −1). It
is part of the vehicle's instance and is never annotated as a person of its own: MOT17 annotates only
people who are visible and not inside vehicles, and the driver is only seen through glass. It lies inside
the closed shell, so the vehicle's box and mask are the same with or without it.

A city bus's saloon (`bus_interior_part`): forward-facing pairs of seats on both sides at a seat pitch (`bus_rows`),
a gangway between them, a standing space opposite door 2, podiums over the wheel arches and yellow handrails,
seen through its large windows; in service (driven), 2–8 seated passengers (`bus_passengers_part`), procedural
people seated like the driver, hands on their laps. Like the driver they belong to the vehicle's instance and are
never annotated as people (MOT17's convention: people inside vehicles are not annotated), and they lie inside the
closed shell.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh

from camgen.actors.riding import HIP_ABOVE_SEAT_M
from camgen.vehicles.body import ARCH_GAP_M, PROFILES, Part, _bottom_m, _coloured_part, _interp_top
from camgen.vehicles.look import VehicleLook
from camgen.vehicles.plate import UK_PLATE_PATTERN

DRIVER_SPAWN_KEY = 0x6472_6976
"""Spawn key of a vehicle's driver's identity seed from the vehicle's (ASCII "driv")."""
DRIVER_FACES = 1200
"""Triangles of a driver (the person mesh has about 7000): the driver is seen small, through glass."""
INTERIOR_RGB = (0.035, 0.035, 0.038)
"""Linear albedo of the cabin's inside (dark grey plastics, fabric and carpet: 3–5 %)."""
DRIVER_LATERAL_SHARE = 0.205
"""The driver's seat centreline off the vehicle's centreline, as a share of the width (0.37 m of a
1.80 m car; 0.52 m of a 2.55 m bus)."""
LINING_INSET_M = 0.035
"""How far inside the shell the lining lies, m: behind the inner halves of the lamps sunk into the shell's
ends (`camgen.vehicles.body.LAMP_DEPTH_M` / 2), which would otherwise show inside the cabin."""
CLEARANCE_M = 0.07
"""Space the seat keeps between the driver's head and the roof, and the heels and the shell's underside, m."""
FOOTWELL_FROM_H_POINT_M = 0.25
"""The driver's legs farther than this ahead of the H-point and under the beltline are under the dashboard
and left out, m (the knees of a seated driver are 0.4–0.55 m ahead of the hips)."""
SEAT_STEP_M = 0.04
"""How far the seat slides back at a time while the legs would meet the shell's underside, m."""
SEAT_TRIES = 10

WINDSCREEN_T = 0.78
FRONT_SIDE_T = 0.72
PRIVACY_T = 0.25
PRIVACY_BODIES = ("suv", "van")
ROOF_GLASS_T = 0.10
"""Visible transmittance of a glass roof (`camgen.vehicles.roof`): an estimate. No maker's figure was found here;
panoramic roofs are laminated with a dark grey interlayer and look darker than the 15–26 % privacy glass beside
them in makers' pictures (and a car owner's measurement of a Cadillac Lyriq's rear glass, 17 %), so 10 %."""


@dataclass(frozen=True)
class Seat:
    """A body type's driver package, m and rad (SAE J1100 names: H5 the H-point's height above the
    ground, H30 above the heel point on the floor, A40 the back angle from the vertical)."""

    h_point_z_m: float
    """H5."""
    seat_height_m: float
    """H30: the H-point over the floor where the heels rest."""
    back_angle_rad: float
    """A40."""
    head_behind_windscreen_m: float
    """How far the head joint sits behind the windscreen's upper edge (a bus's: its front end), m."""


SEATS: dict[str, Seat] = {
    "hatchback": Seat(0.50, 0.27, math.radians(25.0), 0.12),
    "sedan": Seat(0.50, 0.26, math.radians(25.0), 0.12),
    "estate": Seat(0.50, 0.26, math.radians(25.0), 0.12),
    "suv": Seat(0.66, 0.33, math.radians(23.0), 0.12),
    "pickup": Seat(0.78, 0.33, math.radians(23.0), 0.0),
    "van": Seat(0.98, 0.40, math.radians(20.0), 0.15),
    "box_truck": Seat(1.45, 0.43, math.radians(18.0), 0.55),
    "bus": Seat(1.10, 0.45, math.radians(15.0), 1.00),
}
"""Driver packages per body type. H30 and A40 within SAE J1100's ranges for passenger cars (H30 about
0.25–0.30 m, A40 about 22–27°; "class A" vehicles) and for upright seating in vans, trucks and buses
(H30 0.35–0.45 m, A40 15–20°, "class B"). H5 are estimates from makers' package drawings: saloons and
hatchbacks put the H-point about 0.50 m above the ground, SUVs 0.6–0.7 m, pickups and vans 0.75–1.0 m,
a 7.5 t truck's cab about 1.4–1.5 m and a low-floor city bus's raised driver's seat about 1.1 m. The
seat's place along the vehicle follows the glass (`head_behind_windscreen_m`: the head in the front side
window, behind the windscreen; a double-cab pickup's at the header, so that its rear bench fits ahead of the cab's
back), which stands over the wheels as on real cars (`camgen.vehicles.proportions`): the cars' front H-points lie
1.1-1.4 m behind the front axle. The shell's wheel arches span its whole width, so the legs under the dashboard,
hidden there, are left out (`FOOTWELL_FROM_H_POINT_M`), and a rear bench keeps clear of the rear arches
(`seats_part`)."""


def drive_side(look: VehicleLook) -> str:
    """Which side the driver sits: "right" for a right-hand-drive vehicle (a UK-format plate,
    `camgen.vehicles.plate`), else "left" (a plate pinned in another format: most of the world drives
    left-hand-drive vehicles)."""
    return "right" if UK_PLATE_PATTERN.match(look.plate_text) else "left"


def glass_transmittance(
    look: VehicleLook, centre_m: np.ndarray, windscreen: np.ndarray, roof: np.ndarray | None = None
) -> np.ndarray:
    """(F,) visible transmittance of glass faces with centres `centre_m` (F, 3), `windscreen` (F,) bool:
    the windscreen's, the front side windows' (ahead of `driver_zone_x_m`), and behind them the rear
    glass's (privacy glass on SUVs and vans); `roof` (F,) bool: a glass roof's (`ROOF_GLASS_T`)."""
    front = centre_m[:, 0] > driver_zone_x_m(look)
    rear_t = PRIVACY_T if look.body_type in PRIVACY_BODIES else FRONT_SIDE_T
    panes = np.where(windscreen, WINDSCREEN_T, np.where(front, FRONT_SIDE_T, rear_t))
    return panes if roof is None else np.where(roof, ROOF_GLASS_T, panes)


WINDSCREEN_REACH_M = 0.1
"""How far behind the windscreen's band (`windscreen_x_m`) forward-facing glass still counts as the windscreen, m:
the band's edge lies in the roof's rounding over the header."""


def windscreen_x_m(look: VehicleLook) -> tuple[float, float]:
    """(upper edge, lower edge) of the windscreen along the vehicle, m (`camgen.vehicles.body.PROFILES`): a
    bus's upright windscreen is its front end."""
    profile = PROFILES[look.body_type]
    if profile.windscreen == (0.0, 0.0):
        return look.length_m / 2, look.length_m / 2
    return (profile.windscreen[0] - 0.5) * look.length_m, (profile.windscreen[1] - 0.5) * look.length_m


def driver_zone_x_m(look: VehicleLook) -> float:
    """Where the front side windows end: 0.45 m behind the driver's head (at the B-pillar)."""
    return windscreen_x_m(look)[0] - SEATS[look.body_type].head_behind_windscreen_m - 0.45


def _floor_m(look: VehicleLook, x_m: float, seat: Seat) -> float:
    """The height the heels rest at with the ball of the foot at `x_m`: H5 − H30, or `CLEARANCE_M` over the
    shell's underside under the foot where that is higher (over a wheel arch)."""
    arch = look.wheel_radius_m + ARCH_GAP_M
    foot = np.linspace(x_m - 0.25, x_m + 0.12, 8)
    axles = (look.front_axle_x_m, look.rear_axle_x_m)
    return max(seat.h_point_z_m - seat.seat_height_m, float(_bottom_m(look, foot, axles, arch).max()) + CLEARANCE_M)


def _roof_z_m(look: VehicleLook, x_m: float) -> float:
    return float(_interp_top(PROFILES[look.body_type], np.array([x_m / look.length_m + 0.5]))[0]) * look.height_m


def driver_appearance(look: VehicleLook):
    """The driver's look from the vehicle's identity seed: an adult (a child drawn is drawn again as an
    adult), no bag."""
    from camgen.actors.appearance import draw_appearance

    seed = int(np.random.SeedSequence(look.identity_seed, spawn_key=(DRIVER_SPAWN_KEY,)).generate_state(1)[0])
    appearance = draw_appearance(seed, pinned={"bag": "none"})
    if appearance.age_group == "child":
        appearance = draw_appearance(seed, pinned={"bag": "none", "age_group": "adult"})
    return appearance


def seated_driver(look: VehicleLook) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(vertices (V, 3), normals (V, 3), faces (F, 3), colours (V, 3)) of the vehicle's driver seated at
    its wheel, in the vehicle's frame, full detail: the head `head_behind_windscreen_m` behind the
    windscreen, the hands on the wheel, the feet on pedals where the legs reach them. The legs under the dashboard
    (`FOOTWELL_FROM_H_POINT_M` ahead of the H-point, under the beltline) are left out: hidden there in any
    view, and where the shell's wheel arches, which span its whole width (a real footwell lies between
    them), would meet them. The seat drops by as much as the head would come within `CLEARANCE_M` of the
    roof, and slides back `SEAT_STEP_M` at a time while what is left comes within `CLEARANCE_M` of the
    shell's underside (up or along)."""
    from camgen.actors.driving import Controls, pedal_x_m, seated_joints_m, seated_vertices, steering_wheel_m
    from camgen.actors.person import build_person
    from camgen.actors.skeleton import INDEX

    model = build_person(driver_appearance(look))
    seat = SEATS[look.body_type]
    side = -1.0 if drive_side(look) == "right" else 1.0  # y points left
    y = side * DRIVER_LATERAL_SHARE * look.width_m
    head_x = windscreen_x_m(look)[0] - seat.head_behind_windscreen_m
    h_z = seat.h_point_z_m
    hip_y = abs(float(model.joints_m[INDEX["thigh_l"], 1]))
    axles, arch = (look.front_axle_x_m, look.rear_axle_x_m), look.wheel_radius_m + ARCH_GAP_M
    belt_z = PROFILES[look.body_type].belt * look.height_m
    for _ in range(SEAT_TRIES):
        origin = np.array([0.0, y, h_z])
        back = head_x - seated_joints_m(model, origin, seat.back_angle_rad)[INDEX["head"], 0]
        h_point = origin + np.array([back, 0.0, 0.0])
        floor_z = _floor_m(look, pedal_x_m(model, h_point, h_z - seat.seat_height_m), seat)
        pedal_x = pedal_x_m(model, h_point, floor_z)
        floor_z = _floor_m(look, pedal_x, seat)
        _, grips = steering_wheel_m(model, h_point, seat.back_angle_rad)
        feet = np.array([[pedal_x, y + hip_y, floor_z], [pedal_x, y - hip_y, floor_z]])
        vertices, normals = seated_vertices(model, Controls(h_point, grips, feet), seat.back_angle_rad)
        footwell = (vertices[:, 0] > h_point[0] + FOOTWELL_FROM_H_POINT_M) & (vertices[:, 2] < belt_z - 0.05)
        kept = vertices[~footwell]
        top = int(np.argmax(kept[:, 2]))
        excess = float(kept[top, 2]) - (_roof_z_m(look, float(kept[top, 0])) - CLEARANCE_M)
        steps = CLEARANCE_M * np.array([-1.0, 0.0, 1.0])
        underside = np.max([_bottom_m(look, kept[:, 0] + dx, axles, arch) for dx in steps], axis=0)
        low = float(np.max(underside + CLEARANCE_M - kept[:, 2]))
        if excess <= 0 and low <= 0:
            break
        h_z -= max(excess, 0.0)
        head_x -= SEAT_STEP_M if low > 0 else 0.0
    faces = np.asarray(model.faces)
    faces = faces[~footwell[faces].any(axis=1)]
    used, remapped = np.unique(faces, return_inverse=True)
    colours = np.asarray(model.colours[used, :3], dtype=np.float64)
    return (vertices[used].astype(np.float64), normals[used].astype(np.float64), remapped.reshape(-1, 3), colours)


def driver_part(look: VehicleLook) -> Part:
    """The seated driver (`seated_driver`) decimated to about `DRIVER_FACES` triangles, as a part of the
    body with per-vertex colours (surface "cabin")."""
    vertices, _, faces, colours = seated_driver(look)
    return _seated_person_part("driver", vertices, faces, colours)


def _seated_person_part(name: str, vertices_m: np.ndarray, faces: np.ndarray, colours: np.ndarray) -> Part:
    """A person seated in the vehicle (vertices (V, 3) in its frame, faces, colours (V, 3)) decimated to about
    `DRIVER_FACES` triangles, as a part of the body (`Part.wheel` −1) with per-vertex colours (surface "cabin"):
    seen small, through glass."""
    from camgen.actors.person import decimate

    unused = np.zeros((len(vertices_m), 4))
    fraction = min(1.0, DRIVER_FACES / len(faces))
    vertices, faces, colours, _, _ = decimate(vertices_m, faces, colours, unused.astype(np.int64), unused, fraction)
    normals = trimesh.Trimesh(vertices, faces, process=False).vertex_normals
    return Part(name, "cabin", vertices, np.asarray(normals), faces, np.full(len(vertices), -1, np.int8),
                colours=colours)  # fmt: skip


def lining_part(vertices_m: np.ndarray, normals: np.ndarray, paint_faces: np.ndarray) -> Part:
    """The shell's painted faces turned inwards (reversed winding and normals), `LINING_INSET_M` inside it,
    coloured `INTERIOR_RGB`."""
    used, remapped = np.unique(paint_faces, return_inverse=True)
    faces = remapped.reshape(-1, 3)[:, ::-1]
    inset = vertices_m[used] - LINING_INSET_M * normals[used]
    return Part("interior", "cabin", inset, -normals[used], np.ascontiguousarray(faces),
                np.full(len(used), -1, np.int8), colours=np.tile(INTERIOR_RGB, (len(used), 1)))  # fmt: skip


def glass_part(
    look: VehicleLook, vertices_m: np.ndarray, normals: np.ndarray, faces: np.ndarray, roof: np.ndarray | None = None
) -> Part:
    """The shell's glass faces with their own vertices (each face's transmittance exact), coloured (1, 1, 1,
    1 − T): the opacity the renderer blends with (`glass_transmittance`). The windscreen is the glass
    facing forward up to its top edge (`windscreen_x_m`; a saloon's reaches back past the vehicle's middle);
    `roof` (F,) bool marks a glass roof's faces."""
    corners = faces.reshape(-1)
    centre = vertices_m[faces].mean(axis=1)
    windscreen = (normals[faces].mean(axis=1)[:, 0] > 0.35) & (
        centre[:, 0] > windscreen_x_m(look)[0] - WINDSCREEN_REACH_M
    )
    transmittance = glass_transmittance(look, centre, windscreen, roof)
    colours = np.ones((len(corners), 4))
    colours[:, 3] = np.repeat(1.0 - transmittance, 3)
    return Part("body_glass", "glass", vertices_m[corners], normals[corners], np.arange(len(corners)).reshape(-1, 3),
                np.full(len(corners), -1, np.int8), colours=colours)  # fmt: skip


def inner_glass_part(glass: Part) -> Part:
    """The glass's inner faces (reversed winding and normals): a window seen from inside the cabin, through
    another (the far side's), which the outer faces, facing away, do not draw; drawn before the outer
    glass, it lets a view through two panes pass T² of what lies beyond."""
    faces = np.ascontiguousarray(glass.faces[:, ::-1])
    return Part(
        "body_glass_inside", "glass", glass.vertices_m, -glass.normals, faces, glass.wheel, colours=glass.colours
    )


SEAT_BODIES = ("hatchback", "sedan", "estate", "suv", "pickup", "van")
"""Body types whose seats are drawn (`seats_part`): a car's two front seats and rear bench, a van's cab seats."""
SEAT_RGB = (0.04, 0.04, 0.042)
"""Linear albedo of the seats' upholstery: black or anthracite cloth or leather, most cars' (an estimate)."""
SEAT_CUSHION_M = (0.50, 0.50, 0.12)
"""A front seat's cushion: depth, width and thickness, m (a car seat's cushion 0.45–0.55 m deep and wide)."""
SEAT_BACK_M = (0.55, 0.10)
"""A seat back's height from the cushion and thickness, m (the torso's support up to the shoulders: 0.5–0.65 m)."""
HEADREST_M = (0.26, 0.20, 0.10, 0.05)
"""A head restraint's width, height, thickness and gap over the seat back, m (UN Regulation No. 17: at least 0.17 m
wide; its top at least 0.80 m over the H-point along the back in its highest position and 0.75 m in its lowest, for
front seats; modelled in the lowest: the built front restraints' tops stand 0.77-0.79 m up; the sizes an estimate)."""
HEAD_ABOVE_H_POINT_M = 0.75
"""The head's centre over the H-point along the torso, m (SAE J826's manikin with a 50th-percentile head: an
estimate); with the back angle it places the seat behind the driver's head (`SEATS`)."""
COUPLE_DISTANCE_M = 0.80
"""Front to rear H-point along the car, m (SAE J1100's L50 "couple distance": about 0.75–0.95 m in small to large
cars; an estimate in that range)."""
REAR_SEAT_RISE_M = 0.03
"""How much higher the rear bench's H-point lies than the front seats', m (an estimate: rear seats are raised a
little for the view ahead)."""


def _seat_pieces(
    h_point_m: np.ndarray, width_m: float, back_angle_rad: float, roof_m: float, headrests: list[float], front_m: float
):
    """A seat's cushion, back and head restraints (at the lateral offsets `headrests` from its middle, m) for an
    H-point `h_point_m` (x, y, z): the back's front face `H_POINT_BEFORE_BACK_M` behind it, leaning back by
    `back_angle_rad`, the restraints kept `CLEARANCE_M` under the roof `roof_m`, the cushion ending at `front_m` at
    the most (clear of the front wheel arches, which span the shell's width); boxes in the vehicle's frame."""
    x, y, z = h_point_m
    depth, _, thickness = SEAT_CUSHION_M
    depth = min(depth, front_m - (x - H_POINT_BEFORE_BACK_M))
    back_height, back_thickness = SEAT_BACK_M
    rest_w, rest_h, rest_t, rest_gap = HEADREST_M
    lean = np.array([-math.sin(back_angle_rad), 0.0, math.cos(back_angle_rad)])  # up the back
    behind = np.array([-math.cos(back_angle_rad), 0.0, -math.sin(back_angle_rad)])  # through it, rearwards
    foot = np.array([x - H_POINT_BEFORE_BACK_M, y, z - 0.08])  # the back's front face meets the cushion's top
    # The back and the restraints shrink (the restraints first drop) as the roof asks.
    top_room = roof_m - CLEARANCE_M - foot[2]
    back_height = min(back_height, max(top_room / math.cos(back_angle_rad) - rest_gap - rest_h, 0.3))
    pieces = []
    cushion = trimesh.creation.box((depth, width_m, thickness))
    cushion.apply_translation((foot[0] + depth / 2, y, foot[2] - thickness / 2))
    pieces.append(cushion)

    def slab(size, centre):
        box = trimesh.creation.box(size)
        box.apply_transform(trimesh.transformations.rotation_matrix(-back_angle_rad, (0.0, 1.0, 0.0)))
        box.apply_translation(centre)
        return box

    pieces.append(
        slab((back_thickness, width_m, back_height), foot + lean * back_height / 2 + behind * back_thickness / 2)
    )
    for offset in headrests:
        centre = foot + lean * (back_height + rest_gap + rest_h / 2) + behind * rest_t / 2 + np.array([0, offset, 0])
        pieces.append(slab((rest_t, rest_w, rest_h), centre))
    return [(piece, SEAT_RGB) for piece in pieces]


def seats_part(look: VehicleLook) -> Part | None:
    """The seats seen through the glass (`SEAT_BODIES`): two front seats (a van's driver's seat and a two-seat bench)
    behind the driver's head (`SEATS`: the head `head_behind_windscreen_m` behind the windscreen, the back at A40),
    and on a car a rear bench `COUPLE_DISTANCE_M` further back (nearer where that keeps it clear of the rear wheel
    arches, which span the shell's width: the smallest hatchbacks', down to about 0.6 m) with two head restraints,
    as one part of the cabin;
    None for other body types. A cabin was its dark lining alone: through the side windows the far windows showed,
    from above an empty tub."""
    if look.body_type not in SEAT_BODIES:
        return None
    seat = SEATS[look.body_type]
    head_x = windscreen_x_m(look)[0] - seat.head_behind_windscreen_m
    h_x = head_x + HEAD_ABOVE_H_POINT_M * math.sin(seat.back_angle_rad)
    lateral = DRIVER_LATERAL_SHARE * look.width_m
    width_m = SEAT_CUSHION_M[1]
    front_m = look.front_axle_x_m - look.wheel_radius_m - ARCH_GAP_M - CLEARANCE_M
    pieces = []
    for y in (lateral, -lateral):
        roof = _roof_z_m(look, h_x - 0.4)
        h_point = np.array([h_x, y, seat.h_point_z_m])
        pieces += _seat_pieces(h_point, width_m, seat.back_angle_rad, roof, [0.0], front_m)
    if look.body_type != "van":
        # Clear of the rear wheel arches, which span the shell's width (a real bench sits between them): a small
        # hatchback's couple distance shrinks.
        arch_front = look.rear_axle_x_m + look.wheel_radius_m + ARCH_GAP_M
        rear_x = max(h_x - COUPLE_DISTANCE_M, arch_front + H_POINT_BEFORE_BACK_M + SEAT_BACK_M[1] + CLEARANCE_M)
        bench = 2 * lateral + width_m
        roof = _roof_z_m(look, rear_x - 0.4)
        h_point = np.array([rear_x, 0.0, seat.h_point_z_m + REAR_SEAT_RISE_M])
        pieces += _seat_pieces(h_point, bench, seat.back_angle_rad, roof, [lateral, -lateral], front_m)
    return _coloured_part("seats", "cabin", pieces)


BUS_FLOOR_M = 0.37
"""A low-floor city bus's floor over the road, m (Mercedes-Benz Citaro: 370 mm at the doors)."""
BUS_SEAT_PITCH_M = 0.78
"""Distance between rows of a city bus's forward-facing seats, m: 0.75–0.8 m in makers' seating plans (UN
Regulation 107 asks at least 0.65 m between a seat back and the one in front in class I)."""
BUS_SEAT_M = (0.45, 0.44, 0.50, 0.44)
"""A bus seat's cushion height over the floor, the cushion's depth, its back's height over the cushion and each
seat's width, m (UN Regulation 107 Annex 3: a seat at least 0.40 m wide, its cushion 0.40–0.50 m over the
floor; 0.44 m wide leaves a 2.45–2.55 m bus a gangway of 0.49–0.59 m between its pairs (`BUS_WALL_INSET_M`);
R107 gauges a class I gangway with a cylinder about 0.45 m across (Annex 4, figure 6; quoted from memory, not
checked); the back's height, an estimate of current city-bus seats' about 0.5 m)."""
SEAT_BACK_THICKNESS_M = 0.08
"""A bus seat back's thickness, m (a moulded shell with its padding; an estimate)."""
BUS_WALL_INSET_M = 0.10
"""How far inside a bus's width its saloon's side walls are, m: the body's skin, the lining and the window frames
(an estimate: a Citaro is 2.55 m wide outside and about 2.35 m inside at seat height)."""
BUS_SEAT_RGB = (0.02, 0.03, 0.07)
"""Linear albedo of the seats: dark blue moquette, the commonest city-bus trim (an estimate)."""
HANDRAIL_RGB = (0.60, 0.33, 0.01)
"""Linear albedo of the vertical handrails: signal yellow (RAL 1003), the colour UN R107 and the UK's PSVAR 2000
have handrails contrast in (sRGB about (249, 168, 0); as a paint's albedo an estimate)."""
HANDRAIL_RADIUS_M = 0.0175
"""A handrail's radius, m: 35 mm tubes (UN R107 asks handholds 20–45 mm across)."""
BUS_AISLE_STANDING = (0.44, 0.62)
"""The stretch along a bus (shares of the length, rear 0 → front 1) opposite door 2 kept free of seats: the
wheelchair and pushchair space UN R107 Annex 8 asks for (an estimate of its extent)."""


def bus_rows(look: VehicleLook) -> list[tuple[int, float, float]]:
    """A city bus's rows of seats: (the row's number from the front, its cushion's centre along the bus, the floor it
    stands on), m. From behind the front door's stairwell to the rear, `BUS_SEAT_PITCH_M` apart, none in the standing
    space opposite door 2 (`BUS_AISLE_STANDING`); a row over a wheel arch, its legroom included, stands on a podium
    over it (the shell's underside rises there)."""
    L = look.length_m
    depth_m = BUS_SEAT_M[1]
    front_door_u = min(u0 for u0, _ in PROFILES["bus"].doors if u0 > 0.7)
    first_m = (front_door_u - 0.5) * L - 0.9
    standing = [(u - 0.5) * L for u in BUS_AISLE_STANDING]
    axles, arch_m = (look.front_axle_x_m, look.rear_axle_x_m), look.wheel_radius_m + ARCH_GAP_M
    rows = []
    for k, x_m in enumerate(np.arange(first_m, -L / 2 + 0.6, -BUS_SEAT_PITCH_M)):
        if standing[0] < x_m < standing[1]:
            continue
        # The floor under the seat and its legroom, up to the row ahead's seat back.
        reach = np.linspace(x_m - depth_m / 2 - 0.25, x_m + BUS_SEAT_PITCH_M - depth_m / 2, 13)
        under = _bottom_m(look, reach, axles, arch_m)
        rows.append((k, float(x_m), max(BUS_FLOOR_M, float(under.max()) + CLEARANCE_M)))
    return rows


def _bus_wall_m(look: VehicleLook) -> float:
    """The saloon's side walls' inside, off the centreline, m: behind the lining and the window frames."""
    return look.width_m / 2 - BUS_WALL_INSET_M


def bus_interior_part(look: VehicleLook) -> Part:
    """A city bus's passenger saloon, seen through its windows: forward-facing pairs of seats along both sides
    from behind the front door to the rear (`BUS_SEAT_PITCH_M`), none in the standing space opposite door 2
    (`BUS_AISLE_STANDING`), and a yellow vertical handrail from the floor to the roof at the aisle end of every
    other row, each on the floor or on a podium over a wheel arch; one part of per-vertex colours (surface "cabin"),
    inside the closed shell."""
    cushion_m, depth_m, back_m, seat_w_m = BUS_SEAT_M
    wall_m = _bus_wall_m(look)
    roof_m = _roof_z_m(look, 0.0) - LINING_INSET_M - 0.02
    pieces = []
    for k, x_m, floor_m in bus_rows(look):
        for s in (1, -1):
            y_m = s * (wall_m - seat_w_m)  # the pair's middle
            cushion = trimesh.creation.box((depth_m, 2 * seat_w_m, 0.12))
            cushion.apply_translation((x_m, y_m, floor_m + cushion_m - 0.06))
            back = trimesh.creation.box((SEAT_BACK_THICKNESS_M, 2 * seat_w_m, back_m))
            back.apply_translation((x_m - depth_m / 2, y_m, floor_m + cushion_m + back_m / 2))
            pieces += [(cushion, BUS_SEAT_RGB), (back, BUS_SEAT_RGB)]
            if k % 2 == 0:
                pole = trimesh.creation.cylinder(HANDRAIL_RADIUS_M, roof_m - floor_m, sections=8)
                pole.apply_translation(
                    (x_m - depth_m / 2 - 0.1, s * (wall_m - 2 * seat_w_m - HANDRAIL_RADIUS_M), (roof_m + floor_m) / 2)
                )
                pieces.append((pole, HANDRAIL_RGB))
    return _coloured_part("bus_saloon", "cabin", pieces)


PASSENGER_SPAWN_KEY = 0x7061_7373
"""Spawn key of a bus's passengers' draws from the vehicle's identity seed (ASCII "pass")."""
BUS_PASSENGERS = (2, 8)
"""Fewest and most seated passengers a bus in service carries, drawn uniformly (an estimate: a 12 m city bus seats
26–32; off-peak buses run a quarter full or less, and the standing are not drawn)."""
PASSENGER_BACK_ANGLE_RAD = math.radians(12.0)
"""A seated passenger's back angle from the vertical (a city bus's seat backs are upright: about 10–15°)."""
LAP_FROM_H_POINT_M = (0.25, 0.13, 0.10)
"""Where a seated passenger's hands rest on the thighs: ahead of the H-point, to either side and up, m (an estimate
from a seated adult's thigh length, about 0.45–0.6 m)."""
FOOT_ROOM_M = 0.15
"""How far the balls of a seated passenger's feet stay behind the seat back ahead, m (the toes ahead of them)."""
H_POINT_BEFORE_BACK_M = 0.14
"""The H-point's distance ahead of the seat back's front face, m (SAE J826's manikin: about 0.13–0.14 m)."""


def _passenger(look: VehicleLook, seed: int, h_point_m: np.ndarray, floor_m: float, toe_room_m: float) -> Part:
    """One seated passenger (`camgen.actors`' procedural person of appearance seed `seed`, any age, no bag): hips at
    `h_point_m`, back at `PASSENGER_BACK_ANGLE_RAD`, hands on the thighs, feet flat on the floor at `floor_m`, the
    balls of the feet no further forward than `toe_room_m`; decimated to `DRIVER_FACES`, per-vertex colours."""
    from camgen.actors.appearance import draw_appearance
    from camgen.actors.driving import Controls, pedal_x_m, seated_vertices
    from camgen.actors.person import build_person
    from camgen.actors.skeleton import INDEX

    model = build_person(draw_appearance(seed, pinned={"bag": "none"}))
    hip_y = abs(float(model.joints_m[INDEX["thigh_l"], 1]))
    x, y, z = h_point_m
    feet_x = min(pedal_x_m(model, h_point_m, floor_m), toe_room_m)
    feet = np.array([[feet_x, y + hip_y, floor_m], [feet_x, y - hip_y, floor_m]])
    ahead_m, apart_m, up_m = LAP_FROM_H_POINT_M
    laps = np.array([[x + ahead_m, y + apart_m, z + up_m], [x + ahead_m, y - apart_m, z + up_m]])
    vertices, _ = seated_vertices(model, Controls(np.asarray(h_point_m), laps, feet), PASSENGER_BACK_ANGLE_RAD)
    colours = np.asarray(model.colours[:, :3], dtype=np.float64)
    return _seated_person_part("passenger", vertices, np.asarray(model.faces), colours)


def bus_passengers_part(look: VehicleLook) -> Part:
    """A bus in service's seated passengers (`BUS_PASSENGERS` of them, on seats of `bus_rows` drawn without
    replacement from the vehicle's identity seed), each `_passenger`, as one part of the cabin. Like the driver,
    they are part of the vehicle's instance and never annotated as people: they are seen only through glass."""
    from camgen.vehicles.body import _merge

    rng = np.random.default_rng(np.random.SeedSequence(look.identity_seed, spawn_key=(PASSENGER_SPAWN_KEY,)))
    cushion_m, depth_m, _, seat_w_m = BUS_SEAT_M
    wall_m = _bus_wall_m(look)
    seats = [
        (x_m, side * (wall_m - seat_w_m * (0.5 + inner)), floor_m)
        for _, x_m, floor_m in bus_rows(look)
        for side in (1, -1)
        for inner in (0, 1)
    ]
    count = int(rng.integers(BUS_PASSENGERS[0], BUS_PASSENGERS[1] + 1))
    chosen = rng.choice(len(seats), size=min(count, len(seats)), replace=False)
    seeds = rng.integers(0, 2**32, size=len(chosen))
    passengers = []
    for index, seed in zip(sorted(chosen), seeds, strict=True):
        x_m, y_m, floor_m = seats[index]
        back_face_m = x_m - depth_m / 2 + SEAT_BACK_THICKNESS_M / 2
        h_point = np.array([back_face_m + H_POINT_BEFORE_BACK_M, y_m, floor_m + cushion_m + HIP_ABOVE_SEAT_M])
        # The seat back of the row ahead (its rear face) bounds the feet; a hand's breadth short of it.
        toe_room_m = x_m + BUS_SEAT_PITCH_M - depth_m / 2 - SEAT_BACK_THICKNESS_M / 2 - FOOT_ROOM_M
        passengers.append(_passenger(look, int(seed), h_point, floor_m, toe_room_m))
    return _merge("passengers", "cabin", passengers)
