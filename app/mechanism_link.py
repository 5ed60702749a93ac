"""A mechanism in the explorer's state and link: a preset with its parameters, or an uploaded file.

**Definition.** The explorer computes either on the paper's :class:`~kinematics.design.Design`
(``ExplorerState.mechanism is None``, the default: today's explorer) or on a :class:`MechanismLink`:

* ``preset`` names one of :data:`kinematics.presets.PRESETS` other than ``paper``, and ``params``
  holds every one of its parameters (``(name, value)`` in :class:`~kinematics.presets.PresetParam`
  order): the mechanism is ``PRESETS[preset].mechanism(dict(params))``;
* ``preset == "file"``: ``text`` is the compact JSON (sorted keys, no spaces) of an uploaded
  description (:func:`kinematics.mechanism.loads_mechanism`, at most ``MAX_TEXT_BYTES``).

A link writes (:func:`encode_mechanism`; read back by :func:`parse_mechanism_pairs`)::

    mech=PRESET[&mp_NAME=VALUE...]      parameters that differ from the preset's default
    mech=file&mfile=DATA               DATA = base64url(zlib(compact JSON)), without padding

A file is carried only while ``in_link`` is true (the explorer clears it when the whole link would
exceed the server's query bound; the page then says so and the link carries no mechanism). Every
preset parameter is validated by the preset's own builder, so a bad one gets the same message as
the CLI's ``--param NAME=VALUE``.
"""

from __future__ import annotations

import base64
import dataclasses
import functools
import json
import math
import zlib
from collections.abc import Mapping
from typing import Any

from paraspace.kinematics.design import ParameterError
from paraspace.kinematics.mechanism import MAX_TEXT_BYTES, Mechanism, loads_mechanism, parse_mechanism
from paraspace.kinematics.presets import PRESETS, PresetParam

from .numfmt import format_number

#: The mechanism choices of a link's ``mech`` key besides ``paper``: every other preset, and ``file``.
FILE = "file"
#: Presets the explorer offers besides the paper's (the paper's is its Design tab).
MECH_PRESETS: tuple[str, ...] = tuple(name for name in PRESETS if name != "paper")
#: Prefix of a preset parameter's link key (``mp_lift=40``): the names repeat the design's (``l_min``).
PARAM_PREFIX = "mp_"
#: Longest piece of a link's value quoted in a message (as ``app.urlstate.QUOTE_CHARS``).
QUOTE_CHARS = 40
#: Longest message about an unreadable uploaded description in a link.
MESSAGE_CHARS = 300


def preset_params(name: str) -> tuple[PresetParam, ...]:
    """The numeric parameters of preset ``name`` (its sliders, its link keys)."""
    return tuple(p for p in PRESETS[name].params if not isinstance(p.default, str))


def param_keys() -> tuple[str, ...]:
    """Every ``mp_NAME`` link key of the explorer's presets (each name once)."""
    names: list[str] = []
    for preset in MECH_PRESETS:
        names += [p.name for p in preset_params(preset) if p.name not in names]
    return tuple(PARAM_PREFIX + n for n in names)


@functools.lru_cache(maxsize=32)
def _build(preset: str, params: tuple[tuple[str, float], ...], text: str | None) -> Mechanism:
    if preset == FILE:
        assert text is not None
        return parse_mechanism(json.loads(text))
    return PRESETS[preset].mechanism(dict(params))


@dataclasses.dataclass(frozen=True)
class MechanismLink:
    """A non-paper mechanism of the explorer (module docstring). Build with :func:`preset_link` or
    :func:`file_link`, which validate; :meth:`mechanism` then never raises."""

    preset: str
    params: tuple[tuple[str, float], ...] = ()
    text: str | None = None
    #: the link carries the uploaded file (cleared when it would make the link too long)
    in_link: bool = dataclasses.field(default=True, compare=False)

    def mechanism(self) -> Mechanism:
        """The validated :class:`~kinematics.mechanism.Mechanism` (cached)."""
        return _build(self.preset, self.params, self.text)

    def key(self) -> tuple:
        """A cache key of the mechanism."""
        return (self.preset, self.params, self.text)

    @property
    def label(self) -> str:
        """Its name in words: the preset's name, or the uploaded description's ``name``."""
        return self.preset if self.preset != FILE else f"uploaded '{self.mechanism().name[:60]}'"

    def not_yet(self) -> str:
        """The sentence a panel that does not apply to it yet shows."""
        return f"not for the {self.label} mechanism yet"


def preset_link(name: str, values: Mapping[str, Any] | None = None) -> MechanismLink:
    """The link of preset ``name`` with ``values`` over its defaults; raises the preset's
    :class:`~kinematics.design.ParameterError` (the CLI's ``--param`` message) on a bad value."""
    if name not in MECH_PRESETS:
        raise ParameterError("mech", name, f"one of paper, {', '.join(MECH_PRESETS)} or {FILE}")
    values = dict(values or {})
    specs = preset_params(name)
    known = {p.name for p in specs}
    for key in values:
        if key not in known:
            raise ParameterError(key, values[key], f"a parameter of preset {name!r}: {', '.join(sorted(known))}")
    PRESETS[name].mechanism(values)  # validates (the builder's own checks: types, ranges, l_min < l_max)
    params = tuple((p.name, float(values.get(p.name, p.default))) for p in specs)
    return MechanismLink(name, params)


def file_link(content: bytes | str) -> MechanismLink:
    """The link of an uploaded TOML/JSON description; raises the parser's
    :class:`~kinematics.design.ParameterError` naming the bad field (nothing else is changed)."""
    mech = loads_mechanism(content)
    text = json.dumps(mech.to_dict(), sort_keys=True, separators=(",", ":"))
    return MechanismLink(FILE, (), text)


def _pack(text: str) -> str:
    return base64.urlsafe_b64encode(zlib.compress(text.encode("utf-8"), 9)).decode("ascii").rstrip("=")


def _unpack(data: str) -> bytes:
    raw = base64.urlsafe_b64decode(data + "=" * (-len(data) % 4))
    d = zlib.decompressobj()
    out = d.decompress(raw, MAX_TEXT_BYTES + 1)
    if len(out) > MAX_TEXT_BYTES or d.unconsumed_tail:
        raise ParameterError("mfile", f"more than {MAX_TEXT_BYTES:,} bytes", f"a description of at most "
                             f"{MAX_TEXT_BYTES:,} bytes")
    return out


def _number(raw: str) -> float | str:
    try:
        v = float(raw)
    except ValueError:
        return raw
    return v if math.isfinite(v) else raw


def encode_mechanism(link: MechanismLink | None) -> list[tuple[str, str]]:
    """The link pairs of ``link`` (none for the paper's Design); numbers as ``format_number``."""

    if link is None:
        return []
    if link.preset == FILE:
        if not link.in_link or link.text is None:
            return []
        return [("mech", FILE), ("mfile", _pack(link.text))]
    defaults = {p.name: p.default for p in preset_params(link.preset)}
    return [("mech", link.preset)] + [(PARAM_PREFIX + k, format_number(v)) for k, v in link.params
                                      if v != defaults[k]]


def parse_mechanism_pairs(values: Mapping[str, str]) -> tuple[MechanismLink | None, list[str]]:
    """The mechanism of a link's ``values`` (``mech``, ``mfile``, ``mp_*``) and one message per bad
    field; a bad parameter keeps its default (the others still apply), a bad ``mech`` or file
    gives the paper's Design. Never raises."""
    messages: list[str] = []
    params = {k[len(PARAM_PREFIX):]: v for k, v in values.items() if k.startswith(PARAM_PREFIX)}
    name = values.get("mech")
    if name is None or name == "paper":
        if params:
            messages.append(f"{', '.join(PARAM_PREFIX + k for k in params)} ignored: parameters of a preset "
                            f"go with mech={'|'.join(MECH_PRESETS)}")
        return None, messages
    if name == FILE:
        if "mfile" not in values:
            return None, ["mech = 'file' without mfile: the link carries no description; the paper's design "
                          "is shown"]
        try:
            return file_link(_unpack(values["mfile"])), messages
        except (ValueError, zlib.error) as exc:
            why = str(exc)[:MESSAGE_CHARS] if isinstance(exc, ParameterError) else "not base64url(zlib(JSON))"
            return None, [f"mfile: the uploaded description could not be read ({why}); the paper's design is "
                          "shown"]
    if name not in MECH_PRESETS:
        return None, [f"mech = {name[:40]!r} is invalid; valid values: paper, {', '.join(MECH_PRESETS)}, {FILE}"]
    known = {p.name for p in preset_params(name)}
    typed: dict[str, Any] = {}
    for key, raw in params.items():
        if key not in known:
            messages.append(f"{PARAM_PREFIX}{key} is not a parameter of preset {name!r} "
                            f"({', '.join(sorted(known))}); ignored")
        else:
            typed[key] = _number(raw)
    for _ in range(len(typed) + 1):
        try:
            return preset_link(name, typed), messages
        except ParameterError as exc:
            value = typed.get(exc.field)
            if isinstance(value, str) and len(value) > QUOTE_CHARS:  # the CLI's message, its quote cut
                exc = ParameterError(exc.field, value[: QUOTE_CHARS - 1] + "…", exc.valid)
            messages.append(f"{PARAM_PREFIX}{exc}; the preset's default is used")
            if exc.field not in typed:  # a cross-field check (l_max > l_min): drop the last given
                exc.field = next(reversed(typed)) if typed else exc.field
            if typed.pop(exc.field, None) is None:
                break
    return preset_link(name), messages
