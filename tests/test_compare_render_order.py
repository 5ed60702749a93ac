"""The Compare table's refreshes run on several threads (GUI callbacks, the ends of pins' jobs, the
session when the current design's measures arrive): a refresh that took its snapshot earlier but
ends later must not put back an older table. Seen as a race in CI: with another mechanism selected,
a late render of the paper's comparison could overwrite the sentence that says why the pins wait."""

from __future__ import annotations

import threading
import types

import pytest
import viser

from paraspace.app.explorer import compare_panel
from paraspace.app.explorer.compare_panel import CompareHooks, ComparePanel, Pin
from paraspace.app.jobs import JobManager
from paraspace.kinematics.design import Design


@pytest.fixture(scope="module")
def server():
    srv = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield srv
    srv.stop()


def _bundle(design: Design | None, mechanism: str | None = None) -> types.SimpleNamespace:
    return types.SimpleNamespace(result=types.SimpleNamespace(design=design), measures=object(), mesh=None,
                                 mechanism=mechanism)


@pytest.fixture
def panel(server):
    jobs = JobManager(max_workers=1)
    current = {"bundle": _bundle(Design(a=60.0))}
    hooks = CompareHooks(get_state=lambda: None, set_pins=lambda _d: None, bundle_for=lambda _s: None,
                         compute_bundle=lambda *_a: None, current_bundle=lambda: current["bundle"],
                         load_design=lambda _d: None, notify=lambda *_a: None)
    p = ComparePanel(server.gui, server.scene, jobs, "client", hooks)
    pinned = Design()
    p.pins = [Pin(pinned, (255, 0, 0, 255), bundle=_bundle(pinned))]
    p.current = current  # the test may put another mechanism's shell on screen
    yield p
    jobs.shutdown(wait=False)


def test_a_late_refresh_of_the_paper_table_does_not_overwrite_the_other_mechanisms_sentence(panel, monkeypatch):
    inside = threading.Event()
    release = threading.Event()

    def slow_table(pinned, current, indices):  # the older refresh is slow: it ends after the newer one
        inside.set()
        assert release.wait(10.0)
        return "the paper's comparison"

    monkeypatch.setattr(compare_panel, "comparison_table", slow_table)
    late = threading.Thread(target=panel.refresh)
    late.start()
    assert inside.wait(10.0)
    panel.set_mechanism("delta")  # the user selects another mechanism meanwhile
    assert "not the delta mechanism" in panel.table.content
    release.set()
    late.join(10.0)
    assert not late.is_alive()
    assert "not the delta mechanism" in panel.table.content  # the older refresh wrote nothing
    assert "comparison" not in panel.table.content


def test_refreshes_after_it_still_write(panel, monkeypatch):
    monkeypatch.setattr(compare_panel, "comparison_table", lambda pinned, current, indices: "the paper's comparison")
    panel.set_mechanism("delta")
    assert "not the delta mechanism" in panel.table.content
    panel.set_mechanism(None)  # the paper's mechanism again: its table is back
    assert "the paper's comparison" in panel.table.content
    assert "current: " in panel.table.content
    panel.pins = []
    panel.refresh()
    assert panel.table.content == "" and panel.title.content == "*nothing pinned*"


def test_another_mechanism_keeps_the_pin_button_disabled_through_refreshes(panel):
    """The mechanism's note disables "Pin this design" for another mechanism; a later refresh (the
    current design's measures arriving) must not enable it again, and the paper's mechanism does."""
    panel.set_mechanism("delta")
    assert panel.pin_button.disabled
    panel.refresh()  # e.g. the session, when the current design's measures arrive
    assert panel.pin_button.disabled
    panel.set_mechanism(None)
    assert not panel.pin_button.disabled


def test_back_on_the_paper_with_another_mechanisms_shell_still_on_screen(panel, monkeypatch):
    """Seen in CI: the paper's mechanism selected again while the other mechanism's shell (whose result
    has no paper design) was still on screen; the table raised in the callback, and the ghosts never
    came back. Its column now waits for the paper's shell, and the ghosts are shown again."""
    monkeypatch.setattr(compare_panel, "comparison_table", lambda pinned, current, indices: "the paper's comparison")
    panel.set_mechanism("6-pss")
    panel.current["bundle"] = _bundle(None, mechanism="6-pss")  # the other mechanism's shell on screen
    shown = []
    monkeypatch.setattr(panel, "_show_ghosts", lambda: shown.append(panel.other_mechanism))
    panel.set_mechanism(None)
    assert panel.table.content == "*current design: computing...*"
    assert shown == [None]  # the ghosts follow the selection at once
    panel.current["bundle"] = _bundle(Design(a=60.0))  # the paper's shell and measures arrive
    panel.refresh()
    text = panel.table.content.replace("\\", "")  # markdown escapes
    assert "the paper's comparison" in text and "current: a 60, b 14" in text
