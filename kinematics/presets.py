"""Preset mechanisms: functions of named parameters that build a :class:`~kinematics.mechanism.Mechanism`.

* :func:`paper`: the 3-(arc-P, P, 2-(UPS)) of the paper with Table I's parameters. Chain ``i``
  (``gamma_i = 0, 120, 240`` degrees) is a revolute about ``z`` (the arc, ``eta_i``) then a
  prismatic along ``-e(gamma_i)`` (the radial ``d_i``, inward from ``r``), carrying two legs from
  ``Rz(gamma_i) [r, +-b/2, 0]`` to ``Rz(gamma_i) [sqrt(3) a/2, +-a/2, 0]``: by (M1)-(M2)
  ``D_i^j = Rz(gamma_i + eta_i) [r - d_i, +-b/2, 0]``, the paper's eq. (11).
* :func:`gough_stewart`: a 6-UPS on semi-regular hexagons: base joints in pairs at
  ``0/120/240 +- base_half_angle`` on ``base_radius``, platform joints in pairs at
  ``60/180/300 +- platform_half_angle`` on ``platform_radius``; the leg from the base joint at
  ``gamma + alpha`` goes to the platform joint at ``gamma + 60 - beta`` (and its mirror). With
  ``base_radius = sqrt(r^2 + b^2/4)``, ``base_half_angle = atan(b / 2r)``, ``platform_radius = a``
  and ``platform_half_angle = 30`` it is the paper's mechanism with ``d_s = eta_s = 0``.
* :func:`six_pups`: that Gough-Stewart platform with a vertical prismatic joint (stroke ``lift``)
  under each leg: a kinematically redundant hexapod (Kotlarski et al.).
* :func:`six_pss`: six fixed-length legs on vertical rails (stroke ``rail_stroke``): the
  Linapod / Hexaglide family with vertical rails.

:data:`PRESETS` maps each name to its function and its parameters' defaults, ranges and words,
for the CLI (``--mechanism NAME --param NAME=VALUE``), REST and the explorer. A
:class:`PresetDesign` (a preset's name and all its parameters' values) is one point of a study:
what the sweeps and the optimiser vary for a general mechanism, as :class:`Design` for the paper's.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from typing import Any

from .design import PARAMS, Design, ParameterError
from .mechanism import CarriageJoint, Chain, Leg, Mechanism

GAMMAS_DEG = (0.0, 120.0, 240.0)


def _rz(angle_deg: float, v: tuple[float, float, float]) -> tuple[float, float, float]:
    c, s = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    return (c * v[0] - s * v[1], s * v[0] + c * v[1], v[2])


def paper(a: float = 50.0, b: float = 14.0, d_s: float = 50.0, r: float = 100.0, l_min: float = 114.5,
          l_s: float = 50.0, eta_s: float = 30.0, eta_range: str = "centered") -> Mechanism:
    """The paper's 3-(arc-P, P, 2-(UPS)) mechanism (Table I names; validated as :class:`Design` is)."""
    design = Design(a=a, b=b, d_s=d_s, r=r, l_min=l_min, l_s=l_s, eta_s=eta_s, eta_range=eta_range)  # type: ignore[arg-type]
    lo, hi = design.eta_limits
    chains = []
    for gamma in GAMMAS_DEG:
        carriage = (
            CarriageJoint("revolute", (0.0, 0.0, 1.0), (lo, hi)),
            CarriageJoint("prismatic", _rz(gamma, (-1.0, 0.0, 0.0)), (0.0, design.d_s)),
        )
        legs = tuple(
            Leg(base=_rz(gamma, (design.r, sign * design.b / 2.0, 0.0)),
                platform=_rz(gamma, (math.sqrt(3.0) * design.a / 2.0, sign * design.a / 2.0, 0.0)),
                length=(design.l_min, design.l_max))
            for sign in (1.0, -1.0))
        chains.append(Chain(carriage, legs))
    return Mechanism("paper 3-(arc-P, P, 2-(UPS))", tuple(chains))


def _hexapod_legs(base_radius: float, base_half_angle: float, platform_radius: float,
                  platform_half_angle: float, length: tuple[float, float]) -> list[Leg]:
    legs = []
    for gamma in GAMMAS_DEG:
        for sign in (1.0, -1.0):
            base_angle = gamma + sign * base_half_angle
            plat_angle = gamma + sign * (60.0 - platform_half_angle)
            legs.append(Leg(
                base=(base_radius * math.cos(math.radians(base_angle)),
                      base_radius * math.sin(math.radians(base_angle)), 0.0),
                platform=(platform_radius * math.cos(math.radians(plat_angle)),
                          platform_radius * math.sin(math.radians(plat_angle)), 0.0),
                length=length))
    return legs


def _check(name: str, value: float, lo: float, hi: float, unit: str = "") -> float:
    bad_type = isinstance(value, bool) or not isinstance(value, (int, float))
    if bad_type or not math.isfinite(value) or not lo <= value <= hi:
        raise ParameterError(name, value, f"[{lo:g}, {hi:g}]{' ' + unit if unit else ''}")
    return float(value)


def gough_stewart(base_radius: float = 100.0, base_half_angle: float = 5.0, platform_radius: float = 50.0,
                  platform_half_angle: float = 10.0, l_min: float = 114.5, l_max: float = 164.5) -> Mechanism:
    """A 6-UPS Gough-Stewart platform on semi-regular hexagons (narrow pairs by default)."""
    _check("base_radius", base_radius, 1e-6, 1000.0)
    _check("base_half_angle", base_half_angle, 0.0, 59.0, "deg")
    _check("platform_radius", platform_radius, 1e-6, 1000.0)
    _check("platform_half_angle", platform_half_angle, 1.0, 60.0, "deg")
    _check("l_min", l_min, 1e-6, 1000.0)
    _check("l_max", l_max, 1e-6, 1000.0)
    if l_max <= l_min:
        raise ParameterError("l_max", l_max, f"(l_min={l_min:g}, 1000]: a UPS leg needs l_min < l_max")
    legs = _hexapod_legs(base_radius, base_half_angle, platform_radius, platform_half_angle, (l_min, l_max))
    return Mechanism("gough-stewart 6-UPS", tuple(Chain((), (leg,)) for leg in legs))


def six_pups(base_radius: float = 100.0, base_half_angle: float = 5.0, platform_radius: float = 50.0,
             platform_half_angle: float = 10.0, l_min: float = 114.5, l_max: float = 164.5,
             lift: float = 50.0) -> Mechanism:
    """A Gough-Stewart platform with a vertical prismatic joint of stroke ``[0, lift]`` under each leg."""
    gs = gough_stewart(base_radius, base_half_angle, platform_radius, platform_half_angle, l_min, l_max)
    _check("lift", lift, 0.0, 1000.0)
    joint = CarriageJoint("prismatic", (0.0, 0.0, 1.0), (0.0, float(lift)))
    return Mechanism("6-PUPS (vertical lifts)", tuple(Chain((joint,), c.legs) for c in gs.chains))


def six_pss(base_radius: float = 100.0, base_half_angle: float = 5.0, platform_radius: float = 50.0,
            platform_half_angle: float = 10.0, leg_length: float = 120.0, rail_stroke: float = 150.0) -> Mechanism:
    """Six fixed-length legs on vertical rails of stroke ``[0, rail_stroke]`` (6-PSS, Linapod-like)."""
    _check("leg_length", leg_length, 1e-6, 1000.0)
    _check("rail_stroke", rail_stroke, 0.0, 1000.0)
    gs = gough_stewart(base_radius, base_half_angle, platform_radius, platform_half_angle, leg_length, leg_length + 1.0)
    joint = CarriageJoint("prismatic", (0.0, 0.0, 1.0), (0.0, float(rail_stroke)))
    chains = tuple(Chain((joint,), tuple(dataclasses.replace(leg, length=(leg_length, leg_length)) for leg in c.legs))
                   for c in gs.chains)
    return Mechanism("6-PSS (vertical rails, fixed legs)", chains)


@dataclasses.dataclass(frozen=True)
class PresetParam:
    """One preset parameter: default, valid range, unit and words; ``study`` is the range a study
    (the optimiser's default bounds, a sweep's ``n`` values) spans, within ``[lo, hi]`` (``None``:
    ``[lo, hi]``; a text parameter has none and is never free)."""

    name: str
    default: float | str
    lo: float
    hi: float
    unit: str
    description: str
    study: tuple[float, float] | None = None

    @property
    def numeric(self) -> bool:
        """Whether the parameter is a number (a study can vary it)."""
        return not isinstance(self.default, str)

    @property
    def study_range(self) -> tuple[float, float]:
        """``study``, else the valid range ``(lo, hi)``."""
        return self.study if self.study is not None else (self.lo, self.hi)


@dataclasses.dataclass(frozen=True)
class Preset:
    """A preset: its builder and its parameters."""

    name: str
    description: str
    build: Callable[..., Mechanism]
    params: tuple[PresetParam, ...]

    def mechanism(self, values: Mapping[str, Any] | None = None) -> Mechanism:
        """Build with the defaults overridden by ``values`` (unknown names refused by name)."""
        values = dict(values or {})
        known = {p.name for p in self.params}
        for key in values:
            if key not in known:
                raise ParameterError(key, values[key],
                                     f"a parameter of preset {self.name!r}: {', '.join(sorted(known))}")
        return self.build(**values)


_HEX = (
    PresetParam("base_radius", 100.0, 1e-6, 1000.0, "", "radius of the base joints' circle", (60.0, 160.0)),
    PresetParam("base_half_angle", 5.0, 0.0, 59.0, "deg", "half the angle between a base pair's joints",
                (0.0, 30.0)),
    PresetParam("platform_radius", 50.0, 1e-6, 1000.0, "", "radius of the platform joints' circle", (25.0, 100.0)),
    PresetParam("platform_half_angle", 10.0, 1.0, 60.0, "deg", "half the angle between a platform pair's joints",
                (1.0, 30.0)),
)
_LEGS = (
    PresetParam("l_min", 114.5, 1e-6, 1000.0, "", "shortest leg length", (80.0, 150.0)),
    PresetParam("l_max", 164.5, 1e-6, 1000.0, "", "longest leg length", (120.0, 220.0)),
)

PRESETS: dict[str, Preset] = {
    "paper": Preset("paper", "the paper's 3-(arc-P, P, 2-(UPS)) (Table I)", paper, tuple(
        PresetParam(p.name, p.default, p.model_min, p.model_max, p.unit, p.description, (p.slider_min, p.slider_max))
        for p in PARAMS.values()
    ) + (PresetParam("eta_range", "centered", 0.0, 0.0, "", "arc stroke convention: centered or from-zero"),)),
    "gough-stewart": Preset("gough-stewart", "a 6-UPS Gough-Stewart platform (semi-regular hexagons)",
                            gough_stewart, _HEX + _LEGS),
    "6-pups": Preset("6-pups", "a Gough-Stewart platform with a vertical lift under each leg (6-PUPS)",
                     six_pups, _HEX + _LEGS + (
                         PresetParam("lift", 50.0, 0.0, 1000.0, "", "stroke of each vertical lift", (0.0, 100.0)),)),
    "6-pss": Preset("6-pss", "six fixed-length legs on vertical rails (6-PSS)", six_pss, _HEX + (
        PresetParam("leg_length", 120.0, 1e-6, 1000.0, "", "length of every leg", (80.0, 200.0)),
        PresetParam("rail_stroke", 150.0, 0.0, 1000.0, "", "stroke of each vertical rail", (50.0, 250.0)))),
}


def preset(name: str, values: Mapping[str, Any] | None = None) -> Mechanism:
    """The preset ``name`` (see :data:`PRESETS`) with parameters ``values``."""
    if name not in PRESETS:
        raise ParameterError("mechanism", name, f"one of the presets {', '.join(PRESETS)} or a description file")
    return PRESETS[name].mechanism(values)


@dataclasses.dataclass(frozen=True)
class PresetDesign:
    """A point of a preset's parameter space: the preset's name and EVERY parameter's value (the
    defaults filled in, numbers as floats), in the preset's order. What a study (sweep, optimiser)
    varies for a general mechanism, as :class:`~kinematics.design.Design` is for the paper's model:
    :meth:`of` validates (builds the mechanism, so a bad value raises ParameterError naming it)."""

    preset: str
    values: tuple[tuple[str, float | str], ...]

    @classmethod
    def of(cls, name: str, values: Mapping[str, Any] | None = None) -> PresetDesign:
        """The preset ``name`` with ``values`` over its defaults (validated)."""
        if not isinstance(name, str) or name not in PRESETS:
            raise ParameterError("mechanism", name, f"one of the presets {', '.join(PRESETS)}")
        spec = PRESETS[name]
        given = dict(values or {})
        spec.mechanism(given)  # names and values validated by the builder
        full = {p.name: given.get(p.name, p.default) for p in spec.params}
        norm = tuple((k, v if isinstance(v, str) else float(v)) for k, v in full.items())
        return cls(name, norm)

    def mechanism(self) -> Mechanism:
        """The described mechanism."""
        return PRESETS[self.preset].mechanism(dict(self.values))

    def replace(self, **changes: Any) -> PresetDesign:
        """A copy with some parameters changed (validated)."""
        return PresetDesign.of(self.preset, {**dict(self.values), **changes})

    def to_dict(self) -> dict[str, Any]:
        """``{"preset": name, parameter: value, ...}`` (what a study's rows carry as ``design``)."""
        return {"preset": self.preset, **dict(self.values)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> PresetDesign:
        """The inverse of :meth:`to_dict`."""
        return cls.of(d.get("preset"), {k: v for k, v in d.items() if k != "preset"})  # type: ignore[arg-type]

    def key(self) -> tuple:
        """Hashable identity."""
        return ("preset", self.preset, self.values)
