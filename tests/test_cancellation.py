"""Every long step checks for cancellation (trust item 4): a cancel requested at any of its checks
ends the step there with Cancelled, and the checks are spread through the work (counted, not timed)."""

from __future__ import annotations

import pytest

from paraspace.kinematics.design import Design
from paraspace.kinematics.measures import measure_workspace
from paraspace.kinematics.progress import Cancelled
from paraspace.kinematics.sweep import evaluate_design
from paraspace.kinematics.workspace import WorkspaceSettings, compute_workspace


class CountingToken:
    """A cancel token (a callable) that counts the checks and answers "cancelled" from check ``at`` on."""

    def __init__(self, at: int | None = None) -> None:
        self.at, self.calls = at, 0

    def __call__(self) -> bool:
        self.calls += 1
        return self.at is not None and self.calls >= self.at


@pytest.fixture(scope="module")
def result():
    return compute_workspace(Design(), WorkspaceSettings(voxel=4.0))


def test_measures_check_between_every_step(result) -> None:
    free = CountingToken()
    reference = measure_workspace(result, cancel=free)
    assert free.calls >= 12, f"the measures check for a cancel {free.calls} times"
    for at in range(1, free.calls + 1):
        token = CountingToken(at)
        with pytest.raises(Cancelled):
            measure_workspace(result, cancel=token)
        assert token.calls == at, "the step ends at the first check that sees the cancel"
    assert measure_workspace(result).to_dict() == reference.to_dict()  # the checks change nothing


def test_a_sweep_point_stops_inside_its_measures(result) -> None:
    """evaluate_design hands its token to the measures: cancelled at the last check, it stops there."""
    free = CountingToken()
    evaluate_design(Design(), WorkspaceSettings(voxel=4.0), cancel=free)
    token = CountingToken(free.calls)
    with pytest.raises(Cancelled):
        evaluate_design(Design(), WorkspaceSettings(voxel=4.0), cancel=token)
    assert token.calls == free.calls
