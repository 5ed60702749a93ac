"""The explorer's "Paper" tab: every checkable claim of the paper with its verdict under each assumption.

One button runs :func:`kinematics.paper.paper_comparison` as a background job (about half a minute
at h = 4 on two cores for the six assumption columns; progress shown in words with the seconds
spent, Stop available, the result cached for every browser of the server). The tab shows the paper's
reported numbers beside ours under each column (never "closest" outside the paper's own design), the
verdict counts per column, and one row per claim: the paper's words, our value under the paper's
model, the verdict there, and the columns (assumptions) under which the verdict flips -- which
assumption decides which claim. The same dictionary is what ``paraspace paper --json`` prints; the
fit of the unstated assumptions is ``paraspace paper --fit`` (README).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import viser

from paraspace.kinematics.bytecache import ByteLRU

from ..jobs import Job, JobManager, LimitExceeded
from ..numfmt import significant
from ..textsafe import md_text
from .session import SessionJobs

#: Voxel edge of the comparison (the CLI's default).
PAPER_VOXEL = 4.0
#: The orientation scan's steps of the comparison (the CLI's defaults).
PAPER_SCAN: dict[str, float] = {"angle_step": 1.0, "position_step": 2.0}
#: The assumption columns computed (None: all of :data:`kinematics.paper.ASSUMPTION_KEYS`).
PAPER_ASSUMPTIONS: tuple[str, ...] | None = None

_MARK = {"holds": "✓ holds", "fails": "✗ **fails**"}


def _verdict(v: str) -> str:
    return _MARK.get(v, md_text(v))


def comparison_markdown(out: dict[str, Any]) -> str:
    """The tables of the tab from the comparison dictionary (all text is ours; numbers formatted)."""
    rep = out["reported"]
    cols = out["assumptions"]
    lines = [f"**The paper** (default design): V = {significant(rep['volume'], 3)} units³, "
             f"TI₁ = {rep['TI_1']:g}, TI₂ = {rep['TI_2']:g} (degree × length). "
             f"Ours at h = {out['voxel']:g}, scan ±{out['scan']['angle_range']:g}° in steps of "
             f"{out['scan']['angle_step']:g}° / {out['scan']['position_step']:g}.", "",
             "**Assumptions (columns)**", "", "| column | what it assumes | holds | fails | not testable |",
             "|---|---|---|---|---|"]
    for a in cols:
        n = out["counts"][a["key"]]
        lines.append(f"| {md_text(a['key'])} | {md_text(a['label'])} | {n['holds']} | {n['fails']} | "
                     f"{n['not testable']} |")
    lines += ["", "**The reported numbers, ours under each column** (gap to the paper's)", "",
              "| column | V | TI₁ | TI₂ |", "|---|---|---|---|",
              f"| *the paper* | {significant(rep['volume'], 3)} | {significant(rep['TI_1'], 4)} | "
              f"{significant(rep['TI_2'], 4)} |"]
    by_col = {k: {r["assumption"]: r for r in v["ours"]} for k, v in out["reported_vs_ours"].items()}
    for a in cols:
        cells = [f"{significant(by_col[k][a['key']]['value'], 3)} "
                 f"({100 * by_col[k][a['key']]['gap']:+.0f}\u00a0%)"
                 for k in ("volume", "TI_1", "TI_2")]
        lines.append(f"| {md_text(a['key'])} | " + " | ".join(cells) + " |")
    lines += ["", "All three **fail** (gap beyond 5 %) under every column; the closest column: " + "; ".join(
        f"{md_text(k)} {md_text(v['closest'])} ({100 * v['closest_gap']:+.0f} %)"
        for k, v in out["reported_vs_ours"].items()) + ".", "", f"**Claims** ({md_text(out['summary'])})", "",
        "Each claim: the verdict under the paper's model, the paper's words, our value, and the columns "
        "under which the verdict differs (which assumption decides the claim).", ""]
    for c in out["claims"]:
        flips = ", ".join(f"{md_text(k)} → {_verdict(c['by_assumption'][k]['verdict'])}" for k in c["decided_by"])
        tuned = (f" · {md_text(c['tuned_value'])}" if c.get("tuned_value") else
                 " · *definition tuned on the nine designs*" if c.get("tuned") else "")
        lines += [f"- {_verdict(c['verdict'])} · **{md_text(c['id'])}** ({md_text(c['where'])}): "
                  f"“{md_text(c['quote'], 200)}”  ",
                  f"  ours: {md_text(str(c['value']), 200)}{tuned}  ",
                  f"  differs under: {flips or 'none'}"]
    lines += ["", "**Tuned on the paper's nine designs:** " + " · ".join(md_text(t, 400) for t in out["tuned"]),
              "", md_text(out.get("note", ""), 800),
              "", "Definitions of every measure: `paraspace paper --json` (field `definition`); the fit of the "
              "unstated assumptions: `paraspace paper --fit`."]
    return "\n".join(lines)


def _checked_words(message: str, fraction: float) -> str:
    """Where the check is, from the core's progress (``"paper: <claim> (<column>)"``, reported after
    each claim under each column): the share checked and the last claim checked, in the tab's words."""
    text = message.removeprefix("paper: ").strip()
    claim, _, column = text.partition(" (")
    if not column:  # nothing checked yet (the first columns' workspaces are being computed)
        return "computing the columns' workspaces, 0 % checked"
    return (f"{100 * fraction:.0f} % checked, the last: claim {md_text(claim, 60)} under the column "
            f"{md_text(column.rstrip(')'), 40)}")


class PaperPanel:
    """The Paper tab of one browser (module docstring)."""

    def __init__(self, gui: viser.GuiApi, jobs: JobManager | SessionJobs, *, client: str, cache: ByteLRU,
                 notify: Callable[[str, str], None]) -> None:
        self.jobs = jobs
        self.client = client
        self.cache = cache  # shared by every browser of the server: voxel -> result
        self.notify = notify
        self.job: Job | None = None
        self.lock = threading.Lock()
        gui.add_markdown("Every checkable claim of the paper (Sec. III, Fig. 4, Fig. 5, conclusion) with its "
                         "verdict under the paper's model and under each assumption the paper does not state. "
                         "The same as `paraspace paper --json`.")
        self.run = gui.add_button("Check the paper's claims", icon=viser.Icon.PLAYER_PLAY,
                                  hint="six assumption columns at h = 4: about half a minute on two cores")
        self.stop = gui.add_button("Stop", color="red", icon=viser.Icon.PLAYER_STOP, visible=False)
        self.progress = gui.add_progress_bar(0.0, visible=False)
        self.status = gui.add_markdown("")
        self.result = gui.add_markdown("")
        self.run.on_click(lambda _e: self.start())
        self.stop.on_click(lambda _e: self.cancel())
        hit = cache.get(PAPER_VOXEL)
        if hit is not None:
            self.result.content = comparison_markdown(hit)

    def start(self) -> None:
        """Run the comparison (or show the cached one)."""
        from paraspace.kinematics.paper import paper_comparison

        hit = self.cache.get(PAPER_VOXEL)
        if hit is not None:
            self.result.content = comparison_markdown(hit)
            return

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> dict:
            return paper_comparison(PAPER_VOXEL, progress, cancel, assumptions=PAPER_ASSUMPTIONS, **PAPER_SCAN)

        def on_progress(job: Job) -> None:
            self.progress.value = 100.0 * float(job.progress)  # type: ignore[misc]  # settable (viser's stub says read-only)
            self.status.content = f"{_checked_words(job.message, job.progress)} ({job.elapsed or 0.0:.0f} s)"

        def done(job: Job) -> None:
            self.stop.visible = False
            self.progress.visible = False
            self.run.disabled = False
            if job.status == "done":
                self.cache.put(PAPER_VOXEL, job.result)
                self.status.content = f"checked in {job.elapsed or 0.0:.0f} s"
                self.result.content = comparison_markdown(job.result)
                return
            why = "Stop pressed" if job.status == "cancelled" else f"failed: {md_text(str(job.error), 200)}"
            self.status.content = (f"**Stopped** at {_checked_words(job.progress_message, job.progress)} ({why}, "
                                   f"{job.elapsed or 0.0:.0f} s): nothing kept; the button runs the whole check again")
            if job.status == "failed":
                self.notify("Paper comparison failed", str(job.error))

        try:
            job = self.jobs.submit(fn, kind="paper", client=self.client, supersede=True, on_done=done,
                                   on_progress=on_progress)
        except (LimitExceeded, RuntimeError) as exc:
            self.notify("Paper comparison not started", str(exc))
            return
        with self.lock:
            self.job = job
        self.run.disabled = True
        self.stop.visible = True
        self.progress.visible = True
        self.status.content = _checked_words("", 0.0)
        self.progress.value = 0.0  # type: ignore[misc]  # settable (viser's stub says read-only)

    def cancel(self) -> None:
        """The Stop button."""
        with self.lock:
            job = self.job
        if job is not None and not job.is_final:
            self.jobs.cancel(job.id)
