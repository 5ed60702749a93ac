"""The Legend's keys (app/explorer/legend.py) and the binding-limit palette: each colour mode has
its own key, and no limit colour can be mistaken for a colour the mechanism uses for a state."""

from __future__ import annotations

import numpy as np

from paraspace.app.explorer.dexterity_colour import LIMIT_COLOUR_NAMES, LIMIT_COLOURS
from paraspace.app.explorer.legend import colorbar_image, swatch_image
from paraspace.app.explorer.scene import LEG_COLORS, REACHABLE_COLOR, UNREACHABLE_COLOR


def _lab(rgb: tuple[int, int, int]) -> np.ndarray:
    """CIE L*a*b* (D65) of an sRGB colour: an independent perceptual distance for the palette check."""
    c = np.asarray(rgb, float) / 255.0
    c = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]) @ c
    xyz /= np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > 216 / 24389, np.cbrt(xyz), (24389 / 27 * xyz + 16) / 116)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def test_limit_colours_stay_away_from_the_state_colours() -> None:
    states = {**{f"leg {k}": v for k, v in LEG_COLORS.items()}, "platform reachable": REACHABLE_COLOR,
              "platform unreachable": UNREACHABLE_COLOR, "pinned design": (255, 0, 255)}
    for name, colour in LIMIT_COLOURS.items():
        for state, other in states.items():
            delta_e = float(np.linalg.norm(_lab(colour) - _lab(other)))
            assert delta_e > 30, f"limit {name} {colour} is close to {state} {other} (Delta E {delta_e:.0f})"
    names = list(LIMIT_COLOURS)
    for i, a in enumerate(names):  # and the limits are told apart from each other
        for b in names[i + 1:]:
            assert np.linalg.norm(_lab(LIMIT_COLOURS[a]) - _lab(LIMIT_COLOURS[b])) > 20, (a, b)
    assert set(LIMIT_COLOUR_NAMES) == set(LIMIT_COLOURS)


def test_swatch_key_shows_each_colour() -> None:
    entries = tuple((k, v) for k, v in LIMIT_COLOURS.items())
    image = swatch_image(entries)
    pixels = {tuple(p) for p in image.reshape(-1, 3)}
    for name, colour in entries:
        assert tuple(colour) in pixels, f"the swatch of {name} is drawn in its colour"
    assert image.shape[1] == colorbar_image(0.0, 1.0).shape[1], "as wide as the colour bar"


def test_one_label_per_chain_names_its_legs_in_words():
    from paraspace.app.explorer.scene import chain_label_text, grid_scale_text
    from paraspace.kinematics.design import Design

    assert chain_label_text(0, ["inside", "inside"]) is None
    assert chain_label_text(1, ["too_long", "too_long"]) == "chain 2: legs 1, 2 too long"
    assert chain_label_text(0, ["inside", "at_limit"]) == "chain 1: leg 2 at a limit"
    assert chain_label_text(2, ["too_short", "at_limit"]) == "chain 3: leg 1 too short, leg 2 at a limit"
    assert grid_scale_text(Design(r=150.0)) == "grid: 30 units per cell, 150 per section"
