"""The explorer's orientation scan range and step: from the link, from the sliders, into the maps
(the same numbers as the direct core call with those settings) and back into the link."""

from __future__ import annotations

import pytest
from explorer_client import FakeBrowser, wait_for, wait_idle  # tests/ (pytest's prepend import mode)

from paraspace.app.explorer import Explorer
from paraspace.kinematics.orientation import OrientationSettings, orientation_workspace


@pytest.fixture(scope="module")
def explorer():
    exp = Explorer("127.0.0.1", 0).start()
    exp.warm.wait(120)
    yield exp
    exp.stop()


def test_scan_range_and_step_from_link_and_sliders(explorer) -> None:
    b = FakeBrowser(explorer, "voxel=6&angle_range=45&angle_step=3&theta_u=30")
    try:
        s = b.session
        assert (s.state.angle_range, s.state.angle_step) == (45.0, 3.0)
        assert (s.panels.scan_range.value, s.panels.scan_step.value) == (45.0, 3.0)
        wait_idle(explorer, s)
        wait_for(lambda: s.orientation is not None and s.orientation.settings.angle_step == 3.0, 60.0, "maps")
        want = orientation_workspace(s.state.design, OrientationSettings(angle_range=45.0, angle_step=3.0,
                                                                         joints=s.state.joints))
        assert s.state.joints.theta_u == 30.0
        assert (s.orientation.ti1, s.orientation.ti2) == (want.ti1, want.ti2)
        b.set(s.panels.scan_step, 2.0)
        wait_for(lambda: s.state.angle_step == 2.0, 5.0, "the step applied")
        wait_for(lambda: s.orientation is not None and s.orientation.settings.angle_step == 2.0, 60.0, "new maps")
        assert s.orientation.settings.angle_range == 45.0
        wait_for(lambda: "angle_step=2" in b.search and "angle_range=45" in b.search, 5.0, "the link")
        b.set(s.panels.scan_range, 0.0)  # typed: outside (0, 180]
        wait_for(lambda: "Not applied" in s.panels.orientation_status.content, 5.0, "the message")
        assert "(0, 180] degrees" in s.panels.orientation_status.content.replace("\\", "")
        assert s.state.angle_range == 45.0
        # maps of the state kept, published after the refusal (a late job under load; here the cache),
        # keep the refusal on top while the refused value is on screen
        s.orientation_controller.submit()
        content = s.panels.orientation_status.content
        assert content.startswith("**Not applied:**") and "TI₁ = " in content
        b.set(s.panels.scan_range, 30.0)  # a valid value: applied, the refusal gone
        wait_for(lambda: s.orientation is not None and s.orientation.settings.angle_range == 30.0, 60.0, "30° maps")
        wait_for(lambda: "TI₁ = " in s.panels.orientation_status.content, 5.0, "the maps' status")
        assert "Not applied" not in s.panels.orientation_status.content
    finally:
        b.close()


def test_maps_on_screen_are_not_computed_again(explorer) -> None:
    """A second submit for a state whose maps are already on screen (here with the cache emptied, as
    when an equal state comes under another key) starts no job and leaves the maps' status as it is:
    no "computing..." over the maps the user is reading."""
    b = FakeBrowser(explorer, "voxel=6&angle_range=40&angle_step=4")
    try:
        s = b.session
        wait_idle(explorer, s)
        wait_for(lambda: s.orientation is not None and s.orientation.settings.angle_step == 4.0, 60.0, "maps")
        wait_for(lambda: "TI₁ = " in s.panels.orientation_status.content, 10.0, "the maps' status")
        shown, status = s.orientation, s.panels.orientation_status.content

        def jobs():
            return [j for j in explorer.jobs.jobs() if j.kind == "orientation" and j.client == s.job_client]
        before = len(jobs())
        explorer.orientation_cache.clear()
        s.orientation_controller.submit()
        assert len(jobs()) == before  # no job started
        assert s.orientation is shown and s.panels.orientation_status.content == status
        # a state whose maps are not on screen still computes them
        b.set(s.panels.scan_step, 5.0)
        wait_for(lambda: s.orientation is not None and s.orientation.settings.angle_step == 5.0, 60.0, "new maps")
        assert len(jobs()) == before + 1
    finally:
        b.close()
