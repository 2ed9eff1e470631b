"""Who a vehicle is: body type, dimensions, paint and plate, drawn from an identity seed.

Every attribute follows from the identity seed through one generator, drawn in a fixed order, so the
same seed always gives the same vehicle (in every frame and every camera) and a scene may pin an
attribute (`camgen.config.scene.VehicleLook`): a pinned value replaces its draw and the others are
drawn as if nothing were pinned.

Sources:

- Body-type shares within a class (car: sedan, hatchback, estate, SUV, pickup; truck: van, box truck):
  new registrations by segment in Europe, 2022 (JATO Dynamics, "European new car registrations by
  segment and body type", 2023: SUVs about 50 %, hatchbacks about 25 %, sedans 10 %, estates 10 %;
  pickups under 1 % in Europe and about 20 % of US light vehicles, so 5 % here as a mix). Vans are
  most of the light commercial vehicles on a street (ACEA 2023: 1.5 M vans against 0.3 M trucks
  over 3.5 t registered in the EU in 2022), so a truck is a van at 75 %.
- Dimensions (`BODY_TYPES`): ranges of length, width (without mirrors), height and wheelbase spanned
  by the best-selling models of each segment in the makers' published specifications (2020–2024):
  hatchback Fiat 500 (3.57 × 1.63 × 1.49 m, wheelbase 2.30 m) to VW Golf 8 (4.28 × 1.79 × 1.46,
  2.64); sedan Toyota Corolla saloon (4.63 × 1.78 × 1.44, 2.70) to Toyota Camry (4.89 × 1.84 × 1.45,
  2.83); estate Skoda Octavia Combi (4.69 × 1.83 × 1.47, 2.69) to VW Passat Variant (4.89 × 1.85 ×
  1.51, 2.84); SUV Peugeot 2008 (4.30 × 1.77 × 1.55, 2.61) to BMW X5 (4.92 × 2.00 × 1.75, 2.98);
  pickup Toyota Hilux double cab (5.33 × 1.86 × 1.82, 3.09) to Ford Ranger (5.37 × 1.92 × 1.88,
  3.27); van VW Transporter T6.1 (4.90 × 1.90 × 1.99, 3.00) to Mercedes Sprinter L2H2 (5.93 × 2.02 ×
  2.69, 3.67); box truck a 7.5 t rigid (MAN TGL, Iveco Eurocargo 75E with box body: 6.9–8.6 m long,
  2.55 m wide, the EU limit of Directive 96/53/EC, 3.2–3.7 m high, wheelbase 3.6–4.8 m); bus a
  city bus (Alexander Dennis Enviro200 10.8 × 2.45 × 2.9, 5.2 m to Mercedes Citaro 12.14 × 2.55 ×
  3.12, 5.85). One size quantile drawn per vehicle sets every dimension (big cars are big in every
  direction), each jittered by 10 % of its range.
- Wheel radius from each segment's typical tyre (ETRTO designation: outer diameter = rim × 25.4 mm +
  2 × section × aspect): hatchback 185/65 R15 0.310 m, sedan and estate 205/55 R16 0.316 m, SUV
  225/65 R17 0.362 m, pickup 265/65 R17 0.388 m, van 215/65 R16C 0.343 m, box truck 215/75 R17.5
  0.384 m, bus 275/70 R22.5 0.478 m.
- Paint colours of cars: Axalta Global Automotive Color Popularity Report 2022 (70th edition, Dec
  2022): white 34 %, black 21 %, grey 19 %, silver 8 % (white, black, grey and silver together 82 %),
  blue 8 %, red 5 %, green 1 %; the remaining 4 % split here between beige/brown (2 %), yellow/gold
  (1 %) and orange (1 %). Vans and trucks are mostly white fleet vehicles (white 60 % here, an
  estimate: Axalta puts white far ahead in commercial vehicles), buses take a livery colour.
- Plates: `camgen.vehicles.plate` (the UK's DVLA format; a motorcycle carries one, at the rear; a
  bicycle none).
- Bicycles: an adult hybrid or city bike with 700C wheels (ISO 5775 / ETRTO 622 mm bead seat, 700 × 32C
  tyre: outer diameter 622 + 2 × 32 = 686 mm, radius 0.343 m); wheelbase and handlebar width within the
  ranges of hybrids' geometry tables for sizes S–L (Trek FX, Giant Escape: wheelbases about 1.04–1.08 m,
  flat bars 0.60–0.68 m wide); the length is the wheelbase plus a wheel's diameter, the height the bar's
  (frame geometry and the rider's saddle: `camgen.vehicles.two_wheeler`; the drawn height is a label,
  the built bike's bar is 1.0 m up for a 1.75 m rider). Frame colours: no fleet
  statistics were found; the shares here are an estimate (black and grey frames most common, then white,
  blue, red, green, silver).
- Motorcycles: a standard (naked) bike of 125–650 cc, from the makers' specifications: Honda CB125F
  (2021: 2.01 × 0.76 × 1.08 m, wheelbase 1.28 m), Honda CB500F (2022: 2.08 × 0.80 × 1.06 m, 1.41 m) and
  Yamaha MT-07 (2021: 2.085 × 0.78 × 1.105 m, 1.40 m); wheels 17-inch with a 120/70 ZR17 front tyre
  (ETRTO: 431.8 + 2 × 84 = 600 mm, radius 0.300 m; the rear's 160/60 is drawn at the same radius).
  Colours: no registration statistics by colour were found; the shares here are an estimate (black
  the most common, then grey, white, red, blue, silver, green, orange, yellow).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from camgen.vehicles.plate import draw_plate_text

BodyType = Literal["sedan", "hatchback", "estate", "suv", "pickup", "van", "box_truck", "bus", "bicycle", "motorcycle"]
VehicleClass = Literal["car", "truck", "bus", "bicycle", "motorcycle"]
TWO_WHEELERS = ("bicycle", "motorcycle")
"""Body types built by `camgen.vehicles.two_wheeler` (a frame, two wheels in line, a rider's seat)."""


@dataclass(frozen=True)
class BodyDimensions:
    """Published ranges (min, max) of one body type, m."""

    length_m: tuple[float, float]
    width_m: tuple[float, float]
    height_m: tuple[float, float]
    wheelbase_m: tuple[float, float]
    wheel_radius_m: float
    front_overhang_share: float
    """Front overhang / (length − wheelbase): cars carry the engine ahead of the front axle (≈ 0.55);
    a city bus's front overhang is 2.8 m of its 6.3 m overhangs (Citaro: 0.45)."""


BODY_TYPES: dict[str, BodyDimensions] = {
    "hatchback": BodyDimensions((3.57, 4.28), (1.63, 1.80), (1.42, 1.52), (2.30, 2.64), 0.310, 0.55),
    "sedan": BodyDimensions((4.63, 4.89), (1.78, 1.85), (1.40, 1.48), (2.70, 2.85), 0.316, 0.52),
    "estate": BodyDimensions((4.69, 4.89), (1.80, 1.86), (1.43, 1.52), (2.69, 2.84), 0.316, 0.50),
    "suv": BodyDimensions((4.30, 4.92), (1.77, 2.00), (1.55, 1.75), (2.61, 2.98), 0.362, 0.52),
    "pickup": BodyDimensions((5.26, 5.37), (1.85, 1.92), (1.79, 1.88), (3.09, 3.27), 0.388, 0.45),
    "van": BodyDimensions((4.90, 5.93), (1.90, 2.02), (1.99, 2.69), (3.00, 3.67), 0.343, 0.50),
    "box_truck": BodyDimensions((6.90, 8.60), (2.45, 2.55), (3.20, 3.70), (3.60, 4.80), 0.384, 0.38),
    "bus": BodyDimensions((10.80, 12.14), (2.45, 2.55), (2.90, 3.12), (5.20, 5.85), 0.478, 0.45),
    "bicycle": BodyDimensions((1.72, 1.80), (0.60, 0.68), (1.00, 1.10), (1.04, 1.08), 0.343, 0.50),
    "motorcycle": BodyDimensions((2.01, 2.09), (0.76, 0.80), (1.06, 1.11), (1.28, 1.41), 0.300, 0.48),
}

CLASS_BODY_TYPES: dict[str, dict[str, float]] = {
    "car": {"suv": 50.0, "hatchback": 25.0, "sedan": 10.0, "estate": 10.0, "pickup": 5.0},
    "truck": {"van": 75.0, "box_truck": 25.0},
    "bus": {"bus": 100.0},
    "bicycle": {"bicycle": 100.0},
    "motorcycle": {"motorcycle": 100.0},
}
"""Body-type shares (%) within each vehicle class (see the module's sources)."""

PAINT_SHARES: dict[str, dict[str, float]] = {
    "car": {"white": 34, "black": 21, "grey": 19, "silver": 8, "blue": 8, "red": 5, "green": 1, "beige": 2,
            "yellow": 1, "orange": 1},
    "truck": {"white": 60, "silver": 10, "grey": 8, "black": 6, "blue": 7, "red": 5, "green": 2, "yellow": 2},
    "bus": {"red": 25, "white": 20, "blue": 20, "green": 15, "yellow": 10, "silver": 10},
    "bicycle": {"black": 30, "grey": 15, "white": 14, "blue": 12, "red": 10, "green": 7, "silver": 7, "yellow": 2,
                "orange": 3},
    "motorcycle": {"black": 35, "grey": 15, "white": 12, "red": 12, "blue": 10, "silver": 6, "green": 4,
                   "orange": 4, "yellow": 2},
}  # fmt: skip


@dataclass(frozen=True)
class Paint:
    """A car paint as glTF metallic-roughness: linear base colour, and how metallic and how rough the
    clear-coated surface looks (solid paints dielectric; metallic and pearl paints partly metallic)."""

    color_rgb: tuple[float, float, float]
    metallic: float
    roughness: float


PAINTS: dict[str, Paint] = {
    "white": Paint((0.78, 0.78, 0.76), 0.0, 0.30),
    "black": Paint((0.018, 0.018, 0.020), 0.3, 0.25),
    "grey": Paint((0.16, 0.165, 0.17), 0.4, 0.35),
    "silver": Paint((0.50, 0.51, 0.52), 0.5, 0.35),
    "blue": Paint((0.025, 0.06, 0.22), 0.4, 0.30),
    "red": Paint((0.40, 0.02, 0.018), 0.2, 0.30),
    "green": Paint((0.03, 0.12, 0.05), 0.3, 0.30),
    "beige": Paint((0.42, 0.33, 0.22), 0.3, 0.35),
    "yellow": Paint((0.62, 0.45, 0.03), 0.1, 0.30),
    "orange": Paint((0.60, 0.16, 0.02), 0.2, 0.30),
}
"""Linear sRGB base colours: a display swatch of each paint decoded and kept below 0.8 (fresh white
paint reflects about 80 %)."""

VEHICLE_LOOK_SPAWN_KEY = 0x6361_7273
"""Spawn key of the generator a vehicle's attributes are drawn from (ASCII "cars")."""

SIZE_JITTER = 0.10
"""Each dimension's own jitter around the shared size quantile, as a share of its range."""


@dataclass(frozen=True)
class VehicleLook:
    """Every visible attribute of a vehicle; dimensions in metres."""

    vehicle_class: str
    body_type: str
    length_m: float
    width_m: float
    height_m: float
    wheelbase_m: float
    wheel_radius_m: float
    colour: str
    plate_text: str
    identity_seed: int = 0

    @property
    def dimensions(self) -> BodyDimensions:
        return BODY_TYPES[self.body_type]

    @property
    def paint(self) -> Paint:
        return PAINTS[self.colour]

    @property
    def track_m(self) -> float:
        """Distance between the left and right wheels' centres, m (about 0.86 of the width for cars
        and vans: a Golf 8's 1.54 m of its 1.79 m; a bus's 2.1 m of 2.55)."""
        return 0.86 * self.width_m

    @property
    def front_axle_x_m(self) -> float:
        """Front axle ahead of the vehicle's centre, m (the origin is the middle of its footprint)."""
        overhangs = self.length_m - self.wheelbase_m
        return self.length_m / 2 - overhangs * self.dimensions.front_overhang_share

    @property
    def rear_axle_x_m(self) -> float:
        return self.front_axle_x_m - self.wheelbase_m

    def attributes(self) -> dict[str, object]:
        """Attribute labels of what is rendered (COCO track attributes); a bicycle has no plate text."""
        labels = {
            "body_type": self.body_type,
            "colour": self.colour,
            "plate_text": self.plate_text,
            "length_m": round(self.length_m, 3),
            "width_m": round(self.width_m, 3),
            "height_m": round(self.height_m, 3),
        }
        if not self.plate_text:
            del labels["plate_text"]
        return labels


def _choice(rng: np.random.Generator, table: dict[str, float]) -> str:
    names = list(table)
    p = np.array([table[n] for n in names], dtype=np.float64)
    return names[int(rng.choice(len(names), p=p / p.sum()))]


def draw_look(seed: int, vehicle_class: str, *, pinned: dict[str, object] | None = None) -> VehicleLook:
    """The look of vehicle identity `seed` of class car, truck, bus, bicycle or motorcycle; `pinned` attributes
    (body_type, colour, plate_text) replace draws. Every draw is made whether or not it is pinned.

    A pinned body type must belong to the class (`CLASS_BODY_TYPES`); the scene's schema checks that.
    """
    if vehicle_class not in CLASS_BODY_TYPES:
        raise ValueError(f"vehicle_class must be one of {sorted(CLASS_BODY_TYPES)}, got {vehicle_class!r}")
    pinned = dict(pinned or {})
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(VEHICLE_LOOK_SPAWN_KEY,)))
    body_type = str(pinned.get("body_type", _choice(rng, CLASS_BODY_TYPES[vehicle_class])))
    dims = BODY_TYPES[body_type]
    quantile = rng.uniform()
    jitter = rng.uniform(-SIZE_JITTER, SIZE_JITTER, size=4)

    def pick(limits: tuple[float, float], k: int) -> float:
        low, high = limits
        return float(low + (high - low) * np.clip(quantile + jitter[k], 0.0, 1.0))

    colour = _choice(rng, PAINT_SHARES[vehicle_class])
    plate_text = draw_plate_text(rng=rng)
    look = VehicleLook(
        vehicle_class=vehicle_class,
        body_type=body_type,
        length_m=pick(dims.length_m, 0),
        width_m=pick(dims.width_m, 1),
        height_m=pick(dims.height_m, 2),
        wheelbase_m=pick(dims.wheelbase_m, 3),
        wheel_radius_m=dims.wheel_radius_m,
        colour=colour,
        plate_text=plate_text,
        identity_seed=int(seed),
    )
    if vehicle_class == "bicycle":  # its plate text drawn all the same, so that every later draw stays as it was
        look = replace(look, plate_text="", length_m=look.wheelbase_m + 2 * look.wheel_radius_m)
    return replace(look, **{k: v for k, v in pinned.items() if k in ("colour", "plate_text")})
