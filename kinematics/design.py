"""The mechanism's design parameters (paper Table I) and their validation.

A :class:`Design` holds the seven geometric parameters of the 3-(arc-P, P, 2-(UPS)) mechanism
plus the convention that fixes the zero of the arc stroke. Lengths are dimensionless (as in the
paper); angles are in degrees in every user-facing place.

Conventions (documented choices where the paper is silent):

* ``d_i`` is measured inward from the base radius: the carriage's radial coordinate is
  ``rho_i = r - d_i`` with ``d_i in [0, d_s]`` (paper eq. (11)).
* ``eta_range="centered"`` (default): ``eta_i in [-eta_s/2, +eta_s/2]`` around ``gamma_i``;
  ``eta_range="from-zero"``: ``eta_i in [0, eta_s]``. The paper writes ``varpi_i = eta_i +
  gamma_i`` and calls ``eta_s`` the stroke without saying where it starts; the centered range
  keeps the mechanism's mirror symmetry, the from-zero range breaks it.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Literal

EtaRange = Literal["centered", "from-zero"]
ETA_RANGES: tuple[str, ...] = ("centered", "from-zero")


class ParameterError(ValueError):
    """A user-supplied value is outside its valid range; names the field and the range."""

    def __init__(self, field: str, value: Any, valid: str) -> None:
        self.field = field
        self.value = value
        self.valid = valid
        kind = "valid range" if valid.startswith(("[", "(")) else "expected"
        super().__init__(f"{field} = {value!r} is invalid: {kind} {valid}")


@dataclasses.dataclass(frozen=True)
class ParamSpec:
    """Range information of one design parameter.

    ``model_min``/``model_max`` bound what the model accepts (every entry point accepts exactly
    this range); ``slider_min``/``slider_max`` are the ranges of paper Table I (used by the
    explorer's sliders and by parameter studies), or a practical range around the value where
    Table I fixes one (``table_fixed``: b, r, l_min).
    """

    name: str
    description: str
    default: float
    model_min: float
    model_max: float
    slider_min: float
    slider_max: float
    unit: str = ""
    table_fixed: float | None = None
    #: a label of a few words for a control ("platform radius"); the description is the long form
    short: str = ""

    @property
    def label(self) -> str:
        """The control's label: the paper's symbol, its name in words and a unit other than length,
        e.g. ``"eta_s · arc stroke (deg)"``."""
        unit = f" ({self.unit})" if self.unit else ""
        return f"{self.name} · {self.short or self.description}{unit}"


PARAMS: dict[str, ParamSpec] = {
    "a": ParamSpec("a", "radius of the moving platform", 50.0, 1e-6, 1000.0, 10.0, 100.0,
                   short="platform radius"),
    "b": ParamSpec("b", "spacing of a carriage's two U joints", 14.0, 0.0, 1000.0, 0.0, 40.0, table_fixed=14.0,
                   short="U-joint spacing"),
    "d_s": ParamSpec("d_s", "stroke of the radial prismatic joint", 50.0, 0.0, 1000.0, 10.0, 100.0,
                     short="radial stroke"),
    "r": ParamSpec("r", "radius of the fixed base", 100.0, 1e-6, 1000.0, 50.0, 200.0, table_fixed=100.0,
                   short="base radius"),
    "l_min": ParamSpec("l_min", "minimum leg length", 114.5, 1e-6, 1000.0, 50.0, 200.0, table_fixed=114.5,
                       short="shortest leg"),
    "l_s": ParamSpec("l_s", "stroke of the leg prismatic joint", 50.0, 0.0, 1000.0, 10.0, 100.0,
                     short="leg stroke"),
    "eta_s": ParamSpec("eta_s", "stroke of the arc joint", 30.0, 0.0, 180.0, 10.0, 100.0, "deg",
                       short="arc stroke"),
}
PARAM_NAMES: tuple[str, ...] = tuple(PARAMS)


def paper_range_text(name: str) -> str:
    """What paper Table I says about a parameter, and the explorer's slider range: "Table I range
    [10, 100]" or "Table I fixes b = 14 (slider [0, 40])"."""
    spec = PARAMS[name]
    unit = " deg" if spec.unit else ""
    if spec.table_fixed is not None:
        return f"Table I fixes {name} = {spec.table_fixed:g}{unit} (slider [{spec.slider_min:g}, {spec.slider_max:g}])"
    return f"Table I range [{spec.slider_min:g}, {spec.slider_max:g}]{unit}"


def _check_number(field: str, value: Any, lo: float, hi: float, hi_text: str | None = None) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(field, value, f"[{lo:g}, {hi_text or f'{hi:g}'}] (a number)") from None
    if not math.isfinite(v) or v < lo or v > hi:
        raise ParameterError(field, value, f"[{lo:g}, {hi_text or f'{hi:g}'}]")
    return v


@dataclasses.dataclass(frozen=True)
class Design:
    """Geometric design of the mechanism (paper Table I); defaults are the paper's Fig. 3 design.

    Attributes:
        a: platform radius; platform joints ``B_i^j`` lie at radius ``a`` (eq. (4)).
        b: distance between the two U joints ``D_i^1, D_i^2`` of one carriage (eq. (11)).
        d_s: stroke of the radial joint, ``d_i in [0, d_s]``, ``d_s <= r``.
        r: base radius.
        l_min: minimum leg length; legs have ``l in [l_min, l_min + l_s]``.
        l_s: leg stroke.
        eta_s: stroke of the arc joint in degrees.
        eta_range: ``"centered"`` or ``"from-zero"`` (see module docstring).
    """

    a: float = 50.0
    b: float = 14.0
    d_s: float = 50.0
    r: float = 100.0
    l_min: float = 114.5
    l_s: float = 50.0
    eta_s: float = 30.0
    eta_range: EtaRange = "centered"

    def __post_init__(self) -> None:
        for name, spec in PARAMS.items():
            hi = spec.model_max
            hi_text = None
            if name == "d_s":
                r = _check_number("r", self.r, PARAMS["r"].model_min, PARAMS["r"].model_max)
                hi, hi_text = r, f"r={r:g}"
            object.__setattr__(self, name, _check_number(name, getattr(self, name), spec.model_min, hi, hi_text))
        if self.eta_range not in ETA_RANGES:
            raise ParameterError("eta_range", self.eta_range, " or ".join(ETA_RANGES))

    # ----- derived quantities -------------------------------------------------------------
    @property
    def l_max(self) -> float:
        """Maximum leg length ``l_min + l_s``."""
        return self.l_min + self.l_s

    @property
    def rho_limits(self) -> tuple[float, float]:
        """Radial carriage coordinate range ``rho = r - d`` for ``d in [0, d_s]``."""
        return (self.r - self.d_s, self.r)

    @property
    def eta_limits(self) -> tuple[float, float]:
        """Arc-joint range ``[eta_lo, eta_hi]`` in degrees under the design's convention."""
        if self.eta_range == "centered":
            return (-0.5 * self.eta_s, 0.5 * self.eta_s)
        return (0.0, self.eta_s)

    def mirror_symmetric(self, orientation: tuple[float, float, float]) -> bool:
        """Whether the workspace at the platform ``orientation`` (ZYX Euler angles, degrees) is
        symmetric under ``y -> -y`` (chain 1 onto itself, chains 2 and 3 swapped): the centered arc
        range and zero orientation."""
        return self.eta_range == "centered" and all(abs(a) == 0.0 for a in orientation)

    @property
    def characteristic_length(self) -> float:
        """``L = a / 2`` used to make the Jacobian dimensionally homogeneous (paper, eq. (26))."""
        return 0.5 * self.a

    def replace(self, **changes: Any) -> Design:
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-serializable dict of the fields."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Design:
        """Build from a dict, rejecting unknown keys with a :class:`ParameterError`."""
        known = {f.name for f in dataclasses.fields(cls)}
        for key in data:
            if key not in known:
                raise ParameterError(key, data[key], "not a design field; fields: " + ", ".join(sorted(known)))
        return cls(**data)

    def key(self) -> tuple:
        """Hashable identity used by caches."""
        return dataclasses.astuple(self)


def check_pose_value(field: str, value: Any, lo: float, hi: float) -> float:
    """Validate one pose/setting number, raising :class:`ParameterError` naming ``field``."""
    return _check_number(field, value, lo, hi)
