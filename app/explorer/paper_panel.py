"""The explorer's "Paper" tab: the paper's reported numbers and Sec. III claims beside ours.

One button runs :func:`kinematics.paper.paper_comparison` as a background job (about 10 s at
h = 4; progress shown, Stop available, the result cached for every browser of the server) and the
tab shows three tables: the volume under each arc-range convention, TI_1/TI_2 under each joint
assumption (with the saturation warning), and every Sec. III claim marked holds / fails. The same
dictionary is what ``paraspace paper --json`` prints.
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


def comparison_markdown(out: dict[str, Any]) -> str:
    """The tables of the tab from the comparison dictionary (all text is ours; numbers formatted)."""
    rep = out["reported"]
    lines = [f"**The paper** (default design): V = {significant(rep['volume'], 3)} units³, "
             f"TI₁ = {rep['TI_1']:g}, TI₂ = {rep['TI_2']:g} (degree × length)", "",
             f"**Volume, ours** (h = {out['voxel']:g})", "", "| convention | V (units³) |", "|---|---|"]
    for row in out["volume"]["ours"]:
        mark = " ← closest" if row["convention"] == out["volume"]["closest"] else ""
        lines.append(f"| {md_text(row['convention'])}{mark} | {significant(row['volume'], 3)} |")
    lines += ["", "**TI₁ / TI₂, ours**", "", "| assumption | TI₁ | TI₂ |", "|---|---|---|"]
    for row in out["indices"]["ours"]:
        sat = " ⚠ scan-limited" if row["saturation_note"] else ""
        lines.append(f"| {md_text(row['convention'])}{sat} | {significant(row['TI_1'], 4)} | "
                     f"{significant(row['TI_2'], 4)} |")
    lines += ["", md_text(out.get("note", "")), "", f"**Sec. III claims** ({md_text(out['summary'])})", "",
              "| design | measure | paper | ours | |", "|---|---|---|---|---|"]
    for c in out["claims"]:
        ours = ("complete" if c["ours"] else "incomplete") if isinstance(c["ours"], bool) else \
            f"{significant(c['ours'], 3)} (default {significant(c['default'], 3)})"
        lines.append(f"| {md_text(c['design'])} | {md_text(c['measure'])} | {md_text(c['paper'])} | {ours} | "
                     f"{'holds' if c['holds'] else '**fails**'} |")
    return "\n".join(lines)


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
        gui.add_markdown("The paper's reported numbers (V, TI₁, TI₂) and the claims of its Sec. III for the "
                         "eight design variants, beside ours under each convention. The same as "
                         "`paraspace paper --json`.")
        self.run = gui.add_button("Compare with the paper (about 10 s)", icon=viser.Icon.PLAYER_PLAY)
        self.stop = gui.add_button("Stop", color="red", icon=viser.Icon.PLAYER_STOP, visible=False)
        self.progress = gui.add_progress_bar(0.0, visible=False)
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
            return paper_comparison(PAPER_VOXEL, progress, cancel)

        def on_progress(job: Job) -> None:
            self.progress.value = 100.0 * float(job.progress)  # type: ignore[misc]  # settable (viser's stub says read-only)

        def done(job: Job) -> None:
            self.stop.visible = False
            self.progress.visible = False
            self.run.disabled = False
            if job.status == "done":
                self.cache.put(PAPER_VOXEL, job.result)
                self.result.content = comparison_markdown(job.result)
            elif job.status == "failed":
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
        self.progress.value = 0.0  # type: ignore[misc]  # settable (viser's stub says read-only)

    def cancel(self) -> None:
        """The Stop button."""
        with self.lock:
            job = self.job
        if job is not None and not job.is_final:
            self.jobs.cancel(job.id)
