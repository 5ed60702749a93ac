"""The explorer's "Optimize" panel: a bounded multi-objective optimisation (``kinematics.optimize``)
run as a job, its Pareto front as an interactive plot, and "Load this design".

The front is shown after each generation of a run; Stop keeps the front of the generations done
(said to be partial in the status line, never held in ``results``).

:class:`OptimizePanel` builds its controls into any viser GUI container it is given (a tab, a
folder, ``client.gui``) and needs from its host only

* ``jobs``: the explorer's :class:`~app.jobs.JobManager` (the run is a job: progress, Stop,
  supersede, the manager's limits);
* ``get_design()``: the current design (the base of the run: fields that are not free stay);
* ``load_design(design)``: called with a front design when the user loads it;
* ``get_joints()``: the current joint cones and leg interference (the run's workspaces and TI's
  use them; default: none);
* optionally ``cache`` (the explorer's sweep :class:`~kinematics.sweep.ResultCache`, so designs
  studied elsewhere are not computed again), ``results`` (a server-wide
  :class:`~kinematics.bytecache.ByteLRU` of finished runs by their settings, so a shared link shows
  its front without recomputing while the server holds it) and ``on_settings_change(query_dict)``
  (to put the settings into the shareable link).

The run's settings travel in the URL as the keys of :data:`URL_KEYS`
(:meth:`OptimizePanel.query` / :meth:`OptimizePanel.apply_query`). Runs are bounded: at most
:data:`MAX_EVALUATIONS` evaluations at a voxel edge of at least :data:`MIN_VOXEL`. Every text a
user typed is shown back only as plain text (viser text fields), never as markdown or HTML.
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import viser

from paraspace.kinematics.bytecache import ByteLRU
from paraspace.kinematics.design import Design, ParameterError
from paraspace.kinematics.joints import Joints
from paraspace.kinematics.optimize import DEFAULT_PARAMS, OptimizeSettings, optimize
from paraspace.kinematics.orientation import OrientationSettings
from paraspace.kinematics.workspace import WorkspaceSettings

from ..jobs import Job, JobManager, LimitExceeded
from ..optimize_plots import front_figure
from ..textsafe import md_text
from .session import SessionJobs

if TYPE_CHECKING:  # pragma: no cover - types only
    from paraspace.kinematics.sweep import ResultCache

__all__ = ["OptimizePanel", "URL_KEYS", "MAX_EVALUATIONS", "MIN_VOXEL", "PANEL_ORIENTATION"]

#: URL query keys of the run's settings (values as the panel's fields hold them).
URL_KEYS: dict[str, str] = {"opt_params": "params", "opt_objectives": "objectives",
                            "opt_constraints": "constraints", "opt_pop": "population",
                            "opt_gen": "generations", "opt_voxel": "voxel", "opt_seed": "seed"}
MAX_EVALUATIONS = 640
MIN_VOXEL = 4.0
#: Orientation sampling of the panel's runs when an objective needs TI_1/TI_2: 2 deg x 4 (the
#: defaults, 0.5 deg x 1, cost about 1.4 s per design, too much for a bounded interactive run).
PANEL_ORIENTATION = OrientationSettings(angle_step=2.0, position_step=4.0)
DEFAULTS: dict[str, Any] = {"params": ",".join(DEFAULT_PARAMS), "objectives": "volume,-footprint",
                            "constraints": "", "population": 16, "generations": 10, "voxel": 6.0, "seed": 1}


def _design_label(i: int, entry: dict, params: list[str], labels: list[str]) -> str:
    ps = ", ".join(f"{p}={entry['design'][p]:g}" for p in params)
    ms = ", ".join(f"{lb.lstrip('-')}={entry['measures'].get(lb.lstrip('-'), float('nan')):.4g}" for lb in labels)
    return f"#{i}: {ps} | {ms}"


class StatusLine:
    """The run's status as a markdown line that wraps in the panel (a text box cut it off); its
    ``value`` is the plain text, shown escaped."""

    def __init__(self, handle: Any) -> None:
        self._handle = handle
        self._value = "not run"

    @property
    def value(self) -> str:
        return self._value

    @value.setter
    def value(self, text: str) -> None:
        self._value = str(text)
        self._handle.content = f"**status:** {md_text(self._value, 600)}"


class OptimizePanel:
    """See the module docstring."""

    def __init__(self, gui: Any, jobs: JobManager | SessionJobs, *, get_design: Callable[[], Design],
                 load_design: Callable[[Design], None], get_joints: Callable[[], Joints] = Joints,
                 client: str = "local", cache: ResultCache | None = None,
                 results: ByteLRU | None = None,
                 on_settings_change: Callable[[dict[str, str]], None] | None = None) -> None:
        self.gui, self.jobs, self.client = gui, jobs, client
        self.get_design, self.load_design, self.get_joints = get_design, load_design, get_joints
        self.cache = cache
        self.results = results if results is not None else ByteLRU(16 << 20, max_entries=16)
        self.on_settings_change = on_settings_change
        self.result: dict | None = None
        self.job: Job | None = None
        self._lock = threading.Lock()
        self._gen = 0
        self._applying = False
        self.plot: Any = None
        self._build()

    # ----- GUI ------------------------------------------------------------------------------------
    def _build(self) -> None:
        g = self.gui
        g.add_markdown("Pareto front of workspace measures over design parameters (pymoo NSGA-II/III). "
                       "Objectives: measures, comma-separated; a leading `-` minimises "
                       "(`volume`, `-footprint`, `-hollowness`, `TI_1`...). "
                       "TI_1/TI_2 are sampled every 2 deg x 4 here (the CLI and API default to 0.5 deg x 1).")
        from paraspace.kinematics.design import PARAMS
        from paraspace.kinematics.objectives import MEASURES

        self.params = g.add_text("free parameters", initial_value=DEFAULTS["params"],
                                 hint="comma-separated, from: " + ", ".join(PARAMS))
        objective_names = [m for m, spec in MEASURES.items() if not spec.flag]
        self.objectives = g.add_text("objectives", initial_value=DEFAULTS["objectives"],
                                     hint="comma-separated, a leading - minimises; from: " + ", ".join(objective_names))
        self.constraints = g.add_text("constraints", initial_value=DEFAULTS["constraints"],
                                      hint="e.g. boundary_complete, volume>=2e6; flags: "
                                           + ", ".join(m for m, spec in MEASURES.items() if spec.flag))
        self.population = g.add_slider("population", min=4, max=32, step=1, initial_value=DEFAULTS["population"])
        self.generations = g.add_slider("generations", min=1, max=20, step=1, initial_value=DEFAULTS["generations"])
        self.voxel = g.add_slider("voxel h", min=MIN_VOXEL, max=12.0, step=1.0, initial_value=DEFAULTS["voxel"])
        self.seed = g.add_number("seed", initial_value=DEFAULTS["seed"], min=0, max=2**31 - 1, step=1)
        self.run_button = g.add_button("Run optimisation", icon=viser.Icon.PLAYER_PLAY)
        self.stop_button = g.add_button("Stop", color="red", icon=viser.Icon.PLAYER_STOP, visible=False)
        self.progress = g.add_progress_bar(0.0, visible=False)
        self.status = StatusLine(g.add_markdown("**status:** not run"))
        self.plot_folder = g.add_folder("Pareto front")
        self.designs = g.add_dropdown("front design", ("(no front yet)",), initial_value="(no front yet)")
        self.load_button = g.add_button("Load this design", icon=viser.Icon.DOWNLOAD, disabled=True)
        self.run_button.on_click(lambda _e: self.run())
        self.stop_button.on_click(lambda _e: self.stop())
        self.load_button.on_click(lambda _e: self.load_selected())
        self.designs.on_update(lambda _e: self._on_select())
        for h in (self.params, self.objectives, self.constraints, self.population, self.generations, self.voxel,
                  self.seed):
            h.on_update(lambda _e: self._settings_changed())

    # ----- settings and URL -----------------------------------------------------------------------
    def query(self) -> dict[str, str]:
        """The run's settings as URL query entries (keys of :data:`URL_KEYS`)."""
        vals = self._values()
        return {k: (f"{vals[v]:g}" if isinstance(vals[v], float) else str(vals[v])) for k, v in URL_KEYS.items()}

    def _values(self) -> dict[str, Any]:
        return {"params": str(self.params.value), "objectives": str(self.objectives.value),
                "constraints": str(self.constraints.value), "population": int(self.population.value),
                "generations": int(self.generations.value), "voxel": float(self.voxel.value),
                "seed": int(self.seed.value)}

    def apply_query(self, query: Mapping[str, str]) -> list[str]:
        """Set the fields from URL entries (others keep their values); show the front at once if
        the server holds the result of these settings. Returns one message per bad entry (the
        field keeps its value)."""
        errors: list[str] = []
        self._applying = True
        try:
            for key, field in URL_KEYS.items():
                if key not in query:
                    continue
                raw = str(query[key])[:200]
                handle = getattr(self, field)
                if field in ("params", "objectives", "constraints"):
                    handle.value = raw
                    continue
                lo, hi = ((handle.min, handle.max) if getattr(handle, "min", None) is not None
                          else (0, 2**31 - 1))
                try:
                    v = float(raw)
                    if not lo <= v <= hi:
                        raise ValueError
                    handle.value = int(v) if field in ("population", "generations", "seed") else v
                except (ValueError, TypeError):
                    errors.append(f"{key} = {raw!r} is invalid: valid range [{lo:g}, {hi:g}]")
        finally:
            self._applying = False
        self.show_cached()
        return errors

    def _settings_changed(self) -> None:
        if not self._applying and self.on_settings_change is not None:
            self.on_settings_change(self.query())

    def settings(self) -> OptimizeSettings:
        """The core settings of the fields and the host's current design.

        Raises:
            ParameterError: a field is invalid (the message names it).
        """
        v = self._values()
        if v["voxel"] < MIN_VOXEL:  # refused by name, never raised to the minimum without a word
            raise ParameterError("voxel", v["voxel"], f">= {MIN_VOXEL:g} in the explorer's optimiser")
        if v["population"] * v["generations"] > MAX_EVALUATIONS:
            raise ParameterError("generations", v["generations"],
                                 f"population x generations <= {MAX_EVALUATIONS} in the explorer")
        joints = self.get_joints()
        return OptimizeSettings(params=v["params"], objectives=v["objectives"],
                                constraints=[c for c in v["constraints"].split(",") if c.strip()],
                                design=self.get_design(),
                                workspace=WorkspaceSettings(voxel=v["voxel"], joints=joints),
                                orientation=dataclasses.replace(PANEL_ORIENTATION, joints=joints),
                                population=v["population"], generations=v["generations"], seed=v["seed"])

    # ----- running ----------------------------------------------------------------------------------
    def show_cached(self) -> bool:
        """Show the held result of the current settings, if any (no computation)."""
        try:
            s = self.settings()
        except ParameterError:
            return False
        hit = self.results.get(s.key())
        if hit is None:
            return False
        with self._lock:
            self._gen += 1
        self._show(hit, cached=True)
        return True

    def run(self) -> Job | None:
        """Start the run as a job (or show the held result of the same settings)."""
        try:
            s = self.settings()
        except ParameterError as e:
            self.status.value = str(e)
            return None
        key = s.key()
        if self.show_cached():
            return None
        with self._lock:
            self._gen += 1
            gen = self._gen
        cache = self.cache
        settings_dict = s.to_dict()
        history: list[dict] = []  # each finished generation's summary (the job's thread)
        partial: dict[str, dict] = {}  # "last": the front of the generations done so far

        def on_generation(info: dict) -> None:
            history.append({k: v for k, v in info.items() if k != "front"})
            front = {"settings": settings_dict, "front": info["front"], "generations": list(history),
                     "evaluations": info["evaluations"], "hypervolume": [], "failed": [], "partial": True}
            partial["last"] = front
            with self._lock:
                if gen != self._gen:
                    return
            self._show(front, cached=False, keep_status=True)  # the progress line keeps the status

        def fn(progress: Callable[[float, str], None], cancel: threading.Event) -> dict:
            return optimize(s, cache=cache, progress=progress, cancel=cancel, on_generation=on_generation).to_dict()

        def on_progress(job: Job) -> None:
            if gen == self._gen:
                self.progress.value = 100.0 * job.progress
                self.status.value = job.message or "running"

        def done(job: Job) -> None:
            if gen != self._gen:
                return
            self.stop_button.visible = False
            self.run_button.disabled = False
            self.progress.visible = False
            if job.status == "done":
                self.results.put(key, job.result)
                self._show(job.result, cached=False)
            elif partial:  # the front of the generations done stays, said to be partial (not held)
                last = partial["last"]
                done_gen = last["generations"][-1]["generation"]
                why = ("Stop pressed" if job.status == "cancelled"
                       else f"{job.status}: {job.error or job.message}")
                self.status.value = (f"stopped at generation {done_gen} of {s.generations} ({why}): "
                                     f"{len(last['front'])} designs on the front of the generations done, "
                                     f"{last['evaluations']} evaluations; not kept for this link: Run computes "
                                     f"all {s.generations}")
            else:
                self.status.value = ("stopped before the first generation ended (Stop pressed): no front"
                                     if job.status == "cancelled" else f"{job.status}: {job.error or job.message}")

        try:
            job = self.jobs.submit(fn, kind="optimize", client=self.client, supersede=True, on_done=done,
                                   on_progress=on_progress)
        except (LimitExceeded, RuntimeError) as exc:
            self.status.value = f"not started: {exc}"
            return None
        self.job = job
        self.progress.value = 0.0
        self.progress.visible = True
        self.stop_button.visible = True
        self.run_button.disabled = True
        self.status.value = f"running {s.population} x {s.generations} evaluations ({s.algorithm_used})"
        return job

    def stop(self) -> None:
        """Cancel the running job; the front of the generations it finished stays on screen, said to
        be partial, and is not held for the link (:meth:`run`)."""
        job = self.job
        if job is not None and not job.is_final:
            self.jobs.cancel(job.id)

    # ----- showing and loading ----------------------------------------------------------------------
    def _show(self, result: dict, *, cached: bool, keep_status: bool = False) -> None:
        """The front of ``result`` in the list and the plot, and the status line says what it is
        (``keep_status``: left as it is, for a run's partial front while its progress speaks)."""
        front = result["front"]
        params = list(result["settings"]["params"])
        labels = list(result["settings"]["objectives"])
        options = tuple(_design_label(i, e, params, labels) for i, e in enumerate(front)) or ("(empty front)",)
        self.designs.options = options
        self.designs.value = options[0]
        fig = front_figure(result, selected=0 if front else None)
        if self.plot is None:
            with self.plot_folder:
                self.plot = self.gui.add_plotly(fig, config={"displayModeBar": False})
        else:
            self.plot.figure = fig
        self.load_button.disabled = not front
        hv = result.get("hypervolume") or []
        if not keep_status:
            self.status.value = (f"{len(front)} designs on the front, {result['evaluations']} evaluations"
                                 + (f", hypervolume {hv[-1]:.3g}" if hv else "")
                                 + (f", {len(result['failed'])} failed" if result.get("failed") else "")
                                 + (" (held result, not recomputed)" if cached else ""))
        self.result = result  # last: a reader that sees the result sees the plot and the list

    def selected_index(self) -> int | None:
        """Index in the front of the dropdown's design (``None`` without a front)."""
        if not self.result or not self.result["front"]:
            return None
        value = str(self.designs.value)
        if not value.startswith("#"):
            return None
        try:
            return int(value[1:].split(":", 1)[0])
        except ValueError:
            return None

    def _on_select(self) -> None:
        i = self.selected_index()
        if i is not None and self.plot is not None and self.result is not None:
            self.plot.figure = front_figure(self.result, selected=i)

    def load_selected(self) -> Design | None:
        """Load the selected front design into the host (``load_design``); returns it."""
        i = self.selected_index()
        if i is None or self.result is None or i >= len(self.result["front"]):
            return None
        design = Design.from_dict(dict(self.result["front"][i]["design"]))
        self.load_design(design)
        return design
