"""The Compare tab's ghost cage (app.explorer.compare_panel.ghost_contours) against closed-form sections."""

from __future__ import annotations

import numpy as np
import trimesh

from paraspace.app.explorer.compare_panel import ghost_contours


def _lengths(segs: np.ndarray) -> np.ndarray:
    return np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1)


def test_box_sections_are_its_perimeter_at_equally_spaced_heights():
    box = trimesh.creation.box(extents=(30.0, 20.0, 50.0))  # z in [-25, 25]
    segs = ghost_contours(box, levels=4)
    z = np.unique(np.round(segs[:, :, 2], 9))
    assert np.allclose(z, [-15.0, -5.0, 5.0, 15.0])  # strictly inside, equally spaced
    for level in z:
        on = np.all(np.isclose(segs[:, :, 2], level), axis=1)
        assert np.isclose(_lengths(segs[on]).sum(), 2 * (30.0 + 20.0))  # the rectangle's perimeter
    assert np.all(np.abs(segs[:, :, 0]) <= 15.0 + 1e-9) and np.all(np.abs(segs[:, :, 1]) <= 10.0 + 1e-9)


def test_sphere_sections_are_circles_of_the_right_radius():
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=10.0)
    segs = ghost_contours(sphere, levels=5)
    for level in np.unique(np.round(segs[:, :, 2], 6)):
        on = np.all(np.isclose(segs[:, :, 2], level, atol=1e-6), axis=1)
        r = np.sqrt(100.0 - level ** 2)
        assert abs(_lengths(segs[on]).sum() - 2 * np.pi * r) < 0.01 * 2 * np.pi * r  # inscribed polygon


def test_empty_mesh_has_no_cage():
    assert ghost_contours(trimesh.Trimesh()).shape == (0, 2, 3)
    assert ghost_contours(None).shape == (0, 2, 3)
