"""The shut lines of a vehicle's doors and of a van's sliding side door, a car's tailgate or boot lid and its rear
wiper, in the vehicle's frame (`camgen.vehicles.body`).

A real car's side is not one smooth panel: its doors' edges show as dark lines (the 3–5 mm gaps between panels,
`camgen.vehicles.roof.SHUT_LINE_WIDTH_M`), seen from the side, from a mast and from behind at an angle. A
five-door car shows three on each side under its windows: the front door's leading edge behind the front wing, the
B-pillar between the doors and the rear door's trailing edge at the C-pillar (a pickup's double cab likewise, at
its cab's rear). A panel van shows its cab doors' edges on both sides and, on the nearside (the kerb's,
`camgen.vehicles.body.nearside_sign`), its sliding door: two upright edges from the sill to near the roof, the
door's top edge between them, and behind it the rail the door runs on, at the side's middle, back to the rear.
At the rear (`rear_details`) a car's tailgate or boot lid shows its lower edge across the rear between the lamp
clusters and its sides up their inner edges; hatchbacks, estates and SUVs carry a rear wiper parked along the rear
window's foot (nearly all do; saloons' rear windows are not wiped).

Sources and estimates:

- Where a car's front door starts (`FRONT_DOOR_BEHIND_ARCH_M`): makers' side views put the front door's leading
  edge 0.1–0.25 m behind the front wheel arch (VW Golf 8, Toyota Corolla), so 0.15 m behind the arch here: 0.50-0.55 m
  behind the front axle, within 0.1 m of the windscreen's foot (the A-pillar's base, 0.48-0.67 m behind it on the cars
  here, `camgen.vehicles.proportions`), as on those cars, whose front door opens under the A-pillar. A van's cab door
  stands over the front wheel's rear half, its lower edge cut round the arch (Ford Transit, Mercedes Sprinter), and
  reaches back to about the windscreen's header, 1.15 m wide (`VAN_CAB_DOOR_WIDTH_M`, an estimate from makers' side
  views).
- Where the doors meet (`DOOR_EDGES_U`): at the B-pillar (`camgen.vehicles.body.Profile.pillars`), and the rear
  door's trailing edge at the C-pillar's foot (a saloon's where its rear side window ends), read from the body types'
  profiles (shares of the length); a van's cab door ends where its side window does.
- A van's sliding door (`SLIDING_DOOR_WIDTH_M`): 1.30 m wide, as the Ford Transit's and Mercedes Sprinter's
  side-door openings in their dimension sheets (recalled, not rechecked here: an estimate), its top at
  `SLIDING_DOOR_TOP_SHARE` of the van's height (the openings are 1.6–1.8 m tall over a 0.55 m floor).
"""

from __future__ import annotations

import numpy as np
import trimesh

from camgen.vehicles.look import VehicleLook
from camgen.vehicles.roof import SHUT_LINE_RGB, SHUT_LINE_WIDTH_M

DOOR_BODIES = ("hatchback", "sedan", "estate", "suv", "pickup", "van")
FRONT_DOOR_BEHIND_ARCH_M = 0.15
VAN_CAB_DOOR_WIDTH_M = 1.15
DOOR_EDGES_U = {
    "sedan": (0.44, 0.25),
    "hatchback": (0.40, 0.15),
    "estate": (0.445, 0.265),
    "suv": (0.45, 0.20),
    "pickup": (0.465, 0.32),
    "van": (0.55,),
}
"""Per body type, the doors' edges behind the front door's leading edge, as shares of the length (rear 0 → front 1):
the B-pillar's middle and the rear door's trailing edge (a van's cab door has only the first)."""
SLIDING_DOOR_WIDTH_M = 1.30
SLIDING_DOOR_GAP_M = 0.10
"""How far behind the cab door's trailing edge the sliding door starts (the B-pillar's width), m; an estimate."""
SLIDING_DOOR_TOP_SHARE = 0.85
SLIDING_RAIL_SHARE = 0.50
"""The sliding door's rail, behind the door, at this share of the van's height (makers' side views; an estimate)."""
SIDE_NORMAL_Y = 0.8
"""A shut line on the side stops where the surface turns under (its outward normal less sideways than this)."""
LINE_SAMPLES = 10
SIDE_LIFT_M = 0.005
"""How far out along the side's normals the shut lines lie, m: more than the roof's lines' 3 mm
(`camgen.vehicles.roof.LIFT_M`), since a line follows the side interpolated between stations at one height, and the
shell's quads, split into two triangles, bend off that by up to 1.2 mm (a sedan's rear door's edge, measured)."""


def _side_chain(count: int, upper_points: int, side_quads: int) -> np.ndarray:
    """The left side's section points from its roof-edge row down over the belt to the underside (index 0 is the
    left beltline, 1…`side_quads` run up the greenhouse, the last ones down the side under the belt)."""
    up = np.arange(side_quads, 0, -1)
    down = (count - np.arange(0, count - upper_points)) % count
    return np.concatenate([up, down])


class SideSurface:
    """The shell's side at any (x, z): y on the left (mirror for the right) and the outward normal, interpolated
    between the two stations around x along the side's section points (`_side_chain`)."""

    def __init__(self, vertices_m: np.ndarray, normals: np.ndarray, count: int, upper_points: int, side_quads: int):
        self.grid = vertices_m.reshape(-1, count, 3)
        self.grid_n = normals.reshape(-1, count, 3)
        self.x = self.grid[:, 0, 0]
        self.chain = _side_chain(count, upper_points, side_quads)
        self.belt_index = side_quads
        """Where the left beltline (section point 0) is in the chain."""

    def _run_bounds(self, station: int) -> tuple[int, int]:
        """(start, stop) in `_side_chain` of one station's left side: the run through the beltline that faces out
        (`SIDE_NORMAL_Y`), from its top down."""
        side = self.grid_n[station, self.chain][:, 1] > SIDE_NORMAL_Y
        belt = self.belt_index
        if not side[belt]:
            return belt, belt + 1
        start = belt - int(np.argmin(side[belt::-1])) + 1 if not side[: belt + 1].all() else 0
        stop = belt + int(np.argmin(side[belt:])) if not side[belt:].all() else len(side)
        return start, stop

    def _side_run(self, station: int) -> tuple[np.ndarray, np.ndarray]:
        """(points, normals) of one station's left side (`_run_bounds`)."""
        start, stop = self._run_bounds(station)
        return self.grid[station, self.chain[start:stop]], self.grid_n[station, self.chain[start:stop]]

    def _station(self, station: int, z_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(y, normals (n, 3)) at heights `z_m` on one station's left side (`_side_run`)."""
        points, normals = self._side_run(station)
        order = np.argsort(points[:, 2])
        z = points[order, 2]
        y = np.interp(z_m, z, points[order, 1])
        n = np.stack([np.interp(z_m, z, normals[order, k]) for k in range(3)], axis=1)
        return y, n

    def _between(self, i: int, t: float, z_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """((n,) y, (n, 2) the cut's outward unit normal in (y, z)) at heights `z_m` on the left side between stations i
        and i + 1, a share `t` of the way: on the shell's own triangles. Each quad of the tube is split along
        its diagonal from point k at station i to point k + 1 at station i + 1 (`camgen.vehicles.body.shell`),
        so the side's cut at that x runs through each row's point and each diagonal's point in turn;
        interpolating the two stations' sides at one height instead misses a quad's bend by up to a centimetre
        where the sections change fast (at the cowl, where the belt leaves the bonnet)."""
        bounds = [self._run_bounds(station) for station in (i, i + 1)]
        start, stop = min(b[0] for b in bounds), max(b[1] for b in bounds)
        chain = self.chain[start:stop]
        rows = (1 - t) * self.grid[i, chain] + t * self.grid[i + 1, chain]
        count = self.grid.shape[1]
        cut = [rows[0]]
        for j in range(len(chain) - 1):
            p, q = int(chain[j]), int(chain[j + 1])
            low = p if q == (p + 1) % count else q
            cut += [(1 - t) * self.grid[i, low] + t * self.grid[i + 1, (low + 1) % count], rows[j + 1]]
        cut = np.array(cut)
        order = np.argsort(cut[:, 2], kind="stable")
        z, y = cut[order, 2], cut[order, 1]
        segment = np.clip(np.searchsorted(z, z_m) - 1, 0, len(z) - 2)
        along = np.stack([y[segment + 1] - y[segment], z[segment + 1] - z[segment]], axis=1)
        out = np.stack([along[:, 1], -along[:, 0]], axis=1)  # along turned clockwise: +y on a side rising in z
        out /= np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)
        return np.interp(z_m, z, y), out

    def at(self, x_m: float, z_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(points (n, 3) on the left side at `x_m` and heights `z_m`, unit outward normals (n, 3))."""
        i = int(np.clip(np.searchsorted(self.x, x_m) - 1, 0, len(self.x) - 2))
        t = float(np.clip((x_m - self.x[i]) / max(self.x[i + 1] - self.x[i], 1e-12), 0.0, 1.0))
        _, n0 = self._station(i, z_m)
        _, n1 = self._station(i + 1, z_m)
        n = (1 - t) * n0 + t * n1
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        # The normal's fore-and-aft lean from the stations', its part across from the cut it lies on.
        y, cut_normal = self._between(i, t, z_m)
        across = np.sqrt(np.maximum(1 - n[:, 0] ** 2, 0.0))[:, None] * cut_normal
        n = np.concatenate([n[:, :1], across], axis=1)
        return np.stack([np.full_like(z_m, x_m), y, z_m], axis=1), n

    def z_range(self, x_m: float) -> tuple[float, float]:
        """(lowest, highest) height at which the side faces out at both stations around `x_m`."""
        i = int(np.clip(np.searchsorted(self.x, x_m) - 1, 0, len(self.x) - 2))
        runs = [self._side_run(station)[0][:, 2] for station in (i, i + 1)]
        return max(z.min() for z in runs), min(z.max() for z in runs)


def _strip(edge_m: np.ndarray, other_edge_m: np.ndarray, outward: np.ndarray) -> trimesh.Trimesh:
    """A strip between two polylines (n, 3), its faces wound towards `outward` (n, 3) normals."""
    vertices = np.concatenate([edge_m, other_edge_m])
    n = len(edge_m)
    k = np.arange(n - 1)
    faces = np.concatenate([np.stack([k, k + 1, n + k + 1], 1), np.stack([k, n + k + 1, n + k], 1)])
    corners = vertices[faces]
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    towards = np.concatenate([outward, outward])[faces].mean(axis=1)
    inward = np.einsum("ij,ij->i", cross, towards) < 0
    faces[inward] = faces[inward][:, ::-1]
    return trimesh.Trimesh(vertices, faces, process=False)


def upright_line(surface: SideSurface, x_m: float, z_low_m: float, z_high_m: float, sign: float):
    """A shut line up the side (left for `sign` +1, right for −1) at `x_m` from `z_low_m` to `z_high_m` (clipped to
    where the side faces out), `SHUT_LINE_WIDTH_M` wide, `SIDE_LIFT_M` out along the surface's normals; None where the
    side does not reach."""
    low, high = surface.z_range(x_m)
    low, high = max(low, z_low_m), min(high, z_high_m)
    if high - low < 0.05:
        return None
    z = np.linspace(low, high, LINE_SAMPLES)
    edges, normals = [], []
    for x in (x_m - SHUT_LINE_WIDTH_M / 2, x_m + SHUT_LINE_WIDTH_M / 2):
        points, n = surface.at(x, z)
        edges.append(points + SIDE_LIFT_M * n)
        normals.append(n)
    mirror = np.array([1.0, sign, 1.0])
    return _strip(edges[0] * mirror, edges[1] * mirror, normals[0] * mirror)


def level_line(surface: SideSurface, x_from_m: float, x_to_m: float, z_m: float, sign: float):
    """A shut line along the side at height `z_m` from `x_from_m` to `x_to_m` (where the side faces out there),
    `SHUT_LINE_WIDTH_M` tall; None where too short."""
    x = np.linspace(x_from_m, x_to_m, max(2, int(np.ceil((x_to_m - x_from_m) / 0.08)) + 1))
    keep = np.array([surface.z_range(xi)[0] <= z_m - 0.01 and surface.z_range(xi)[1] >= z_m + 0.01 for xi in x])
    x = x[keep]
    if len(x) < 2 or x[-1] - x[0] < 0.05:
        return None
    edges, normals = [], []
    for z in (z_m - SHUT_LINE_WIDTH_M / 2, z_m + SHUT_LINE_WIDTH_M / 2):
        rows = [surface.at(xi, np.array([z])) for xi in x]
        points = np.concatenate([p for p, _ in rows])
        n = np.concatenate([q for _, q in rows])
        edges.append(points + SIDE_LIFT_M * n)
        normals.append(n)
    mirror = np.array([1.0, sign, 1.0])
    return _strip(edges[0] * mirror, edges[1] * mirror, normals[0] * mirror)


def door_shut_lines(
    look: VehicleLook,
    shell_m: tuple[np.ndarray, np.ndarray, np.ndarray],
    count: int,
    upper_points: int,
    side_quads: int,
) -> list[tuple[trimesh.Trimesh, tuple[float, float, float]]]:
    """The doors' shut lines on both sides (a van's sliding door on its nearside) as [(mesh, linear albedo)] for the
    running gear; [] for a body type without doors drawn (`DOOR_BODIES`). `shell_m`: the shell's vertices, normals
    and faces (`camgen.vehicles.body.shell`)."""
    from camgen.vehicles.body import ARCH_GAP_M, PROFILES, nearside_sign

    if look.body_type not in DOOR_BODIES:
        return []
    vertices, normals, _ = shell_m
    surface = SideSurface(vertices, normals, count, upper_points, side_quads)
    L, H = look.length_m, look.height_m
    belt = PROFILES[look.body_type].belt * H
    edges = [(u - 0.5) * L for u in DOOR_EDGES_U[look.body_type]]
    if look.body_type == "van":
        edges.insert(0, edges[0] + VAN_CAB_DOOR_WIDTH_M)
    else:
        edges.insert(0, look.front_axle_x_m - look.wheel_radius_m - ARCH_GAP_M - FRONT_DOOR_BEHIND_ARCH_M)
    lines = []
    for sign in (1.0, -1.0):
        for x in edges:
            lines.append(upright_line(surface, x, 0.0, belt, sign))
    if look.body_type == "van":
        sign = nearside_sign(look)
        front = edges[1] - SLIDING_DOOR_GAP_M
        rear = front - SLIDING_DOOR_WIDTH_M
        top = SLIDING_DOOR_TOP_SHARE * H
        lines += [upright_line(surface, x, 0.0, top, sign) for x in (front, rear)]
        lines.append(level_line(surface, rear, front, top, sign))
        lines.append(level_line(surface, -L / 2 + 0.15, rear, SLIDING_RAIL_SHARE * H, sign))
    return [(line, SHUT_LINE_RGB) for line in lines if line is not None]


TAILGATE_BODIES = ("hatchback", "sedan", "estate", "suv")
REAR_WIPER_BODIES = ("hatchback", "estate", "suv")
REAR_WIPER_REACH_M = 0.33
"""From the rear wiper's pivot to its blade's tip, m: Bosch's rear blades for hatchbacks, estates and SUVs are
250–400 mm long (its Rear range); an estimate for the arm and blade parked along the screen's foot."""
REAR_WIPER_UP_SCREEN_M = 0.04
"""How far over the rear window's lowest edge the parked wiper lies, m; an estimate."""
REAR_WIPER_BOSS_M = (0.06, 0.06, 0.03)
"""The wiper's pivot boss (the motor's spindle cover) at the screen's foot: width, height and depth, m; an estimate."""


def _rear_cap_half_width_m(grid: np.ndarray, z_m: np.ndarray) -> np.ndarray:
    """(n,) the rear end face's half-width at heights `z_m`, m: the first station's section (the cap's outline)."""
    section = grid[0]
    left = section[section[:, 1] > 0]
    order = np.argsort(left[:, 2])
    return np.interp(z_m, left[order, 2], left[order, 1], left=0.0, right=0.0)


def _rear_face_line(start_yz: tuple[float, float], stop_yz: tuple[float, float], x_m: float) -> trimesh.Trimesh:
    """A shut line on the flat rear end face (at `x_m`, facing −x) from (y, z) `start_yz` to `stop_yz`,
    `SHUT_LINE_WIDTH_M` wide."""
    a, b = np.array(start_yz, dtype=np.float64), np.array(stop_yz, dtype=np.float64)
    along = (b - a) / np.linalg.norm(b - a)
    side = np.array([-along[1], along[0]]) * SHUT_LINE_WIDTH_M / 2
    t = np.linspace(0.0, 1.0, 2)[:, None]
    line = a + t * (b - a)
    edges = [np.column_stack([np.full(len(line), x_m), line + s * side]) for s in (-1, 1)]
    return _strip(*edges, np.tile((-1.0, 0.0, 0.0), (len(line), 1)))


def _on_glass(corners: np.ndarray, normals: np.ndarray, points_yz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where lines along x through `points_yz` (n, 2) meet the glass triangles `corners` (F, 3, 3) with unit normals
    (F, 3): (points (n, 3), normals (n, 3)), the rearmost hit of each (NaN where none)."""
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    v0, v1 = b[:, 1:] - a[:, 1:], c[:, 1:] - a[:, 1:]
    den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
    ok = np.abs(den) > 1e-12
    points = np.full((len(points_yz), 3), np.nan)
    out_n = np.full((len(points_yz), 3), np.nan)
    for i, point in enumerate(points_yz):
        v2 = point - a[:, 1:]
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / den
            t = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / den
        inside = ok & (s >= -1e-9) & (t >= -1e-9) & (s + t <= 1 + 1e-9)
        if inside.any():
            x = a[inside, 0] + s[inside] * (b[inside, 0] - a[inside, 0]) + t[inside] * (c[inside, 0] - a[inside, 0])
            k = int(np.argmin(x))
            points[i] = (x[k], point[0], point[1])
            out_n[i] = normals[inside][k]
    return points, out_n


def rear_details(
    look: VehicleLook, vertices_m: np.ndarray, glass_faces: np.ndarray, count: int
) -> list[tuple[trimesh.Trimesh, tuple[float, float, float]]]:
    """What a car's rear shows beyond its lamps and plate, as [(mesh, linear albedo)] for the running gear: the
    tailgate's or boot lid's shut lines on the rear end face (its lower edge across between the rear lamp clusters,
    at their lower edge, and its sides up the clusters' inner edges: `TAILGATE_BODIES`), and on a hatchback, estate or
    SUV the rear wiper parked along its rear window's foot (`REAR_WIPER_BODIES`). `vertices_m`: the shell's vertices
    (`camgen.vehicles.body.shell`, `count` section points a station), `glass_faces`: its glass faces (kind 1)."""
    from camgen.vehicles.body import PROFILES, _end_heights, _rear_lamps_m
    from camgen.vehicles.roof import WIPER_OVER_GLASS_M, WIPER_RGB, WIPER_SIZE_M, _sweep

    if look.body_type not in TAILGATE_BODIES:
        return []
    vertices = vertices_m
    grid = vertices.reshape(-1, count, 3)
    L, W = look.length_m, look.width_m
    (rear_low, rear_high), _ = _end_heights(look)
    tail_z = float(np.clip(rear_high - 0.12, rear_low + 0.25, 1.2))  # as `lamps_and_plates`
    _, z_cluster, cluster_w, cluster_h = _rear_lamps_m(look, tail_z, rear_high)["cluster"]
    half = W / 2 * PROFILES[look.body_type].end_width
    inner_y = half - cluster_w
    low_z = z_cluster - cluster_h / 2
    x = -L / 2 - SIDE_LIFT_M
    top_z = rear_high - 0.02
    pieces = []
    if top_z - low_z > 0.05 and _rear_cap_half_width_m(grid, np.array([low_z]))[0] > inner_y + 0.02:
        pieces.append(_rear_face_line((-inner_y, low_z), (inner_y, low_z), x))
        for s in (1.0, -1.0):
            pieces.append(_rear_face_line((s * inner_y, low_z), (s * inner_y, top_z), x))
    lines = [(mesh, SHUT_LINE_RGB) for mesh in pieces]
    if look.body_type not in REAR_WIPER_BODIES or not len(glass_faces):
        return lines
    # The rear window: the glass behind the middle that faces back.
    corners = vertices[glass_faces]
    n = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    rear = (n[:, 0] < -0.35) & (corners.mean(axis=1)[:, 0] < 0)
    if not rear.any():
        return lines
    corners, n = corners[rear], n[rear]
    z_m = corners[:, :, 2].min() + REAR_WIPER_UP_SCREEN_M
    half_m = min(REAR_WIPER_REACH_M, float(np.abs(corners[:, :, 1]).max()) - 0.05)
    y = np.linspace(0.0, -half_m, 8)
    on_glass, up = _on_glass(corners, n, np.column_stack([y, np.full_like(y, z_m)]))
    if not np.isfinite(on_glass).all():
        return lines
    at = on_glass + WIPER_OVER_GLASS_M * up
    across = np.cross(up, np.tile((0.0, 1.0, 0.0), (len(y), 1)))
    across /= np.linalg.norm(across, axis=1, keepdims=True)
    wiper = [(_sweep(at, across, up, *WIPER_SIZE_M), WIPER_RGB)]
    boss_w, boss_h, boss_d = REAR_WIPER_BOSS_M
    boss = trimesh.creation.box((boss_d, boss_w, boss_h))
    # Centred on the pivot, its depth along the glass's normal (half sunk into the glass), a right-handed frame.
    lateral = np.array([0.0, 1.0, 0.0]) - up[0][1] * up[0]
    lateral /= np.linalg.norm(lateral)
    frame = np.eye(4)
    frame[:3, 0], frame[:3, 1], frame[:3, 2] = up[0], lateral, np.cross(up[0], lateral)
    frame[:3, 3] = on_glass[0]
    boss.apply_transform(frame)
    wiper.append((boss, WIPER_RGB))
    return lines + wiper
