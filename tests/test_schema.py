"""URL state and REST bodies are the same fields (app/schema.py): for every numeric link key, the
explorer's link parser and the REST model of the same name accept and refuse the same numbers,
with the same range text."""

from __future__ import annotations

import math

import pytest
from pydantic import ValidationError

from paraspace.app.schema import LINK_FIELDS, RANGES
from paraspace.app.urlstate import check_field, parse_query


def _bounds(key: str) -> tuple[float | None, float | None, bool]:
    model, _ = LINK_FIELDS[key]
    prop = model.model_json_schema()["properties"][key]
    prop = next((p for p in prop.get("anyOf", [prop]) if p.get("type") == "number"), prop)
    lo = prop.get("minimum", prop.get("exclusiveMinimum"))
    return lo, prop.get("maximum"), "exclusiveMinimum" in prop


def _rest_accepts(key: str, value: float) -> bool:
    model, _ = LINK_FIELDS[key]
    try:
        model.model_validate({key: value})
    except ValidationError as exc:
        return not any(e["loc"] == (key,) for e in exc.errors())
    return True


@pytest.mark.parametrize("key", sorted(LINK_FIELDS))
def test_link_and_rest_share_each_field(key: str) -> None:
    lo, hi, lo_open = _bounds(key)
    assert hi is not None and lo is not None, f"{key} has bounds in the REST schema"
    _, section = LINK_FIELDS[key]
    # JSON says "no limit" with null; a link by leaving the key out: the range itself is the same text
    text = RANGES[(section, key)].removesuffix(" or null (no limit)")
    outside = [hi + max(1.0, abs(hi) * 0.01), lo - max(1.0, abs(lo) * 0.01)] + ([lo] if lo_open else [])
    inside = [hi] + ([] if lo_open else [lo])
    for v in outside:
        assert not _rest_accepts(key, v), (key, v)
        state, msgs = parse_query(f"{key}={v!r}")
        mine = [m for m in msgs if m.startswith(f"{key} = ")]
        assert mine and text in mine[0], (key, v, msgs)
        msg = check_field(key, v) if key not in ("theta_u", "theta_s", "leg_diameter", "clearance") else None
        assert msg is None or text in msg, (key, v, msg)
    for v in inside:
        assert _rest_accepts(key, v), (key, v)
        msgs = parse_query(f"{key}={v!r}")[1]
        assert not any(m.startswith(f"{key} = ") and "out of range" in m for m in msgs), (key, v, msgs)
    assert math.isfinite(hi)
