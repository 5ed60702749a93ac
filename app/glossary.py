"""What each number the product shows means: one definition per measure, written once.

The explorer shows these texts where a number is shown (a hover text on its name in the Numbers
and on the pinned strip, the hint of the optimiser's pick-lists), the design report prints them
under its table, and ``paraspace workspace --explain`` prints them in the terminal. A definition
says what is counted, in which unit, with the equation or the module that fixes it; it is the
short form of the definitions in :mod:`paraspace.kinematics.measures`,
:mod:`paraspace.kinematics.bracket` and :mod:`paraspace.kinematics.orientation`.

``tests/test_glossary.py`` checks that every measure the optimiser, the studies and the Numbers
offer has an entry here, so a new measure cannot reach the screen undefined.
"""

from __future__ import annotations

import html

from paraspace.kinematics.design import PARAMS
from paraspace.kinematics.presets import PRESETS, PresetParam

__all__ = ["DEFINITIONS", "define", "hover"]

#: name -> one-paragraph definition (plain text; units in words).
DEFINITIONS: dict[str, str] = {
    "volume": "V = N h³: the number N of reachable voxels (edge h) times the voxel volume, in units³. "
              "A voxel is reachable when its centre is reachable by the platform centre at the set "
              "orientation (psi, theta, phi) for some carriage position within the strokes.",
    "bracket": "Certified bracket V_in ≤ V ≤ V_out of the continuous workspace's volume: V_in counts "
               "blocks proven reachable everywhere (a Lipschitz bound on the leg lengths), V_out "
               "excludes only blocks proven unreachable everywhere; the true volume lies between them "
               "(kinematics.bracket; a general mechanism's: kinematics.mechanism_workspace.general_bracket).",
    "voids": "Enclosed voids: unreachable regions surrounded by the workspace on every side (not open "
             "to the outside or to a face of the box); the percentage is their volume over V + their "
             "volume.",
    "void_ratio": "Enclosed void volume / (V + enclosed void volume), 0 for a solid workspace.",
    "void_volume": "Volume of the enclosed voids, units³.",
    "hollowness": "Underside cavity ratio H / (H + V): H is the unreachable volume inside the convex "
                  "hull of the workspace with reachable space directly above it (the 'bowl' seen from "
                  "below, voids included); 0 for a solid block, near 1 for a thin dome.",
    "boundary": "Boundary complete ('sealed'): the workspace is one piece, not cut by the box, "
                "without tunnels, standing on the base so that it closes its underside all around "
                "(an inverted bowl whose rim meets the base; at most 2 % of the underside leaks). "
                "'Surface closed' (Topology) asks less: one piece not cut by the box. So a dome whose "
                "rim does not meet the base has a closed surface and an incomplete boundary.",
    "boundary_complete": "1 when the workspace is one uncut piece without tunnels whose underside is "
                         "sealed by the base all around, else 0 (kinematics.measures, 'sealed').",
    "boundary_closed": "1 when the voxel workspace's surface is closed (not cut by the box), else 0.",
    "boundary_closed_stable": "1 when the filtered solid is one piece not cut by the box (stable in h).",
    "topology": "Pieces: connected parts holding at least 1 % of V; fragments: smaller parts (with "
                "their share of V); genus: the number of handles (tunnels) of the outer surface after "
                "removing features narrower than the stated size (an open-close filter); these do not "
                "change with h. The voxel-level genus and component count are raw counts that change "
                "with h.",
    "pieces": "Connected parts holding at least 1 % of V (stable in h).",
    "fragments": "Connected parts below 1 % of V (and their share of V).",
    "fragment_volume_fraction": "Share of V held by the fragments (parts below 1 % of V).",
    "stable_genus": "Handles of the outer surface after an open-close filter that removes features "
                    "narrower than the stated size (stable in h).",
    "genus": "Handles (tunnels) of the voxel workspace's outer surface: a raw count that changes with h.",
    "components": "Connected components of the voxel workspace: a raw count that changes with h.",
    "euler_characteristic": "Euler characteristic chi = components - tunnels + voids of the voxel set.",
    "largest_component_fraction": "Share of V held by the largest connected component.",
    "box_contact_fraction": "Share of the computation box's face voxels that are reachable (0 when the "
                            "workspace lies inside the box).",
    "solidity": "V / volume of the convex hull of the reachable voxels (1 for a convex workspace).",
    "hull_volume": "Volume of the convex hull of the reachable voxels, units³.",
    "hollow_volume": "Underside cavity volume H (see hollowness), units³.",
    "sealed_cavity_volume": "Volume of cavities sealed by the workspace and the floor plane, units³.",
    "open_cavity_ratio": "The part of the underside cavity that leaks to the outside (not sealed by the "
                         "workspace and the base plane), over H + V as for hollowness.",
    "column_gap_ratio": "Q / (Q + V), Q the unreachable volume between reachable voxels of the same "
                        "vertical column (voids and pockets, not the open underside of a bowl).",
    "voxels": "Number N of reachable voxels.",
    "height": "z extent of the workspace's bounding box, units.",
    "width": "x extent of the workspace's bounding box, units.",
    "TI_1": "Rotation index TI₁ of eq. (28a): the area under the rotation range about z along the "
            "z line (x = y' = 0), in degree·units; '(lower bound ⚠)' when the range reaches the "
            "scan's ends, so a wider scan could give more.",
    "TI_2": "Tilt index TI₂ of eq. (28b): the area under the tilt ranges about y' along the x line "
            "and about x along the y' line (at z = z0), in degree·units.",
    "GCI": "Global conditioning index: the mean of 1/kappa (kappa the condition number of the "
           "Jacobian, eq. (26)) over the workspace; 1 is isotropic, 0 singular.",
    "gci": "Global conditioning index: the mean of 1/kappa (kappa the condition number of the "
           "Jacobian, eq. (26)) over the workspace; 1 is isotropic, 0 singular.",
    "footprint": "r + l_min + l_s: the base radius plus the longest leg, our proxy for the "
                 "mechanism's size, units.",
    "l_max": "Longest leg length l_min + l_s, units.",
    "compute": "Wall-clock seconds of the workspace computation and of building the displayed shell.",
    "pose": "Whether the platform pose of the Pose tab is reachable (some carriage position keeps "
            "every leg within its stroke and every joint within its cone) and whether its position "
            "lies in the computed workspace.",
    "features": "Features narrower than this size (twice the filter radius, in length units) are "
                "ignored by the stable topology: thinner necks and slots do not count as tunnels.",
}


DEFINITIONS.update({
    "task_fraction": "Share of the task that is reachable: of the region's sample points (each reachable at "
                     "every required orientation), or of the poses of a pose list (kinematics.task).",
    "task_margin": "How far the task region could grow (positive) or must shrink (negative) and stay in the "
                   "workspace, units; for a pose list the smallest leg slack (kinematics.task).",
    "contains_task": "1 when every sample of the task is reachable (task_fraction = 1), else 0.",
    "total_orientation_volume": "Volume of the positions from which every tilt up to T (all azimuths) and every "
                                "torsion within ±Q is reachable, units³ (kinematics.dexterous).",
})
# a design parameter offered as a measure (a size to minimise) is defined by its own description
DEFINITIONS.update({name: f"{spec.description} ({spec.unit or 'length units'}): a design parameter, offered as a "
                          "size to minimise" for name, spec in PARAMS.items()})
# a mechanism preset's numeric parameter, likewise, by its PresetParam's words (kinematics/presets.py)


def _preset_parameter(q: PresetParam) -> str:
    names = sorted(n for n, pr in PRESETS.items() if q in pr.params)
    return (f"{q.description} ({q.unit or 'length units'}): a parameter of the {', '.join(names)} "
            f"preset{'s' if len(names) > 1 else ''}, offered as a size to minimise")


DEFINITIONS.update({q.name: _preset_parameter(q)
                    for spec in PRESETS.values() for q in spec.params if q.numeric and q.name not in DEFINITIONS})


def define(name: str) -> str:
    """The definition of measure ``name``; ``KeyError`` when it has none (tests rely on that)."""
    return DEFINITIONS[name]


def hover(label: str, name: str) -> str:
    """``label`` as HTML whose hover text (``title``) is the definition of ``name``, for viser's
    markdown (which renders raw HTML): the definition is escaped, the label too. A dotted
    underline says that it can be hovered."""
    return (f'<span title="{html.escape(define(name), quote=True)}" '
            f'style="text-decoration: underline dotted; cursor: help">{html.escape(label)}</span>')
