"""What a car shows from above beyond its painted shell: a glass roof, roof rails, a shark-fin antenna, the black
cowl and wipers at the windscreen's foot and the bonnet's shut lines, in the vehicle's frame (`camgen.vehicles.body`).

Seen from a pole or a 6–10 m mast a car is mostly its roof, bonnet and screens, and a real one is not one colour
there: a share of recent cars carry a tinted glass roof over both rows of seats, estates and SUVs roof rails along
the roof's edges, most cars a shark-fin antenna at the roof's rear, every car a black plastic cowl (the scuttle
panel over the heater's air intake) between the bonnet and the windscreen with the wipers parked on it, and the
bonnet's edges show as dark shut lines (the 3–5 mm gaps between panels) inboard of the wings. Which of these a car
has is drawn from its identity seed (`roof_kit`), so it keeps them in every frame and camera.

Sources and estimates:

- Glass roofs (`GLASS_ROOF_SHARE`): no European fleet statistic was found. JATO Dynamics India put sunroofs
  (tilt-and-slide and panoramic) on 26 % of India's new cars in 2023 (4.6 % in 2018; reported by News9/TOI, July
  2023), and Ford reported almost half of its 2011 Explorer and Edge buyers choosing its panoramic "Vista Roof"
  (LA Times via AutoGuide, August 2011). The shares here are estimates in that range, higher for SUVs and
  estates (where makers list panoramic roofs most), lower for small hatchbacks and pickups. A panoramic roof's glass
  starts just behind the windscreen's header and is about 0.8–1.3 m long (makers' option pictures: Peugeot 3008,
  VW Tiguan, Skoda Octavia Combi), spanning the roof between its edge rails (`GLASS_ROOF_LENGTH_M`).
- Roof rails (`ROOF_RAIL_SHARE`): standard on most trims of current estates and SUVs in makers' price lists
  (Skoda Octavia Combi, VW Passat Variant, Nissan Qashqai, Kia Sportage: silver or black anodised aluminium),
  hence 70 % here (an estimate); a rail is about 30 mm wide and stands 40–60 mm over the roof
  (`RAIL_SIZE_M`, an estimate from makers' pictures).
- Shark-fin antennas (`SHARK_FIN_SHARE`): the roof antenna of most cars built since the mid-2010s (they house the
  GNSS, cellular and radio antennas in one module), about 0.2 m long, 0.07 m wide and 0.065 m tall
  (`SHARK_FIN_M`; an estimate from OEM and aftermarket part listings), at the roof's rear centre; 85 % of cars
  here, body-coloured on 60 % of them (estimates).
- The cowl (`COWL_DEPTH_M`): black grained plastic 0.10–0.15 m deep across the car's width at the windscreen's
  foot (an estimate from makers' pictures); wipers (`WIPER_LENGTHS_M`) as the blade lengths of Bosch's
  application lists for a VW Golf 8 (600 and 450 mm) and common vans (650 and 650 mm), parked along the
  screen's foot.
- Shut lines (`SHUT_LINE_WIDTH_M`): panel gaps of 3–5 mm (makers' gap-and-flush specifications run 3.5–4.5 mm),
  dark because the gap's depth hides the light: drawn as 6 mm dark ribbons so that a pixel of about 1 cm on a
  car 7 m away still shows them as a faint line, as a photograph does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from camgen.vehicles.look import VehicleLook

ROOF_SPAWN_KEY = 0x726F_6F66
"""Spawn key of a vehicle's roof kit's draws from its identity seed (ASCII "roof")."""
CAR_BODIES = ("hatchback", "sedan", "estate", "suv", "pickup")
GLASS_ROOF_SHARE = {"hatchback": 0.15, "sedan": 0.20, "estate": 0.30, "suv": 0.40, "pickup": 0.10}
"""Share of each body type with a tinted glass roof (panoramic or a large sunroof); estimates (module docstring)."""
ROOF_RAIL_SHARE = {"estate": 0.70, "suv": 0.70}
"""Share of each body type with roof rails; an estimate from makers' price lists (module docstring)."""
RAIL_SILVER_SHARE = 0.5
"""Share of roof rails in silver anodised aluminium (the others black); an estimate."""
SHARK_FIN_SHARE = 0.85
SHARK_FIN_PAINTED_SHARE = 0.6
GLASS_ROOF_LENGTH_M = 1.3
"""The longest glass roof, m; a shorter roof's glass keeps `GLASS_ROOF_MARGINS_M` of paint at its ends."""
GLASS_ROOF_MARGINS_M = (0.25, 0.10)
"""Paint kept behind the glass (over the rear window or tailgate) and ahead of it (the windscreen's header), m."""
GLASS_ROOF_MIN_M = 0.4
"""A roof shorter than this between its margins (a pickup's cab) takes no glass."""
ROOF_NORMAL_Z = 0.9
"""The roof's quads face up more than this (within 26° of the vertical)."""
ROOF_TOP_SHARE = 0.95
"""The roof's quads lie higher than this share of the vehicle's height (a boot lid or bonnet does not)."""
RAIL_SIZE_M = (0.03, 0.045)
"""A roof rail's width and height over the roof, m."""
RAIL_INSET_M = (0.10, 0.08)
"""How far a rail stops short of the roof's rear and front ends, m."""
RAIL_SILVER_RGB = (0.40, 0.41, 0.42)
"""Linear albedo of a silver anodised rail (like a painted alloy wheel's, `camgen.vehicles.body.RIM_RGB`)."""
SHARK_FIN_M = (0.20, 0.07, 0.065)
"""A shark-fin antenna's length, width and height, m."""
SHARK_FIN_FROM_REAR_M = 0.12
"""How far ahead of the roof's rear end the fin's tail stands, m."""
COWL_DEPTH_M = 0.12
COWL_BODIES = ("hatchback", "sedan", "estate", "suv", "pickup", "van")
WIPER_LENGTHS_M = {"van": (0.65, 0.65)}
"""Wiper blades' lengths, m (driver's, passenger's); cars' `WIPER_LENGTHS_CAR_M`."""
WIPER_LENGTHS_CAR_M = (0.60, 0.45)
WIPER_SIZE_M = (0.025, 0.02)
"""A parked wiper's width (its arm and blade seen from above) and height over the glass, m."""
WIPER_UP_SCREEN_M = 0.05
"""How far up the windscreen from its foot the parked blades lie, m."""
WIPER_OVER_GLASS_M = 0.008
"""The parked blades' underside over the glass, m."""
WIPER_FROM_PILLAR_M = 0.08
"""How far in from the screen's sides the parked blades' outer ends lie, m."""
COWL_RGB = (0.035, 0.035, 0.035)
"""Linear albedo of the cowl's grained black polypropylene (3–4 %, like other black plastic trim: an estimate)."""
WIPER_RGB = (0.02, 0.02, 0.02)
"""Linear albedo of wiper arms (black powder-coated steel) and blades (rubber): an estimate."""
RAIL_SUNK_M = 0.01
"""How far a rail's underside is sunk into the roof at the roof-edge row's middle, m (the roof curves down across
the rail's width: so no gap shows under its outer edge)."""
SHUT_LINE_WIDTH_M = 0.006
SHUT_LINE_RGB = (0.01, 0.01, 0.01)
"""Linear albedo of a shut line: a narrow gap's depth traps the light (darker than black trim)."""
LIFT_M = 0.003
"""How far out along the shell's normals the cowl and the shut lines lie, m."""


@dataclass(frozen=True)
class RoofKit:
    """What a vehicle carries over its shell, drawn from its identity seed (`roof_kit`)."""

    glass_roof: bool
    rails_rgb: tuple[float, float, float] | None
    """Roof rails' albedo, or None without rails."""
    fin: str | None
    """"paint" (body-coloured), "black", or None without a shark fin."""


def roof_kit(look: VehicleLook) -> RoofKit:
    """The roof kit of `look`: the same draws, in a fixed order, from its identity seed, for every body type (a
    van, truck or bus gets none of it)."""
    rng = np.random.default_rng(np.random.SeedSequence(look.identity_seed, spawn_key=(ROOF_SPAWN_KEY,)))
    glass, rails, silver, fin, painted = rng.random(5)
    body = look.body_type
    rails_rgb = None
    if rails < ROOF_RAIL_SHARE.get(body, 0.0):
        rails_rgb = RAIL_SILVER_RGB if silver < RAIL_SILVER_SHARE else SHUT_LINE_RGB
    fin_kind = None
    if body in CAR_BODIES and fin < SHARK_FIN_SHARE:
        fin_kind = "paint" if painted < SHARK_FIN_PAINTED_SHARE else "black"
    return RoofKit(bool(glass < GLASS_ROOF_SHARE.get(body, 0.0)), rails_rgb, fin_kind)


def roof_quads(upper_points: int, side_quads: int) -> np.ndarray:
    """Indices of a section's quads across its roof between the roof-edge rows (`camgen.vehicles.body._sections`:
    `side_quads` rows up each side, then one roof-edge row, then the roof)."""
    return np.arange(side_quads + 1, upper_points - side_quads - 1)


def roof_span(station_x_m: np.ndarray, roof_up: np.ndarray) -> tuple[int, int] | None:
    """(first, last + 1) quad row of the longest run of stations whose roof quads all face up (`roof_up`, (S − 1,)
    bool), or None."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], roof_up.astype(np.int8), [0]])))
    runs = list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))
    if not runs:
        return None
    return max(runs, key=lambda run: station_x_m[run[1]] - station_x_m[run[0]])


def glass_roof_rows(look: VehicleLook, station_x_m: np.ndarray, roof_up: np.ndarray) -> np.ndarray:
    """(S − 1,) bool: the quad rows of the glass roof, if `look` has one (`roof_kit`): over the roof's longest
    upward-facing run (`roof_span`), from `GLASS_ROOF_MARGINS_M` behind its front end back at most
    `GLASS_ROOF_LENGTH_M`, stopping the rear margin short of its rear end."""
    rows = np.zeros(len(station_x_m) - 1, dtype=bool)
    span = roof_span(station_x_m, roof_up)
    if span is None or not roof_kit(look).glass_roof:
        return rows
    rear_m, front_m = station_x_m[span[0]], station_x_m[span[1]]
    stop_m = front_m - GLASS_ROOF_MARGINS_M[1]
    start_m = max(rear_m + GLASS_ROOF_MARGINS_M[0], stop_m - GLASS_ROOF_LENGTH_M)
    if stop_m - start_m < GLASS_ROOF_MIN_M:
        return rows
    middle = (station_x_m[:-1] + station_x_m[1:]) / 2
    return (middle > start_m) & (middle < stop_m)


def _sweep(points_m: np.ndarray, across: np.ndarray, up: np.ndarray, width_m: float, height_m: float):
    """A bar of `width_m` × `height_m` section swept along `points_m` (n, 3), its bottom on them, `across` and `up`
    (n, 3) unit vectors per point: a closed box-like tube (its four sides and two ends)."""
    half = width_m / 2 * across
    lift = height_m * up
    rings = np.stack([points_m - half, points_m + half, points_m + half + lift, points_m - half + lift], axis=1)
    n = len(points_m)
    vertices = rings.reshape(-1, 3)
    faces = []
    for i in range(n - 1):
        for k in range(4):
            a, b = 4 * i + k, 4 * i + (k + 1) % 4
            c, d = b + 4, a + 4
            faces += [(a, b, c), (a, c, d)]
    faces += [(0, 2, 1), (0, 3, 2), (4 * (n - 1), 4 * (n - 1) + 1, 4 * (n - 1) + 2)]
    faces += [(4 * (n - 1), 4 * (n - 1) + 2, 4 * (n - 1) + 3)]
    faces = np.array(faces)
    # Outward when the section's corners turn counter-clockwise seen from ahead (across × up along the sweep).
    if np.dot(np.cross(across[0], up[0]), points_m[-1] - points_m[0]) < 0:
        faces = faces[:, ::-1]
    return trimesh.Trimesh(vertices, faces, process=False)


def _row_line(grid_m: np.ndarray, normals: np.ndarray, stations: np.ndarray, point: float):
    """Points, outward normals and unit tangents across the section (towards +y) at fractional section point
    `point` (k + t: between points k and k + 1) of `stations` of the shell's (S, N, 3) grid."""
    k, t = int(np.floor(point)), point - np.floor(point)
    at = grid_m[stations, k] * (1 - t) + grid_m[stations, k + 1] * t
    n = normals[stations, k] * (1 - t) + normals[stations, k + 1] * t
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    along = np.gradient(at[:, 0])[:, None] * np.array([1.0, 0.0, 0.0])
    across = np.cross(n, along + np.array([1e-9, 0.0, 0.0]))
    across /= np.linalg.norm(across, axis=1, keepdims=True)
    across *= np.sign(across[:, 1:2] + 1e-12)
    return at, n, across


def _surface_band(grid_m, normals, stations, rows, lift_m: float) -> trimesh.Trimesh:
    """The shell's own quads of `stations` (consecutive, S' of them) × section points `rows` (consecutive), lifted
    `lift_m` along the normals: a patch on the surface that never dips under it."""
    patch = grid_m[np.ix_(stations, rows)] + lift_m * normals[np.ix_(stations, rows)]
    s, r = patch.shape[:2]
    index = np.arange(s * r).reshape(s, r)
    a, b, c, d = index[:-1, :-1], index[:-1, 1:], index[1:, 1:], index[1:, :-1]
    # Section points run counter-clockwise about +x: (a, c, d) and (a, b, c) face outwards, as the shell's quads.
    faces = np.concatenate([np.stack([a, c, d], -1).reshape(-1, 3), np.stack([a, b, c], -1).reshape(-1, 3)])
    return trimesh.Trimesh(patch.reshape(-1, 3), faces, process=False)


Piece = tuple[trimesh.Trimesh, tuple[float, float, float]]
"""A mesh in the vehicle's frame and its linear albedo."""


def roof_details(
    look: VehicleLook,
    shell_m: tuple[np.ndarray, np.ndarray, np.ndarray],
    windscreen_foot_x_m: float | None,
    upper_points: int,
    side_quads: int,
    count: int,
) -> dict[str, list[Piece]]:
    """The pieces over the shell by name: "rails", "fin" (a black one), "cowl", "wipers" and "shut_lines", each
    [(mesh, linear albedo)] for the running gear, and "fin_paint" (a body-coloured fin's mesh, its albedo the paint's
    in the renderer); names a vehicle lacks map to []. `shell_m`: the shell's vertices (S · `count`, 3), normals and
    faces (`camgen.vehicles.body.shell`: `upper_points`, `side_quads`); `windscreen_foot_x_m`: where the
    windscreen's glass ends at the bonnet (None: no windscreen)."""
    vertices, normals, _ = shell_m
    grid = vertices.reshape(-1, count, 3)
    grid_n = normals.reshape(-1, count, 3)
    x = grid[:, 0, 0]
    kit = roof_kit(look)
    pieces: dict[str, list[Piece]] = {
        name: [] for name in ("rails", "fin", "fin_paint", "cowl", "wipers", "shut_lines")
    }
    span = roof_span(x, roof_rows_up(look, grid, upper_points, side_quads)) if look.body_type in CAR_BODIES else None
    if span is not None:
        rear_m, front_m = x[span[0]], x[span[1]]
        if kit.rails_rgb is not None:
            stations = np.flatnonzero((x >= rear_m + RAIL_INSET_M[0]) & (x <= front_m - RAIL_INSET_M[1]))
            up = np.tile((0.0, 0.0, 1.0), (len(stations), 1))
            across = np.tile((0.0, 1.0, 0.0), (len(stations), 1))
            for point in (side_quads + 0.5, upper_points - side_quads - 0.5):  # the roof-edge rows' middles
                at, _, _ = _row_line(grid, grid_n, stations, point)
                pieces["rails"].append((_sweep(at - RAIL_SUNK_M * up, across, up, *RAIL_SIZE_M), kit.rails_rgb))
        if kit.fin is not None:
            fin = _shark_fin(grid, rear_m + SHARK_FIN_FROM_REAR_M, upper_points)
            pieces["fin_paint" if kit.fin == "paint" else "fin"].append((fin, SHUT_LINE_RGB))
    if windscreen_foot_x_m is not None and look.body_type in COWL_BODIES:
        _cowl_and_wipers(look, grid, grid_n, windscreen_foot_x_m, upper_points, side_quads, pieces)
    return pieces


def roof_rows_up(look: VehicleLook, grid: np.ndarray, upper_points: int, side_quads: int) -> np.ndarray:
    """(S − 1,) bool: the quad rows of the shell's (S, N, 3) `grid` whose roof quads (`roof_quads`) all face up
    (`ROOF_NORMAL_Z`) at the roof's height (`ROOF_TOP_SHARE`), not a bonnet's or boot lid's."""
    roof = roof_quads(upper_points, side_quads)
    high = grid[:-1, roof, 2].min(axis=1) > ROOF_TOP_SHARE * look.height_m
    return (_quad_normal_z(grid)[:, roof].min(axis=1) > ROOF_NORMAL_Z) & high


def _quad_normal_z(grid: np.ndarray) -> np.ndarray:
    """(S − 1, N): the z of each shell quad's unit normal (the quad between points k and k + 1 of two stations)."""
    a, b = grid[:-1], np.roll(grid[:-1], -1, axis=1)
    c = np.roll(grid[1:], -1, axis=1)
    n = np.cross(b - a, c - a)  # (a, b, c) turns outward, as the shell's quads (`camgen.vehicles.body.shell`)
    return n[..., 2] / np.maximum(np.linalg.norm(n, axis=-1), 1e-12)


def _shark_fin(grid: np.ndarray, tail_x_m: float, upper_points: int) -> trimesh.Trimesh:
    """A shark fin (`SHARK_FIN_M`) on the roof's centre line, its tail at `tail_x_m`, its base sunk 1 cm into the
    roof: a rounded wedge, tallest at its tail, sloping down to its nose."""
    length_m, width_m, height_m = SHARK_FIN_M
    sphere = trimesh.creation.icosphere(subdivisions=2)
    d = np.asarray(sphere.vertices)
    r = np.sum(np.abs(d) ** 3.0, axis=1) ** (-1.0 / 3.0)
    unit = d * r[:, None]  # a superellipsoid of exponent 3 in the unit box
    t = (unit[:, 0] + 1) / 2  # 0 at the tail, 1 at the nose
    z = (unit[:, 2] + 1) / 2 * height_m * (1 - 0.75 * t) ** 1.2
    half_w = width_m / 2 * (1 - 0.5 * t)
    centre = grid[:, upper_points // 2]
    roof_z = float(np.interp(tail_x_m + length_m / 2, centre[:, 0], centre[:, 2]))
    base_m = roof_z - 0.01 + 0.01 * (unit[:, 2] + 1) / 2  # the base's underside sunk 1 cm into the roof
    points = np.stack([tail_x_m + t * length_m, unit[:, 1] * half_w, base_m + z], 1)
    return trimesh.Trimesh(points, np.asarray(sphere.faces), process=False)


def _cowl_and_wipers(look: VehicleLook, grid, grid_n, foot_x_m: float, upper_points: int, side_quads: int, pieces):
    """Into `pieces` (`roof_details`): the cowl (the shell's quads `COWL_DEPTH_M` ahead of the windscreen's foot
    across the section's top between its shoulders, lifted `LIFT_M`), two wipers parked `WIPER_UP_SCREEN_M` up the
    screen, and, on a car, the bonnet's shut lines (`_bonnet_shut_lines`)."""
    x = grid[:, 0, 0]
    cowl = np.flatnonzero((x >= foot_x_m) & (x <= foot_x_m + COWL_DEPTH_M))
    rows = np.arange(side_quads, upper_points - side_quads + 1)
    if len(cowl) >= 2:
        pieces["cowl"].append((_surface_band(grid, grid_n, cowl, rows, LIFT_M), COWL_RGB))
    # The wipers: across the screen at its station nearest a few centimetres up from its foot, from near each side in.
    station = int(np.argmin(np.abs(x - (foot_x_m - WIPER_UP_SCREEN_M))))
    section = grid[station, side_quads : upper_points - side_quads + 1]
    y_order = np.argsort(section[:, 1])
    sy, sz = section[y_order, 1], section[y_order, 2]
    long_m, short_m = WIPER_LENGTHS_M.get(look.body_type, WIPER_LENGTHS_CAR_M)
    half_m = sy.max() - WIPER_FROM_PILLAR_M
    for y0, y1 in ((-half_m, -half_m + long_m), (half_m - short_m, half_m)):
        y = np.linspace(y0, y1, 8)
        at = np.stack([np.full_like(y, x[station]), y, np.interp(y, sy, sz) + WIPER_OVER_GLASS_M], axis=1)
        up = np.tile((0.0, 0.0, 1.0), (len(y), 1))
        across = np.tile((1.0, 0.0, 0.0), (len(y), 1))
        pieces["wipers"].append((_sweep(at, across, up, *WIPER_SIZE_M), WIPER_RGB))
    if look.body_type in CAR_BODIES:
        lines = _bonnet_shut_lines(look, grid, grid_n, foot_x_m, upper_points, side_quads)
        pieces["shut_lines"] += [(mesh, SHUT_LINE_RGB) for mesh in lines]


BONNET_EDGE_INSET_M = 0.12
"""How far inboard of the body's side in plan the bonnet's side shut lines run, m (where a current car's bonnet meets
its wings, about 0.1–0.15 m in from the wings' outer edge on makers' top views; an estimate)."""


def _bonnet_shut_lines(look: VehicleLook, grid, grid_n, foot_x_m: float, upper_points: int, side_quads: int):
    """The bonnet's edges as dark ribbons `SHUT_LINE_WIDTH_M` wide, `LIFT_M` over the surface: along each side
    `BONNET_EDGE_INSET_M` inboard of the body's plan outline (`camgen.vehicles.body.plan_half_width_m`) from the cowl
    to the headlamp units' rear edge, and across the bonnet there (its front edge, over the grille)."""
    from camgen.vehicles.body import HEADLAMP_TOP_DEPTH_M, plan_half_width_m

    x = grid[:, 0, 0]
    front_m = look.length_m / 2 - HEADLAMP_TOP_DEPTH_M
    stations = np.flatnonzero((x >= foot_x_m + COWL_DEPTH_M) & (x <= front_m))
    if len(stations) < 2:
        return []
    # The section's upper arc, from the belt on one side over the top to the other: one height per y (the section
    # is convex and its sides lean in), whatever the bonnet's shoulders.
    upper = slice(0, upper_points + 1)
    half = SHUT_LINE_WIDTH_M / 2

    def on_top(station: int, y_m: np.ndarray) -> np.ndarray:
        section = grid[station, upper]
        order = np.argsort(section[:, 1])
        return np.interp(y_m, section[order, 1], section[order, 2]) + LIFT_M

    inset = plan_half_width_m(look, x[stations]) - BONNET_EDGE_INSET_M
    lines = []
    for side in (1.0, -1.0):
        edges = []
        for y in (side * inset - half, side * inset + half):  # each edge on the surface: the shoulder slopes across
            z = np.array([on_top(station, np.array([y_m]))[0] for station, y_m in zip(stations, y, strict=True)])
            edges.append(np.stack([x[stations], y, z], axis=1))
        lines.append(_ribbon(*edges))
    front = stations[-1]
    y = np.linspace(-inset[-1], inset[-1], 12)
    z = on_top(front, y)
    lines.append(_ribbon(*(np.stack([np.full_like(y, x[front] + d), y, z], axis=1) for d in (-half, half))))
    return lines


def _ribbon(edge_m: np.ndarray, other_edge_m: np.ndarray) -> trimesh.Trimesh:
    """A strip between two polylines (n, 3) of its edges, its faces wound towards +z."""
    vertices = np.concatenate([edge_m, other_edge_m])
    n = len(edge_m)
    k = np.arange(n - 1)
    faces = np.concatenate([np.stack([k, k + 1, n + k + 1], 1), np.stack([k, n + k + 1, n + k], 1)])
    corners = vertices[faces]
    down = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])[:, 2] < 0
    faces[down] = faces[down][:, ::-1]
    return trimesh.Trimesh(vertices, faces, process=False)
