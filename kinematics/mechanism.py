"""A mechanism description: chains of actuated carriage joints, each carrying U(S)-P-S legs to one
moving platform. The paper's 3-(arc-P, P, 2-(UPS)) is one instance (:mod:`kinematics.presets`).

**Definition.** A mechanism has chains ``c = 1..C``. Chain ``c`` has an ordered list of carriage
joints ``J_1 .. J_k`` from the base outward, each with a joint value ``q_m`` in ``[lo_m, hi_m]``:

* revolute about the unit axis ``n_m`` through the base origin, ``q`` in degrees:
  ``T_m(q) = (Rot(n_m, q), 0)``;
* prismatic along the unit axis ``u_m``: ``T_m(q) = (I, q u_m)``.

Each axis is written in the frame after the joints before it (at their current values), so the
carriage's pose is the product of rigid transforms from the base outward

    T_c(q) = T_1(q_1) T_2(q_2) ... T_k(q_k).                                             (M1)

Leg ``j`` of chain ``c`` has a base joint point ``D0_j`` (the carriage frame, which coincides with
the base frame at zero joint values) and a platform joint point ``u_j`` (the platform frame). At
carriage values ``q`` and platform pose ``(p, R)``

    D_j(q) = T_c(q) D0_j,    B_j = p + R u_j,    l_j = |B_j - D_j(q)|  in  [lmin_j, lmax_j].   (M2)

A platform pose is reachable when every chain has some ``q`` in its box with all its legs in
range (and, when given, each leg inside its joint cones, :mod:`kinematics.joints` (J1)). The
workspace is that of the platform frame's origin.

**What the family covers.** A chain's carriage has at most one revolute and at most two prismatic
joints (the paper's arc + radial carriage, a vertical lift, an x-y table), or none (a fixed base:
the Gough-Stewart platform). A leg's length range may be one value (a fixed-length leg, the
Hexaglide/Linapod family) only where its chain has a prismatic joint to carry it. The platform
has six degrees of freedom, so the description has exactly six legs. Anything else is refused
with a message naming the field (``chains[1].carriage[0].axis``), its value and what is expected.

A description is data: it is read from TOML (or the same structure as JSON) and bounded in size
(:data:`MAX_CHAINS`, :data:`MAX_LEGS`, :data:`MAX_TEXT_BYTES`).
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from collections.abc import Mapping, Sequence
from typing import Any, Literal

import numpy as np

from .design import ParameterError
from .rotation import euler_zyx_deg

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

JointType = Literal["revolute", "prismatic"]
JOINT_TYPES: tuple[str, ...] = ("revolute", "prismatic")

#: Most chains a description may have (one leg each for a Gough-Stewart platform).
MAX_CHAINS = 6
#: Legs of a description: the platform has six degrees of freedom.
LEGS = 6
MAX_LEGS = LEGS
#: Largest description text accepted (TOML or JSON), bytes.
MAX_TEXT_BYTES = 64 * 1024
#: Largest absolute coordinate or length in a description (the model's length bound).
MAX_COORD = 1000.0


@dataclasses.dataclass(frozen=True)
class CarriageJoint:
    """One actuated carriage joint: ``type`` revolute (``range`` in degrees) or prismatic (length
    units), its unit ``axis`` in the frame after the joints before it, and its ``range``."""

    type: JointType
    axis: tuple[float, float, float]
    range: tuple[float, float]

    def transform(self, q: float) -> tuple[np.ndarray, np.ndarray]:
        """``(R, t)`` of (M1) at joint value ``q``."""
        axis = np.asarray(self.axis, float)
        if self.type == "revolute":
            return _axis_rotation(axis, math.radians(q)), np.zeros(3)
        return np.eye(3), q * axis


@dataclasses.dataclass(frozen=True)
class Cone:
    """A joint cone: the leg direction stays within ``angle`` degrees of ``axis`` (unit)."""

    axis: tuple[float, float, float]
    angle: float


@dataclasses.dataclass(frozen=True)
class Leg:
    """A U(or S)-P-S leg: base joint point in the carriage frame at zero joint values, platform
    joint point in the platform frame, length range ``[lmin, lmax]``, optional cones and diameter."""

    base: tuple[float, float, float]
    platform: tuple[float, float, float]
    length: tuple[float, float]
    u_cone: Cone | None = None
    s_cone: Cone | None = None
    diameter: float = 0.0


@dataclasses.dataclass(frozen=True)
class Chain:
    """A carriage (its joints from the base outward; empty for a fixed base) and the legs it carries."""

    carriage: tuple[CarriageJoint, ...]
    legs: tuple[Leg, ...]

    def transform(self, q: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
        """(M1): the carriage's ``(R, t)`` at joint values ``q`` (one per carriage joint)."""
        rot, trans = np.eye(3), np.zeros(3)
        for joint, value in zip(self.carriage, q):
            r_m, t_m = joint.transform(float(value))
            trans = trans + rot @ t_m
            rot = rot @ r_m
        return rot, trans

    def base_points(self, q: Sequence[float]) -> np.ndarray:
        """(M2): the legs' base joints ``D_j(q)`` in the base frame, shape (legs, 3)."""
        rot, trans = self.transform(q)
        return np.array([leg.base for leg in self.legs], float) @ rot.T + trans


@dataclasses.dataclass(frozen=True)
class Mechanism:
    """A validated mechanism description (see the module docstring for the model).

    ``reference`` names the frame of the orientation convention: the platform's angles
    ``psi, theta, phi`` (Z-Y-X) are measured from the base frame rotated by ``reference``
    (Z-Y-X degrees; zero by default).
    """

    name: str
    chains: tuple[Chain, ...]
    reference: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def legs(self) -> list[tuple[int, int, Leg]]:
        """Every leg as ``(chain index, leg index in its chain, leg)``, in description order."""
        return [(c, j, leg) for c, chain in enumerate(self.chains) for j, leg in enumerate(chain.legs)]

    def platform_points(self, position: Sequence[float] | np.ndarray, rotation: np.ndarray) -> np.ndarray:
        """(M2): ``B_j = p + R u_j`` for every leg in description order, shape (6, 3)."""
        u = np.array([leg.platform for _, _, leg in self.legs], float)
        return np.asarray(position, float) + u @ np.asarray(rotation, float).T

    def base_points(self, q: Sequence[Sequence[float]]) -> np.ndarray:
        """(M2): every leg's base joint at carriage values ``q[c]`` per chain, shape (6, 3)."""
        if len(q) != len(self.chains):
            raise ValueError(f"carriage values for {len(q)} chains, the mechanism has {len(self.chains)}")
        return np.concatenate([chain.base_points(qc) for chain, qc in zip(self.chains, q)], axis=0)

    def leg_lengths(self, q: Sequence[Sequence[float]], position: Sequence[float],
                    rotation: np.ndarray) -> np.ndarray:
        """(M2): the six leg lengths at carriage values ``q`` and platform pose ``(p, R)``."""
        return np.linalg.norm(self.platform_points(position, rotation) - self.base_points(q), axis=-1)

    def to_dict(self) -> dict[str, Any]:
        """The description as plain data (the structure of the TOML file)."""
        out: dict[str, Any] = {"name": self.name}
        if any(self.reference):
            out["reference"] = list(self.reference)
        chains = []
        for chain in self.chains:
            carriage = [{"type": j.type, "axis": list(j.axis), "range": list(j.range)} for j in chain.carriage]
            legs = []
            for leg in chain.legs:
                d: dict[str, Any] = {"base": list(leg.base), "platform": list(leg.platform),
                                     "length": list(leg.length)}
                for key in ("u_cone", "s_cone"):
                    cone = getattr(leg, key)
                    if cone is not None:
                        d[key] = {"axis": list(cone.axis), "angle": cone.angle}
                if leg.diameter:
                    d["diameter"] = leg.diameter
                legs.append(d)
            chains.append({"carriage": carriage, "legs": legs})
        out["chains"] = chains
        return out


def _axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues: rotation by ``angle`` (radians) about the unit ``axis``."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


# -- validation: one message per bad field (path, value, what is expected) -------------------------

def _number(path: str, value: Any, lo: float = -MAX_COORD, hi: float = MAX_COORD) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(path, value, f"a number in [{lo:g}, {hi:g}]")
    if not lo <= value <= hi:
        raise ParameterError(path, value, f"[{lo:g}, {hi:g}]")
    return float(value)


def _vector(path: str, value: Any, unit: bool = False) -> tuple[float, float, float]:
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise ParameterError(path, value, "three numbers [x, y, z]")
    v = tuple(_number(f"{path}[{k}]", x) for k, x in enumerate(value))
    if unit:
        norm = math.sqrt(sum(x * x for x in v))
        if norm < 1e-9:
            raise ParameterError(path, list(value), "a non-zero axis [x, y, z]")
        if abs(norm - 1.0) > 1e-12:  # a unit axis is kept as written (a file round-trips exactly)
            v = tuple(x / norm for x in v)
    return v  # type: ignore[return-value]


def _range(path: str, value: Any, lo: float, hi: float, unit: str) -> tuple[float, float]:
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise ParameterError(path, value, f"[low, high] {unit}")
    a = _number(f"{path}[0]", value[0], lo, hi)
    b = _number(f"{path}[1]", value[1], lo, hi)
    if a > b:
        raise ParameterError(path, list(value), f"[low, high] {unit} with low <= high")
    return a, b


def _keys(path: str, data: Mapping[str, Any], allowed: Sequence[str], required: Sequence[str]) -> None:
    if not isinstance(data, Mapping):
        raise ParameterError(path or "mechanism", data, "a table {key = value, ...}")
    for key in data:
        if key not in allowed:
            raise ParameterError(f"{path}.{key}" if path else str(key), data[key],
                                 f"one of the keys {', '.join(allowed)} (unknown key)")
    for key in required:
        if key not in data:
            raise ParameterError(f"{path}.{key}" if path else key, None, "a value (the key is required)")


def _cone(path: str, data: Any) -> Cone:
    _keys(path, data, ("axis", "angle"), ("axis", "angle"))
    angle = _number(f"{path}.angle", data["angle"], 0.0, 90.0)
    if angle <= 0.0:
        raise ParameterError(f"{path}.angle", data["angle"], "(0, 90] degrees")
    return Cone(_vector(f"{path}.axis", data["axis"], unit=True), angle)


def _joint(path: str, data: Any) -> CarriageJoint:
    _keys(path, data, ("type", "axis", "range"), ("type", "axis", "range"))
    kind = data["type"]
    if kind not in JOINT_TYPES:
        raise ParameterError(f"{path}.type", kind, "'revolute' or 'prismatic'")
    axis = _vector(f"{path}.axis", data["axis"], unit=True)
    if kind == "revolute":
        rng = _range(f"{path}.range", data["range"], -180.0, 180.0, "degrees")
    else:
        rng = _range(f"{path}.range", data["range"], -MAX_COORD, MAX_COORD, "(length units)")
    return CarriageJoint(kind, axis, rng)


def _leg(path: str, data: Any) -> Leg:
    _keys(path, data, ("base", "platform", "length", "u_cone", "s_cone", "diameter"),
          ("base", "platform", "length"))
    length = _range(f"{path}.length", data["length"], 0.0, MAX_COORD, "(length units)")
    if length[0] <= 0.0:
        raise ParameterError(f"{path}.length", list(data["length"]), "[l_min, l_max] with 0 < l_min <= l_max")
    return Leg(
        base=_vector(f"{path}.base", data["base"]),
        platform=_vector(f"{path}.platform", data["platform"]),
        length=length,
        u_cone=_cone(f"{path}.u_cone", data["u_cone"]) if "u_cone" in data else None,
        s_cone=_cone(f"{path}.s_cone", data["s_cone"]) if "s_cone" in data else None,
        diameter=_number(f"{path}.diameter", data.get("diameter", 0.0), 0.0, 100.0),
    )


def _chain(path: str, data: Any) -> Chain:
    _keys(path, data, ("carriage", "legs"), ("legs",))
    raw_joints = data.get("carriage", [])
    if not isinstance(raw_joints, (list, tuple)):
        raise ParameterError(f"{path}.carriage", raw_joints, "a list of joints ([] for a fixed base)")
    joints = tuple(_joint(f"{path}.carriage[{m}]", j) for m, j in enumerate(raw_joints))
    revolute = sum(j.type == "revolute" for j in joints)
    prismatic = sum(j.type == "prismatic" for j in joints)
    if revolute > 1 or prismatic > 2:
        raise ParameterError(f"{path}.carriage", [j.type for j in joints],
                             "at most one revolute and at most two prismatic joints")
    raw_legs = data["legs"]
    if not isinstance(raw_legs, (list, tuple)) or not raw_legs:
        raise ParameterError(f"{path}.legs", raw_legs, "a list of one or more legs")
    legs = tuple(_leg(f"{path}.legs[{j}]", leg) for j, leg in enumerate(raw_legs))
    for j, leg in enumerate(legs):
        if leg.length[0] == leg.length[1] and prismatic == 0:
            raise ParameterError(f"{path}.legs[{j}].length", list(leg.length),
                                 "l_min < l_max: a fixed-length leg needs a prismatic carriage joint to carry it")
    return Chain(joints, legs)


def parse_mechanism(data: Any) -> Mechanism:
    """Validate plain data (the TOML/JSON structure) into a :class:`Mechanism`.

    Raises :class:`~kinematics.design.ParameterError` naming the first bad field by its path
    (``chains[0].legs[1].length``), its value and what is expected.
    """
    _keys("", data, ("name", "chains", "reference"), ("chains",))
    name = data.get("name", "mechanism")
    if not isinstance(name, str) or len(name) > 200:
        raise ParameterError("name", name, "a text of at most 200 characters")
    raw = data["chains"]
    if not isinstance(raw, (list, tuple)) or not 1 <= len(raw) <= MAX_CHAINS:
        raise ParameterError("chains", raw if not isinstance(raw, (list, tuple)) else f"{len(raw)} chains",
                             f"a list of 1 to {MAX_CHAINS} chains")
    chains = tuple(_chain(f"chains[{c}]", chain) for c, chain in enumerate(raw))
    total = sum(len(chain.legs) for chain in chains)
    if total != LEGS:
        raise ParameterError("chains", f"{total} legs in all", f"exactly {LEGS} legs in all (a 6-DOF platform)")
    reference = (0.0, 0.0, 0.0)
    if "reference" in data:
        reference = _vector("reference", data["reference"])
    return Mechanism(name, chains, reference)


def loads_mechanism(text: str | bytes) -> Mechanism:
    """Parse a description from TOML, or from JSON when the text starts with ``{``."""
    if isinstance(text, bytes):
        if len(text) > MAX_TEXT_BYTES:
            raise ParameterError("mechanism", f"{len(text):,} bytes",
                                 f"a description of at most {MAX_TEXT_BYTES:,} bytes")
        text = text.decode("utf-8")
    if len(text.encode("utf-8")) > MAX_TEXT_BYTES:
        raise ParameterError("mechanism", f"{len(text.encode('utf-8')):,} bytes",
                             f"a description of at most {MAX_TEXT_BYTES:,} bytes")
    if text.lstrip().startswith("{"):
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ParameterError("mechanism", f"JSON error at line {exc.lineno}: {exc.msg}", "valid JSON") from None
    else:
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ParameterError("mechanism", f"TOML error: {exc}", "valid TOML") from None
    return parse_mechanism(data)


def _toml_value(value: Any) -> str:
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(float(value)) if isinstance(value, float) else str(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{ " + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"cannot write {type(value).__name__} as TOML")


def dumps_mechanism(mech: Mechanism) -> str:
    """The description as a TOML file that :func:`loads_mechanism` reads back to the same mechanism."""
    data = mech.to_dict()
    lines = [f"name = {_toml_value(data['name'])}"]
    if "reference" in data:
        lines.append(f"reference = {_toml_value(data['reference'])}  # Z-Y-X degrees of the angles' zero")
    for chain in data["chains"]:
        lines += ["", "[[chains]]"]
        if chain["carriage"]:
            lines.append("carriage = [")
            lines += [f"  {_toml_value(j)}," for j in chain["carriage"]]
            lines.append("]")
        else:
            lines.append("carriage = []  # a fixed base")
        lines.append("legs = [")
        lines += [f"  {_toml_value(leg)}," for leg in chain["legs"]]
        lines.append("]")
    return "\n".join(lines) + "\n"


def _count(samples: int | Mapping[str, int], kind: str) -> int:
    return int(samples[kind]) if isinstance(samples, Mapping) else int(samples)


def carriage_samples(chain: Chain, samples: int | Mapping[str, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A chain's carriage on a grid of ``samples`` values per joint (one where the range is one
    value; ``samples`` may map a joint type, ``"revolute"`` or ``"prismatic"``, to its count): the
    joint values ``(K, k)``, the legs' base joints ``(K, legs, 3)`` and the carriage rotations
    ``(K, 3, 3)`` by (M1)-(M2)."""
    grids = [np.linspace(j.range[0], j.range[1], _count(samples, j.type) if j.range[1] > j.range[0] else 1)
             for j in chain.carriage]
    if grids:
        mesh = np.meshgrid(*grids, indexing="ij")
        combos = np.stack([m.ravel() for m in mesh], axis=1)
    else:
        combos = np.zeros((1, 0))
    # (M1) for every combination at once: T <- T T_m
    rots = np.broadcast_to(np.eye(3), (len(combos), 3, 3)).copy()
    trans = np.zeros((len(combos), 3))
    for m, joint in enumerate(chain.carriage):
        axis = np.asarray(joint.axis, float)
        if joint.type == "revolute":
            ang = np.radians(combos[:, m])
            k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
            r_m = (np.eye(3)[None] + np.sin(ang)[:, None, None] * k[None]
                   + (1.0 - np.cos(ang))[:, None, None] * (k @ k)[None])
            rots = rots @ r_m
        else:
            trans = trans + combos[:, m, None] * (rots @ axis)
    bases = np.einsum("lc,kdc->kld", np.array([leg.base for leg in chain.legs], float), rots) + trans[:, None, :]
    return combos, bases, rots


def reachable_brute_force(mech: Mechanism, points: Sequence[float] | np.ndarray, rotation: np.ndarray,
                          samples: int | Mapping[str, int] = 41) -> np.ndarray | bool:
    """The plain oracle: some carriage value on a grid of ``samples`` per joint (or per joint type,
    see :func:`carriage_samples`) puts every leg of
    each chain in its length range (and inside its cones, when given), at each of ``points``
    (``(N, 3)``, or one point) with the platform rotation ``rotation``. Returns a bool array
    ``(N,)`` (a bool for one point). For tests and checks, not speed: a sample that passes
    proves the pose reachable; a pose between samples can be missed."""
    pts = np.asarray(points, float)
    single = pts.ndim == 1
    pts = pts.reshape(-1, 3)
    rotation = np.asarray(rotation, float)
    ok_all = np.ones(len(pts), bool)
    for chain in mech.chains:
        n = len(chain.legs)
        u = np.array([leg.platform for leg in chain.legs], float) @ rotation.T  # (n, 3)
        _, bases, rots = carriage_samples(chain, samples)
        lo = np.array([leg.length[0] for leg in chain.legs]) - 1e-9
        hi = np.array([leg.length[1] for leg in chain.legs]) + 1e-9
        Cone_ = tuple[np.ndarray, float] | None
        u_axes: list[Cone_] = [None if leg.u_cone is None else (rots @ np.asarray(leg.u_cone.axis),
                                                               math.cos(math.radians(leg.u_cone.angle)))
                               for leg in chain.legs]
        s_axes: list[Cone_] = [None if leg.s_cone is None else (rotation @ np.asarray(leg.s_cone.axis),
                                                               math.cos(math.radians(leg.s_cone.angle)))
                               for leg in chain.legs]
        for p_i, p in enumerate(pts):
            if not ok_all[p_i]:
                continue
            v = (p + u)[None, :, :] - bases  # (K, n, 3): B_j - D_j(q)
            length = np.linalg.norm(v, axis=2)
            ok = np.all((length >= lo) & (length <= hi), axis=1)
            for j in range(n):
                u_cone, s_cone = u_axes[j], s_axes[j]
                if u_cone is not None:
                    ok &= np.einsum("kc,kc->k", u_cone[0], v[:, j]) >= length[:, j] * u_cone[1] - 1e-9
                if s_cone is not None:
                    ok &= v[:, j] @ s_cone[0] >= length[:, j] * s_cone[1] - 1e-9
            ok_all[p_i] = bool(ok.any())
    return bool(ok_all[0]) if single else ok_all


#: Valid range of ``length_step``, the spacing of a sampled (second) prismatic joint's values.
LENGTH_STEP_RANGE = (0.01, 100.0)


def check_length_step(value: float) -> float:
    """Validate ``length_step`` (the message names the field and its range)."""
    lo, hi = LENGTH_STEP_RANGE
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or not lo <= value <= hi:
        raise ParameterError("length_step", value, f"[{lo:g}, {hi:g}] (length units)")
    return float(value)


def platform_rotation(mech: Mechanism, orientation: Sequence[float] | np.ndarray) -> np.ndarray:
    """``R = Rot(reference) Rz(psi) Ry(theta) Rx(phi)``: ``orientation`` is ``(psi, theta, phi)`` in
    degrees or a 3x3 matrix (used as the rotation from the reference frame)."""
    o = np.asarray(orientation, float)
    rot = o if o.shape == (3, 3) else euler_zyx_deg(*o)
    if any(mech.reference):
        rot = euler_zyx_deg(*mech.reference) @ rot
    return rot
