"""The Numbers panel's renders run on several threads (GUI callbacks, the ends of jobs): a render
that took its snapshot of the session earlier but finishes later must not overwrite a newer one, nor
leave the Numbers and the summary from two states (seen in CI: the Numbers said "(full, h = 8)" while
the summary still said "not computed")."""

from __future__ import annotations

import threading
import types

from paraspace.app.explorer import numbers_panel


def _ctx(tag: str) -> types.SimpleNamespace:
    return types.SimpleNamespace(
        closed=False, lock=threading.RLock(), ws_info=None, resolution=None, in_workspace=None, orientation=None,
        state=types.SimpleNamespace(mechanism=None, tag=tag), bundle=None, preview=None, mechanism_pose=None,
        ws_refused=None, design_error=None, task_line=None,
        panels=types.SimpleNamespace(numbers=types.SimpleNamespace(content=""),
                                     summary=types.SimpleNamespace(content="")))


def test_a_render_of_an_older_state_that_ends_last_writes_nothing(monkeypatch) -> None:
    older_inside = threading.Event()
    newer_done = threading.Event()

    def numbers(s, *_a):
        if s.tag == "old":  # the older render is slow: it ends after the newer one
            older_inside.set()
            assert newer_done.wait(10.0)
        return f"numbers of the {s.tag} state"

    monkeypatch.setattr(numbers_panel, "numbers_markdown", numbers)
    monkeypatch.setattr(numbers_panel, "summary_markdown", lambda s, *_a: f"summary of the {s.tag} state")
    ctx = _ctx("old")
    panel = numbers_panel.NumbersPanel(ctx)
    slow = threading.Thread(target=panel.render)
    slow.start()
    assert older_inside.wait(10.0)
    ctx.state = types.SimpleNamespace(mechanism=None, tag="new")  # the session moves on
    panel.render()
    newer_done.set()
    slow.join(10.0)
    assert ctx.panels.numbers.content == "numbers of the new state"
    assert ctx.panels.summary.content == "summary of the new state"
    panel.render()  # a later render of the same state still writes
    assert ctx.panels.numbers.content == "numbers of the new state"
