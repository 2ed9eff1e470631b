"""Who a person is: body, skin, hair, clothing and carried things, drawn from an identity seed.

Every attribute follows from the identity seed through one generator, drawn in a fixed order, so the
same seed always gives the same person (in every frame and every camera) and a scene may pin any
attribute (`camgen.config.scene.PersonAppearance`): pinned values replace draws, and the other
attributes are drawn as if nothing were pinned.

Distributions and their sources:

- Sex 50/50. Adult stature, cm (mean, SD): men 175.3 ± 7.4, women 161.3 ± 6.9 (NHANES 2015–2018,
  Fryar et al. 2021, Vital Health Stat 3(46)); seniors 171/156 (80 y and over, same source);
  children 6–12 y from the WHO 2007 / CDC 2000 growth references (116 cm at 6 y to 150 cm at 12 y,
  SD 4.5 % of the mean). Stature is clipped to ±2.5 SD.
- Age groups of pedestrians: adults 80 %, seniors 12 %, children 8 % (an estimate for a public
  place; Market-1501's campus population is 98 % teen/adult: Lin et al. 2019).
- Build (MakeHuman weight parameter) from a BMI-like spread: Beta(4, 4) around the average; muscle
  Beta(5, 5).
- Skin: ten tones indexed as the Monk Skin Tone scale's (Monk 2019), each a reflectance in geometric
  steps through the ColorChecker 2005 "light skin" (0.568, 0.293, 0.218) and "dark skin" (0.173,
  0.082, 0.057) patches (colour-science's ColorChecker data, D65; the patches were matched to the
  spectral reflectance of real skin, McCamy et al. 1976) at tones 2 and 7. The Monk swatches
  themselves are display colours for annotators: decoded to linear sRGB their light tones are nearly
  grey (R : G : B = 1 : 0.85 : 0.60 at tone 4, against 1 : 0.52 : 0.38 for the light-skin patch), too
  little red for skin, so they index the tones but do not colour them.
- Hair colour by region-free frequencies (black/dark brown 65 %, brown 20 %, blond 8 %, red 2 %,
  with grey rising with age: Panhard et al. 2012); long hair for 78.5 % of women and 0.6 % of men,
  backpack 25.7 %, handbag 10.8 %, skirt or dress 29.7 % of women (Market-1501 attributes, Lin et
  al. 2019, Pattern Recognition 95); hats 3 % in summer (Market-1501: 2.9 %) and 15 % in winter
  (DukeMTMC-attribute: 17 %). Tops: in summer 65 % T-shirts (short sleeves), 25 % shirts (60 % of them
  long-sleeved), 10 % jackets, so about 75 % short sleeves (Market-1501 counts 94 % on a campus of
  students); in winter mostly jackets and coats. Clothing colours by the Market-1501 (summer) and
  DukeMTMC-attribute (winter) identity-level frequencies; a scene's `season` picks the table, and
  `mixed` (the default) draws each person's season at even odds.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

# Linear sRGB albedos of named clothing colours: typical dyed fabric, less saturated than a pure
# display primary (denim blue ≈ sRGB (70, 90, 130), decoded).
CLOTH_RGB: dict[str, tuple[float, float, float]] = {
    "black": (0.04, 0.04, 0.045),
    "white": (0.70, 0.70, 0.68),
    "gray": (0.20, 0.20, 0.21),
    "red": (0.36, 0.05, 0.05),
    "green": (0.07, 0.15, 0.07),
    "blue": (0.06, 0.09, 0.21),
    "yellow": (0.55, 0.45, 0.10),
    "purple": (0.15, 0.07, 0.20),
    "brown": (0.16, 0.09, 0.045),
    "pink": (0.60, 0.32, 0.38),
}
# Identity-level colour frequencies, % (Lin et al. 2019 attribute files: Market-1501 in summer,
# DukeMTMC-attribute in winter).
UPPER_COLOURS = {
    "summer": {"white": 32.2, "black": 16.4, "gray": 14.2, "red": 11.4, "green": 7.5, "blue": 7.2, "yellow": 7.2,
               "purple": 4.0},
    "winter": {"black": 61.0, "gray": 12.1, "blue": 9.4, "white": 7.6, "red": 5.4, "brown": 1.9, "green": 1.7,
               "purple": 0.9},
}  # fmt: skip
LOWER_COLOURS = {
    "summer": {"black": 40.6, "blue": 19.4, "gray": 17.4, "brown": 8.2, "white": 7.6, "pink": 3.4, "green": 2.4,
               "yellow": 0.8, "purple": 0.1},
    "winter": {"black": 46.1, "blue": 30.0, "gray": 9.3, "white": 7.8, "brown": 4.6, "red": 1.7, "green": 0.4},
}  # fmt: skip

_LIGHT_SKIN = np.array((0.568, 0.293, 0.218))
_DARK_SKIN = np.array((0.173, 0.082, 0.057))


def skin_rgb(tone: int) -> tuple[float, float, float]:
    """Linear albedo of Monk skin tone 1…10: per channel, geometric steps through the ColorChecker
    light-skin patch at tone 2 and the dark-skin patch at tone 7, ρ(t) = ρ_light · (ρ_dark / ρ_light)^((t − 2) / 5),
    extrapolated beyond them (tone 1 lighter, 8–10 darker)."""
    rgb = _LIGHT_SKIN * (_DARK_SKIN / _LIGHT_SKIN) ** ((tone - 2) / 5)
    return tuple(float(c) for c in np.clip(rgb, 0.003, 0.9))


HAIR_RGB: dict[str, tuple[float, float, float]] = {
    "black": (0.02, 0.015, 0.012),
    "dark_brown": (0.05, 0.03, 0.018),
    "brown": (0.12, 0.07, 0.04),
    "blond": (0.45, 0.33, 0.18),
    "red": (0.30, 0.10, 0.04),
    "grey": (0.35, 0.35, 0.35),
    "white": (0.65, 0.65, 0.63),
}

APPEARANCE_SPAWN_KEY = 0x6C6F_6F6B
"""Spawn key of the generator an identity's attributes are drawn from (ASCII "look")."""

Sex = Literal["female", "male"]
AgeGroup = Literal["child", "adult", "senior"]
Top = Literal["tshirt", "shirt", "jacket", "coat"]
Bottom = Literal["trousers", "shorts", "skirt"]
Bag = Literal["none", "backpack", "handbag"]
Season = Literal["summer", "winter", "mixed"]

STATURE_CM = {
    ("adult", "male"): (175.3, 7.4),
    ("adult", "female"): (161.3, 6.9),
    ("senior", "male"): (171.0, 7.0),
    ("senior", "female"): (156.0, 6.5),
}
STATURE_MIN_M, STATURE_MAX_M = 1.45, 1.95
CHILD_STATURE_CM = ((6.0, 116.0), (12.0, 150.0))
"""(age y, median cm) at both ends of the child group (WHO 2007 / CDC 2000), linear between."""


@dataclass(frozen=True)
class Appearance:
    """Every visible attribute of a person; all colours linear sRGB albedo."""

    sex: Sex
    age_group: AgeGroup
    age_years: float
    stature_m: float
    build: float
    """MakeHuman weight parameter, 0 thin … 1 heavy."""
    muscle: float
    skin_tone: int
    """Monk skin tone 1 (lightest) … 10."""
    hair_style: Literal["short", "long", "bald"]
    hair_colour: str
    top: Top
    top_colour: str
    long_sleeves: bool
    bottom: Bottom
    bottom_colour: str
    shoe_colour: str
    bag: Bag
    hat: bool
    identity_seed: int = 0
    """The seed everything above was drawn from (it also seeds the fabric's shading variation)."""

    @property
    def skin_rgb(self) -> tuple[float, float, float]:
        return skin_rgb(self.skin_tone)

    def attributes(self) -> dict[str, object]:
        """PA-100K-style attribute labels of what is rendered."""
        return {
            "female": self.sex == "female",
            "age_group": self.age_group,
            "age_years": round(self.age_years, 1),
            "stature_m": round(self.stature_m, 3),
            "hair": self.hair_style,
            "hair_colour": self.hair_colour,
            "hat": self.hat,
            "upper": self.top,
            "upper_colour": self.top_colour,
            "long_sleeves": self.long_sleeves,
            "lower": self.bottom,
            "lower_colour": self.bottom_colour,
            "shoe_colour": self.shoe_colour,
            "backpack": self.bag == "backpack",
            "handbag": self.bag == "handbag",
            "skin_tone_monk": self.skin_tone,
        }


def _choice(rng: np.random.Generator, table: dict[str, float]) -> str:
    names = list(table)
    p = np.array([table[n] for n in names], dtype=np.float64)
    return names[int(rng.choice(len(names), p=p / p.sum()))]


def draw_appearance(seed: int, *, season: Season = "mixed", pinned: dict[str, object] | None = None) -> Appearance:
    """The appearance of identity `seed`; `pinned` attributes (Appearance field → value) replace draws.

    Every draw is made whether or not it is pinned, so pinning one attribute leaves the others as
    they were.
    """
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(APPEARANCE_SPAWN_KEY,)))
    pinned = dict(pinned or {})
    u = rng.uniform(size=16)
    sex: Sex = "female" if u[0] < 0.5 else "male"
    sex = pinned.get("sex", sex)  # type: ignore[assignment]
    age_group: AgeGroup = "child" if u[1] < 0.08 else ("senior" if u[1] < 0.20 else "adult")
    age_group = pinned.get("age_group", age_group)  # type: ignore[assignment]
    z = float(np.clip(rng.standard_normal(), -2.5, 2.5))
    if age_group == "child":
        (a0, h0), (a1, h1) = CHILD_STATURE_CM
        age_years = a0 + (a1 - a0) * u[2]
        mean_cm = h0 + (h1 - h0) * (age_years - a0) / (a1 - a0)
        stature_m = mean_cm * (1 + 0.045 * z) / 100
    else:
        age_years = 18 + 47 * u[2] if age_group == "adult" else 65 + 20 * u[2]
        mean_cm, sd_cm = STATURE_CM[(age_group, sex)]
        stature_m = float(np.clip((mean_cm + sd_cm * z) / 100, STATURE_MIN_M, STATURE_MAX_M))
    build = float(rng.beta(4, 4))
    muscle = float(rng.beta(5, 5))
    skin_tone = int(rng.integers(1, 11))
    # Hair: grey rises with age (Panhard et al. 2012); long hair mostly for women.
    grey_p = 0.0 if age_years < 35 else min(0.8, (age_years - 35) / 40)
    natural = _choice(rng, {"black": 40, "dark_brown": 25, "brown": 20, "blond": 8, "red": 2})  # drawn always
    hair_colour = ("white" if u[4] < 0.3 else "grey") if u[3] < grey_p else natural
    long_p = 0.785 if sex == "female" else 0.006
    hair_style = "long" if u[5] < long_p else ("bald" if sex == "male" and age_years > 40 and u[6] < 0.15 else "short")
    season_now: Season = season if season != "mixed" else ("summer" if u[7] < 0.5 else "winter")
    winter = season_now == "winter"
    top_table = (
        {"tshirt": 10, "shirt": 25, "jacket": 45, "coat": 20}
        if winter
        else {"tshirt": 65, "shirt": 25, "jacket": 10, "coat": 0}
    )
    top: Top = _choice(rng, top_table)  # type: ignore[assignment]
    # Sleeves follow the top that is worn, pinned or drawn: a jacket or coat has long sleeves.
    worn_top = pinned.get("top", top)
    long_sleeves = bool(worn_top in ("jacket", "coat") or (worn_top == "shirt" and u[8] < 0.6))
    skirt_p = 0.297 if sex == "female" and age_group != "child" else (0.15 if sex == "female" else 0.0)
    shorts_p = 0.0 if winter else (0.45 if age_group == "child" else 0.35)
    bottom: Bottom = "skirt" if u[9] < skirt_p else ("shorts" if u[10] < shorts_p else "trousers")
    top_colour = _choice(rng, UPPER_COLOURS[season_now])
    bottom_colour = _choice(rng, LOWER_COLOURS[season_now])
    shoe_colour = _choice(rng, {"black": 55, "white": 20, "gray": 10, "brown": 15})
    bag: Bag = "backpack" if u[11] < 0.257 else ("handbag" if u[11] < 0.257 + 0.108 else "none")
    hat = bool(u[12] < (0.15 if winter else 0.03))
    appearance = Appearance(
        sex=sex,
        age_group=age_group,
        age_years=float(age_years),
        stature_m=float(stature_m),
        build=build,
        muscle=muscle,
        skin_tone=skin_tone,
        hair_style=hair_style,  # type: ignore[arg-type]
        hair_colour=hair_colour,
        top=top,
        top_colour=top_colour,
        long_sleeves=long_sleeves,
        bottom=bottom,
        bottom_colour=bottom_colour,
        shoe_colour=shoe_colour,
        bag=bag,
        hat=hat,
        identity_seed=int(seed),
    )
    return replace(appearance, **{k: v for k, v in pinned.items() if k not in ("sex", "age_group")})
