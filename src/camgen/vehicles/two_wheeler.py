"""Two-wheelers: a bicycle and a standard motorcycle, as parts in the vehicle's frame, and where a rider
sits, holds on and puts the feet.

The vehicle's frame is a car's (`camgen.vehicles.body`): x forward, y left, z up, origin on the ground
at the middle of the footprint; the rear axle is at `VehicleLook.rear_axle_x_m`, the front axle a
wheelbase ahead. A part's vertices belong to one bone (`Part.wheel`, `BONES`): the body (−1), a wheel
(in its own frame, axle along y), the steering assembly (fork, handlebar, headlamp; in the vehicle's
frame, turned about the steering axis), the crank (about the bottom bracket) or a pedal (about its
spindle, kept level while the crank turns). `camgen.vehicles.TwoWheelerRig` poses the bones.

Bicycle geometry (a hybrid's, size M, within the ranges of the makers' geometry tables for hybrids
such as Trek's FX and Giant's Escape: head angle 70–71.5°, seat angle 73–73.5°, chainstays 0.43–0.45 m,
bottom-bracket drop 0.065–0.075 m): head angle 71°, seat angle 73°, chainstays 0.445 m, drop 0.07 m,
stack 0.59 m, fork offset 0.045 m, cranks 0.170 m (165–175 mm arms are the usual adult sizes),
pedals 0.115 m off the frame's centre plane. Tubes of 32 mm (top), 38 mm (down) and 16–18 mm (stays)
diameter. Gearing 42/19: the crank turns once per 2.21 turns of the rear wheel, 63 rpm at 5 m/s on a
0.343 m wheel, the low end of freely chosen cadences (professional cyclists choose about 90 rpm: Lucía
et al. 2001, "Preferred pedalling cadence in professional cycling", Med. Sci. Sports Exerc. 33: 1361).
The crank is locked to the wheel (a fixed gear: a freewheel's coasting is not modelled). The saddle is
set for its rider: the knee flexed `KNEE_FLEXION_AT_BOTTOM_RAD` with the pedal at the bottom (25–30° is
the recommended saddle height: Bini, Hume & Croft 2011, Sports Med. 41: 463), and the bar raised with a
high saddle (`BAR_DROP_M`, `STEM_RISE_M`).

Motorcycle geometry (a standard 500 cc, Honda CB500F 2022 specifications): rake 25.5°, trail 0.102 m,
seat height 0.785 m, 17-inch wheels, footpegs about 0.33 m over the ground below the seat's front; head
and tail lamps (emitting as a car's when lit, `camgen.vehicles.LAMP_LUMINANCE_CD_M2`) and one rear plate
(`camgen.vehicles.plate.motorcycle_plate_image`). A bicycle carries a white front and a red rear lamp
(`camgen.vehicles.LAMP_LUMINANCE_CD_M2`'s cycle_head and cycle_tail).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh

from camgen.vehicles.body import LAMP_DEPTH_M, RIM_RGB, TRIM_RGB, TYRE_RGB, Part, VehicleModel, _merge, _part
from camgen.vehicles.look import VehicleLook
from camgen.vehicles.plate import MOTORCYCLE_PLATE_SIZE_M

BONES = ("front_wheel", "rear_wheel", "steering", "crank", "pedal_left", "pedal_right")
"""A two-wheeler's bones, by `Part.wheel` index (−1: the body)."""
FRONT, REAR, STEERING, CRANK, PEDAL_LEFT, PEDAL_RIGHT = range(6)

HEAD_ANGLE_RAD = math.radians(71.0)
SEAT_ANGLE_RAD = math.radians(73.0)
CHAINSTAY_M = 0.445
BB_DROP_M = 0.070
STACK_M = 0.59
FORK_OFFSET_M = 0.045
HEAD_TUBE_M = 0.16
SEAT_TUBE_M = 0.48
CRANK_M = 0.170
PEDAL_Y_M = 0.115
CHAINRING_TEETH, COG_TEETH = 42, 19
BICYCLE_TYRE_M = 0.032
"""700 × 32C: the tyre's section, m."""
KNEE_FLEXION_AT_BOTTOM_RAD = math.radians(30.0)
HIP_ABOVE_SEAT_M = 0.09
"""The hip joints' centres sit about 9 cm above a firm seat (Reed, Manary & Schneider 1999, SAE
1999-01-0959), as `camgen.actors.actions` seats a person."""
DEFAULT_SADDLE_M = 0.72
"""Bottom bracket to the saddle's top along the seat tube for a rider of 1.75 m (0.883 × an 0.82 m
inseam: LeMond's rule), the saddle of a bicycle nobody rides."""
PEDAL_TOP_M = 0.012
"""The pedal's tread above its spindle, m."""
BAR_DROP_M = 0.02
"""How far the grips sit under the saddle's top, m: a hybrid's flat bar is set about level with the
saddle (road bikes drop it 5–10 cm)."""
STEM_RISE_M = (0.10, 0.30)
"""Range of the stem's rise over the head tube along the steering axis (spacers and an adjustable
riser stem), m."""
SEAT_BEHIND_SADDLE_TOP_M = 0.05
"""The sitting bones rest this far behind the seat tube's line at the saddle's top, m (on the saddle's
wide rear)."""

MOTO_RAKE_RAD = math.radians(25.5)
MOTO_TRAIL_M = 0.102
MOTO_SEAT_M = 0.785
MOTO_FRONT_TYRE_M = 0.084
"""120/70: the section's height, m."""
MOTO_REAR_TYRE_M = 0.096
"""160/60: the section's height, m."""

FRAME_TUBE_SECTIONS = 10
SPOKES = 16
CHROME_RGB = (0.55, 0.55, 0.56)
ENGINE_RGB = (0.06, 0.06, 0.065)
CYLINDER_RGB = (0.30, 0.30, 0.31)
SEAT_RGB = (0.025, 0.025, 0.025)
CYCLE_FRONT_LAMP_M = (0.05, 0.045, 0.03)
"""A bicycle's front lamp's box, m: its length along x, then the lens's width and height (13.5 cm²)."""
CYCLE_REAR_LAMP_M = (0.03, 0.035, 0.05)
"""The rear lamp's box, m (a 17.5 cm² lens)."""


@dataclass
class TwoWheelerModel(VehicleModel):
    """A bicycle or motorcycle at rest in its frame (`wheel_centres_m`: (2, 3), front then rear), and
    where its rider's body meets it."""

    steer_point_m: np.ndarray = None
    """(3,) a point of the steering axis, vehicle frame."""
    steer_axis: np.ndarray = None
    """(3,) the steering axis's unit direction, upwards."""
    bottom_bracket_m: np.ndarray | None = None
    """(3,) the crank's axle (a bicycle's), or None."""
    seat_m: np.ndarray = None
    """(3,) where the rider's sitting bones rest on the saddle or seat, vehicle frame."""
    grips_m: np.ndarray = None
    """(2, 3) the handlebar's grips, left then right, at zero steer (they turn with the steering bone)."""
    pegs_m: np.ndarray | None = None
    """(2, 3) a motorcycle's footpegs, left then right (a bicycle's feet are on its pedals)."""

    @property
    def rake_rad(self) -> float:
        """The steering axis's angle from the vertical, rad."""
        return math.acos(float(self.steer_axis[2]))


def _v(x: float, y: float, z: float) -> np.ndarray:
    """A vector (3,), m."""
    return np.array([x, y, z], dtype=np.float64)


def _tube(p0, p1, radius_m: float, sections: int = FRAME_TUBE_SECTIONS) -> trimesh.Trimesh:
    return trimesh.creation.cylinder(radius=radius_m, segment=np.array([p0, p1], dtype=np.float64), sections=sections)


def _blob(centre_m, half_m, subdivisions: int = 2, pitch_rad: float = 0.0) -> trimesh.Trimesh:
    """An ellipsoid of half-axes `half_m` (x, y, z) at `centre_m`, pitched nose-up by `pitch_rad`."""
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    sphere.apply_scale(half_m)
    sphere.apply_transform(trimesh.transformations.rotation_matrix(-pitch_rad, (0, 1, 0)))
    sphere.apply_translation(centre_m)
    return sphere


def _block(size_m, centre_m, pitch_rad: float = 0.0) -> trimesh.Trimesh:
    box = trimesh.creation.box(extents=size_m)
    box.apply_transform(trimesh.transformations.rotation_matrix(-pitch_rad, (0, 1, 0)))
    box.apply_translation(centre_m)
    return box


def _ring(major_m: float, minor_m: float, major_sections: int = 40, minor_sections: int = 8) -> trimesh.Trimesh:
    """A torus about the y axis (a tyre or a rim), centred on the origin."""
    torus = trimesh.creation.torus(major_m, minor_m, major_sections=major_sections, minor_sections=minor_sections)
    torus.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
    return torus


def _coloured(name: str, surface: str, pieces: list[tuple[trimesh.Trimesh, int, tuple]], smooth=True) -> Part:
    """One part of meshes (mesh, bone, linear albedo), coloured per vertex."""
    parts = []
    for mesh, bone, rgb in pieces:
        part = _part(name, surface, [(mesh, bone)], smooth=smooth)
        part.colours = np.tile(rgb, (len(part.vertices_m), 1))
        parts.append(part)
    return _merge(name, surface, parts)


def _spoked_wheel(radius_m: float, tyre_m: float, bone: int) -> list[tuple[trimesh.Trimesh, int, tuple]]:
    """A bicycle wheel in its frame: tyre, rim, hub and `SPOKES` spokes (laced to both hub flanges)."""
    rim_m = radius_m - 2 * tyre_m + 0.004
    pieces = [(_ring(radius_m - tyre_m / 2, tyre_m / 2), bone, TYRE_RGB), (_ring(rim_m, 0.008, 40, 6), bone, RIM_RGB)]
    pieces.append((_tube((0, -0.05, 0), (0, 0.05, 0), 0.018, 12), bone, RIM_RGB))
    for k in range(SPOKES):
        angle = 2 * np.pi * k / SPOKES
        end = (rim_m * math.cos(angle), 0.0, rim_m * math.sin(angle))
        flange = (0.0, 0.03 if k % 2 else -0.03, 0.0)
        pieces.append((_tube(flange, end, 0.0018, 4), bone, CHROME_RGB))
    return pieces


def _cast_wheel(radius_m: float, tyre_m: float, bone: int, disc: bool) -> list[tuple[trimesh.Trimesh, int, tuple]]:
    """A motorcycle wheel in its frame: a fat tyre, a 17-inch rim with five spokes, a brake disc."""
    rim_m = radius_m - tyre_m
    pieces = [(_ring(radius_m - tyre_m * 0.6, tyre_m * 0.6, 40, 10), bone, TYRE_RGB)]
    pieces.append((_ring(rim_m, 0.012, 40, 6), bone, ENGINE_RGB))
    pieces.append((_tube((0, -0.07, 0), (0, 0.07, 0), 0.04, 12), bone, CYLINDER_RGB))
    for k in range(5):
        angle = 2 * np.pi * k / 5
        end = (rim_m * math.cos(angle), 0.0, rim_m * math.sin(angle))
        pieces.append((_tube((0, 0, 0), end, 0.013, 6), bone, ENGINE_RGB))
    if disc:
        pieces.append((_tube((0, 0.055, 0), (0, 0.06, 0), 0.15, 24), bone, CHROME_RGB))
    return pieces


def _on_axis(point_m: np.ndarray, axis: np.ndarray, z_m: float) -> np.ndarray:
    """The point of the line through `point_m` along `axis` at height `z_m`."""
    return point_m + axis * (z_m - point_m[2]) / axis[2]


def saddle_height_for(thigh_m: float, shin_m: float, ankle_from_tread_m: np.ndarray, hip_half_width_m: float) -> float:
    """The saddle height (bottom bracket to the saddle's top along the seat tube, m) at which a rider's
    knee is flexed `KNEE_FLEXION_AT_BOTTOM_RAD` with the pedal at the bottom of its circle and the ball
    of the foot on the pedal. `ankle_from_tread_m`: (x, z) of the ankle joint from the tread under the
    ball of a level foot (behind it, and the ankle's height over the sole), m."""
    reach = math.sqrt(thigh_m**2 + shin_m**2 + 2 * thigh_m * shin_m * math.cos(KNEE_FLEXION_AT_BOTTOM_RAD))
    seat_dir = np.array([-math.cos(SEAT_ANGLE_RAD), math.sin(SEAT_ANGLE_RAD)])
    ankle = np.array([ankle_from_tread_m[0], -CRANK_M + PEDAL_TOP_M + ankle_from_tread_m[1]])
    lateral = PEDAL_Y_M - hip_half_width_m
    low, high = 0.3, 1.2
    for _ in range(50):  # the hip rises away from the pedal as the saddle goes up
        mid = (low + high) / 2
        hip = mid * seat_dir + np.array([-SEAT_BEHIND_SADDLE_TOP_M, HIP_ABOVE_SEAT_M])
        if math.hypot(*(hip - ankle), lateral) < reach:
            low = mid
        else:
            high = mid
    return (low + high) / 2


def build_bicycle(look: VehicleLook, saddle_m: float = DEFAULT_SADDLE_M) -> TwoWheelerModel:
    """A hybrid bicycle of `look` (wheelbase, wheel radius, handlebar width = `width_m`), its saddle
    `saddle_m` up the seat tube from the bottom bracket."""
    R = look.wheel_radius_m
    rear = np.array([look.rear_axle_x_m, 0.0, R])
    front = np.array([look.front_axle_x_m, 0.0, R])
    bb = rear + np.array([math.sqrt(CHAINSTAY_M**2 - BB_DROP_M**2), 0.0, -BB_DROP_M])
    axis = np.array([-math.cos(HEAD_ANGLE_RAD), 0.0, math.sin(HEAD_ANGLE_RAD)])
    normal = np.array([math.sin(HEAD_ANGLE_RAD), 0.0, math.cos(HEAD_ANGLE_RAD)])  # ahead of the axis
    on_axis = front - FORK_OFFSET_M * normal
    head_top = _on_axis(on_axis, axis, bb[2] + STACK_M)
    head_bottom = head_top - HEAD_TUBE_M * axis
    seat_dir = np.array([-math.cos(SEAT_ANGLE_RAD), 0.0, math.sin(SEAT_ANGLE_RAD)])
    seat_top = bb + SEAT_TUBE_M * seat_dir
    saddle_top = bb + saddle_m * seat_dir
    body = [
        (_tube(head_bottom, head_top, 0.019), -1),
        (_tube(head_top - 0.025 * axis, seat_top - 0.02 * seat_dir, 0.016), -1),
        (_tube(head_bottom + 0.02 * axis, bb, 0.019), -1),
        (_tube(bb, seat_top, 0.016), -1),
    ]
    for side in (1, -1):
        stay = np.array([0.0, side * 0.065, 0.0])
        body.append((_tube(bb + stay * 0.5, rear + stay, 0.009, 8), -1))
        body.append((_tube(seat_top - 0.03 * seat_dir + stay * 0.3, rear + stay, 0.008, 8), -1))
    paint = _part("frame", "paint", body, smooth=True)
    # The fork and the cockpit turn with the handlebar.
    crown = head_bottom - 0.02 * axis
    # An adjustable riser stem puts the bar `BAR_DROP_M` under a high saddle (within its range; a low saddle
    # has the bar above it).
    rise = float(np.clip((saddle_top[2] - BAR_DROP_M - 0.02 - head_top[2]) / axis[2], *STEM_RISE_M))
    stem_top = head_top + rise * axis
    bar = stem_top + np.array([0.06, 0.0, 0.02])
    half_bar = look.width_m / 2
    grips = np.array([bar + _v(-0.06, half_bar - 0.06, 0.0), bar + _v(-0.06, -half_bar + 0.06, 0.0)])  # swept back
    fork = [(_tube(crown, head_top + 0.03 * axis, 0.015), STEERING, (0.03, 0.03, 0.03))]
    for side in (1, -1):
        fork.append(
            (_tube(crown + _v(0, side * 0.045, 0), front + _v(0, side * 0.05, 0), 0.013, 8), STEERING, TRIM_RGB)
        )
    cockpit = [
        (_tube(head_top, stem_top, 0.016), STEERING, TRIM_RGB),
        (_tube(stem_top, bar, 0.015), STEERING, TRIM_RGB),
        (_tube(bar + _v(-0.06, half_bar, 0), bar + _v(0, 0.12, 0), 0.011), STEERING, CHROME_RGB),
        (_tube(bar + _v(0, 0.12, 0), bar + _v(0, -0.12, 0), 0.013), STEERING, CHROME_RGB),
        (_tube(bar + _v(0, -0.12, 0), bar + _v(-0.06, -half_bar, 0), 0.011), STEERING, CHROME_RGB),
    ]
    for grip in grips:
        cockpit.append((_tube(grip + _v(0, 0.06, 0), grip - _v(0, 0.06, 0), 0.017), STEERING, SEAT_RGB))
    saddle_centre = saddle_top + np.array([0.02, 0.0, -0.025])
    rest = [
        (_tube(seat_top - 0.05 * seat_dir, saddle_top - 0.03 * seat_dir, 0.0135), -1, CHROME_RGB),
        (_blob(saddle_centre + _v(0.04, 0, 0), (0.10, 0.04, 0.022)), -1, SEAT_RGB),
        (_blob(saddle_centre - _v(0.05, 0, 0), (0.07, 0.075, 0.025)), -1, SEAT_RGB),
        (_tube(bb + _v(0, 0.075, 0), bb - _v(0, 0.075, 0), 0.02), -1, CHROME_RGB),
    ]
    crank = [(_tube((0, -0.055, 0), (0, -0.06, 0), 0.085, 28), CRANK, CHROME_RGB)]
    for side, bone in ((1, PEDAL_LEFT), (-1, PEDAL_RIGHT)):
        along = -side * CRANK_M / 2  # the right arm points along +x at crank angle 0, the left along −x
        crank.append((_block((CRANK_M + 0.03, 0.012, 0.03), (along, side * 0.078, 0.0)), CRANK, CHROME_RGB))
        crank.append((_block((0.095, 0.075, 0.022), (0.0, 0.0, PEDAL_TOP_M - 0.011)), bone, SEAT_RGB))
    wheels = _spoked_wheel(R, BICYCLE_TYRE_M, FRONT) + _spoked_wheel(R, BICYCLE_TYRE_M, REAR)
    gear = _coloured("running_gear", "gear", fork + cockpit + rest + crank + wheels)
    seat = saddle_top + np.array([-SEAT_BEHIND_SADDLE_TOP_M, 0.0, 0.0])
    # Lamps (Road Vehicles Lighting Regulations 1989): a white one clipped to the bar beside the stem, a red
    # one on the seat post under the saddle, each a small box whose end is its lens.
    front_lamp = _block(CYCLE_FRONT_LAMP_M, bar + _v(0.035, 0.05, -0.035))
    rear_lamp = _block(CYCLE_REAR_LAMP_M, seat_top - 0.02 * seat_dir - _v(0.035, 0, 0))
    lamps = [
        _part("front_lamp", "cycle_head", [(front_lamp, STEERING)]),
        _part("rear_lamp", "cycle_tail", [(rear_lamp, -1)]),
    ]
    return TwoWheelerModel(
        look=look,
        parts=[paint, gear, *lamps],
        wheel_centres_m=np.array([front, rear]),
        plate_corners_m={},
        steer_point_m=head_top,
        steer_axis=axis,
        bottom_bracket_m=bb,
        seat_m=seat,
        grips_m=grips,
    )


def build_motorcycle(look: VehicleLook) -> TwoWheelerModel:
    """A standard motorcycle of `look`: frame, fork, tank, seat, engine, exhaust, lamps and a rear plate."""
    R = look.wheel_radius_m
    L = look.length_m
    rear = np.array([look.rear_axle_x_m, 0.0, R])
    front = np.array([look.front_axle_x_m, 0.0, R])
    axis = np.array([-math.sin(MOTO_RAKE_RAD), 0.0, math.cos(MOTO_RAKE_RAD)])
    ground = np.array([front[0] + MOTO_TRAIL_M, 0.0, 0.0])  # the steering axis meets the ground a trail ahead
    head_low, head_top = _on_axis(ground, axis, 0.74), _on_axis(ground, axis, 0.93)
    pivot = np.array([rear[0] + 0.56, 0.0, 0.42])  # the swingarm's
    # The tank behind the steering head, the seat behind the tank, the engine behind the front tyre.
    tank_centre = np.array([head_top[0] - 0.32, 0.0, 0.88])
    seat_front_x = tank_centre[0] - 0.26
    engine_x = front[0] - R - 0.06 - 0.21
    # Fork, triple clamps, handlebar, headlamp: the steering bone.
    steer = []
    for side in (1, -1):
        leg = front + _v(0, side * 0.095, 0)
        steer.append((_tube(leg, _on_axis(leg, axis, 0.95), 0.026, 12), STEERING, CHROME_RGB))
    steer.append((_block((0.09, 0.26, 0.035), _on_axis(ground, axis, 0.95)), STEERING, ENGINE_RGB))
    bar = _on_axis(ground, axis, 0.96) + np.array([-0.13, 0.0, 0.01])
    half = look.width_m / 2
    grips = np.array([bar + _v(-0.04, half - 0.07, 0.0), bar + _v(-0.04, -half + 0.07, 0.0)])
    steer.append((_tube(_on_axis(ground, axis, 0.96), bar, 0.02), STEERING, ENGINE_RGB))
    steer.append((_tube(bar + _v(-0.04, half - 0.01, 0), bar + _v(0, 0.1, 0), 0.011), STEERING, ENGINE_RGB))
    steer.append((_tube(bar + _v(0, 0.1, 0), bar + _v(0, -0.1, 0), 0.013), STEERING, ENGINE_RGB))
    steer.append((_tube(bar + _v(0, -0.1, 0), bar + _v(-0.04, -half + 0.01, 0), 0.011), STEERING, ENGINE_RGB))
    for grip in grips:
        steer.append((_tube(grip + _v(0, 0.06, 0), grip - _v(0, 0.06, 0), 0.018), STEERING, SEAT_RGB))
        mirror = grip + np.array([0.02, np.sign(grip[1]) * -0.05, 0.0])
        top = mirror + np.array([0.03, np.sign(grip[1]) * 0.05, look.height_m - 0.065 - mirror[2]])  # the highest point
        steer.append((_tube(mirror, top, 0.006, 6), STEERING, ENGINE_RGB))
        steer.append((_blob(top + _v(0, 0, 0.03), (0.015, 0.06, 0.035), 1), STEERING, ENGINE_RGB))
    lamp_centre = _on_axis(ground, axis, 0.84) + np.array([0.13, 0.0, 0.0])
    steer.append((_tube(lamp_centre - _v(0.07, 0, 0), lamp_centre - _v(0.01, 0, 0), 0.09, 20), STEERING, ENGINE_RGB))
    fender = _blob(front + _v(0.0, 0.0, R + 0.03), (R * 0.75, 0.07, 0.025), 2)
    steer.append((fender, STEERING, ENGINE_RGB))
    head_lamp = _part("head_lamp", "head", [(_tube(lamp_centre - _v(0.01, 0, 0), lamp_centre, 0.08, 20), STEERING)])
    # The body: tank and tail in paint, frame and engine dark, seat black, exhaust chrome.
    tail_end = np.array([-L / 2 + 0.06, 0.0, 0.82])
    tail_start = np.array([seat_front_x - 0.30, 0.0, 0.74])
    tail_centre, tail_half = (tail_start + tail_end) / 2, float(tail_start[0] - tail_end[0]) / 2 + 0.04
    paint = _part(
        "bodywork",
        "paint",
        [
            (_blob(tank_centre, (0.27, 0.17, 0.12), 3, math.radians(-8)), -1),
            (_blob(tail_centre, (tail_half, 0.10, 0.055), 2, math.radians(-8)), -1),
            (_blob(lamp_centre - _v(0.10, 0, -0.08), (0.09, 0.12, 0.08), 2), -1),
        ],
        smooth=True,
    )
    seat_top = np.array([seat_front_x - 0.08, 0.0, MOTO_SEAT_M])
    body = [
        (_blob(seat_top + _v(-0.22, 0, -0.035), (0.36, 0.13, 0.05), 2, math.radians(-4)), -1, SEAT_RGB),  # and pillion
        (_block((0.42, 0.30, 0.30), (engine_x, 0.0, 0.40)), -1, ENGINE_RGB),
        (_block((0.22, 0.27, 0.24), (engine_x + 0.16, 0.0, 0.60), math.radians(-20)), -1, CYLINDER_RGB),
        (_tube(head_low, pivot + _v(0.05, 0, 0.30), 0.025), -1, ENGINE_RGB),
        (_tube(head_top, pivot + _v(0.10, 0, 0.40), 0.025), -1, ENGINE_RGB),
        (_tube(pivot + _v(0.10, 0, 0.35), tail_end + _v(0.05, 0, -0.08), 0.02), -1, ENGINE_RGB),
        (_tube(_v(engine_x + 0.24, -0.05, 0.62), _v(engine_x + 0.10, -0.12, 0.20), 0.022), -1, CHROME_RGB),
        (_tube(_v(engine_x + 0.10, -0.12, 0.20), pivot + _v(0.0, -0.17, -0.16), 0.024), -1, CHROME_RGB),
        (_tube(pivot + _v(0.02, -0.17, -0.15), rear + _v(0.20, -0.19, 0.10), 0.055, 16), -1, CHROME_RGB),
        (_tube(rear + _v(0.45, 0, 0.12), pivot + _v(0.06, 0, 0.35), 0.025), -1, (0.45, 0.08, 0.03)),
    ]
    for side in (1, -1):
        body.append((_block((0.56, 0.03, 0.05), ((pivot[0] + rear[0]) / 2, side * 0.11, (pivot[2] + R) / 2),
                            math.atan2(pivot[2] - R, pivot[0] - rear[0])), -1, ENGINE_RGB))  # fmt: skip
    pegs = np.array([[seat_front_x + 0.05, 0.19, 0.33], [seat_front_x + 0.05, -0.19, 0.33]])
    for peg in pegs:
        out = _v(0, np.sign(peg[1]), 0)
        body.append((_tube(peg - 0.09 * out, peg + 0.04 * out, 0.012), -1, SEAT_RGB))
    # Rear: tail and brake lamps on the tail's end, the plate on a hugger below them.
    tail_x = -L / 2 + 0.02
    lamp = lambda z, w, h: _block((LAMP_DEPTH_M / 2, w, h), (tail_x + LAMP_DEPTH_M / 4, 0.0, z))  # noqa: E731
    tail = _part("tail_lamp", "tail", [(lamp(0.815, 0.13, 0.035), -1)])
    brake = _part("brake_lamp", "brake", [(lamp(0.78, 0.10, 0.03), -1)])
    pw, ph = MOTORCYCLE_PLATE_SIZE_M
    plate_x, plate_z = -L / 2 + 0.015, 0.60
    body.append((_block((0.02, pw + 0.02, ph + 0.02), (plate_x + 0.012, 0.0, plate_z)), -1, TRIM_RGB))
    body.append((_block((0.03, 0.05, 0.13), (plate_x + 0.03, 0.0, 0.72)), -1, TRIM_RGB))
    left = pw / 2  # behind the vehicle the viewer's left is +y
    quad = np.array([(plate_x, left, plate_z + ph / 2), (plate_x, -left, plate_z + ph / 2),
                     (plate_x, -left, plate_z - ph / 2), (plate_x, left, plate_z - ph / 2)])  # fmt: skip
    plate = Part(
        "plates",
        "plates",
        quad,
        np.tile((-1.0, 0.0, 0.0), (4, 1)),
        np.array([(0, 3, 2), (0, 2, 1)]),
        np.full(4, -1, np.int8),
        np.array([(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)]),
    )
    wheels = _cast_wheel(R, MOTO_FRONT_TYRE_M, FRONT, True) + _cast_wheel(R, MOTO_REAR_TYRE_M, REAR, False)
    gear = _coloured("running_gear", "gear", steer + body + wheels)
    return TwoWheelerModel(
        look=look,
        parts=[paint, gear, head_lamp, tail, brake, plate],
        wheel_centres_m=np.array([front, rear]),
        plate_corners_m={"rear": quad},
        steer_point_m=head_top,
        steer_axis=axis,
        bottom_bracket_m=None,
        seat_m=seat_top,
        grips_m=grips,
        pegs_m=pegs,
    )


def chain_ratio(look: VehicleLook) -> float:
    """Rear-wheel turns per crank turn (a bicycle's gearing), 1 for a motorcycle (no crank)."""
    return CHAINRING_TEETH / COG_TEETH if look.body_type == "bicycle" else 1.0
