"""Resource limits of the REST API (:class:`ApiLimits`), checked before any work is queued."""

from __future__ import annotations

import dataclasses
from typing import Any

from paraspace.kinematics.task import MAX_CSV_BYTES

from ..limits import MAX_VOXELS


@dataclasses.dataclass(frozen=True)
class ApiLimits:
    """Resource limits of the API, checked before any work is queued.

    Attributes:
        max_voxels: voxels of one workspace grid (computed from the bounds and the voxel edge
            before running; for default bounds the design's derived box). Over it: 413.
        max_sweep_points: design points of one sweep (1-D length, or the 2-D product). Over: 413.
        max_sweep_voxels: voxels summed over a sweep's points (each point's analytical reach box,
            an upper bound). Over it: 413.
        max_orientation_samples: position x angle samples of an orientation request (3 lines x
            3 rotations), per design point. Over it: 413.
        max_task_samples: lattice points x orientation samples of a region task (its box and margin
            shell). Over it: 413.
        max_jobs_per_client: unfinished API jobs per client. Over it: 429.
        max_jobs_total: unfinished API jobs over all clients. Over it: 429.
        max_job_seconds: run time of one job; after it the job is stopped and reported failed.
        max_body_bytes: size of a request body. Over it: 413. The default holds the largest pose
            list a task takes (:data:`kinematics.task.MAX_CSV_BYTES`) with 64 KiB to spare, so the
            REST API takes the same pose lists as the CLI.
        max_body_seconds: seconds a request body may take to arrive in full (a body dripped more
            slowly holds a worker): after it, 408.
        max_shell_faces: largest ``max_faces`` accepted for shell downloads.
        client_header: take the client identity from this request header (set it only behind a
            proxy you control that overwrites the header); ``None``: the connection's peer address
            (which uvicorn takes from X-Forwarded-For only for ``paraspace serve --trusted-proxy``).
        cache_bytes: finished results kept per kind (workspace, orientation, sweep, optimize), in
            bytes (estimated, voxel grids included).
        shell_cache_bytes: exported shell files kept for repeated downloads, in bytes.
        max_optimize_evaluations: population x generations of one optimisation. Over it: 413.
        max_optimize_voxels: evaluations x the voxels of the largest design in the bounds (the
            analytical reach box at every corner of the parameter box, an upper bound). Over: 413.
    """

    max_voxels: int = MAX_VOXELS
    max_sweep_points: int = 64
    max_sweep_voxels: int = 200_000_000
    max_orientation_samples: int = 20_000_000
    max_task_samples: int = 20_000_000
    max_jobs_per_client: int = 4
    max_jobs_total: int = 16
    max_job_seconds: float = 300.0
    max_body_bytes: int = MAX_CSV_BYTES + 65_536
    max_body_seconds: float = 10.0
    max_shell_faces: int = 2_000_000
    client_header: str | None = None
    cache_bytes: int = 256 << 20
    shell_cache_bytes: int = 128 << 20
    # --- optimisation (issue 11) ---
    max_optimize_evaluations: int = 2000
    max_optimize_voxels: int = 4_000_000_000

    def to_dict(self) -> dict[str, Any]:
        """JSON form (reported by ``/health``)."""
        return dataclasses.asdict(self)
