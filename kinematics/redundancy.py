"""Redundancy resolution: for a pose, the carriage values ``(d_i, eta_i)`` of each chain that keep
both of its legs furthest inside their limits (our documented definition).

Per chain ``i`` we maximise the margin

    m_i(eta, d) = min_j min(l_i^j - l_min, l_max - l_i^j)            (length units)

over the strokes ``eta in [eta_lo, eta_hi]``, ``d in [0, d_s]`` (a dense grid followed by two
zoom-in refinements around the best cell; deterministic). The chain is feasible when the best
margin is ``>= 0`` (within 1e-9). When it is not, the carriage pose of the least violation is
reported with the leg and the limit it fails ("leg 2 too long by 3.2"). The chains are
independent: each one's carriage only moves its own two legs.

Note: the workspace engine samples ``eta`` at a fixed spacing, this optimiser searches ``eta``
continuously, so at the very boundary of the workspace the two can disagree by the engine's
documented one-sided sampling error.
"""

from __future__ import annotations

import dataclasses
from typing import Optional, Sequence

import numpy as np

from .design import Design
from .geometry import GAMMA, LEG_SIGN, platform_points
from .inverse import check_carriage, leg_lengths, leg_margin, leg_states
from .jacobian import jacobians
from .pose import Pose


@dataclasses.dataclass
class ChainResolution:
    """Carriage choice and leg state of one chain (``chain`` zero-based; the paper's i = chain + 1)."""

    chain: int
    feasible: bool
    d: float
    eta: float  # degrees
    lengths: list[float]
    margin: float
    leg_status: list[str]
    binding: str  # what limits this chain at the chosen carriage pose

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclasses.dataclass
class Resolution:
    """IK with redundancy resolved (or with hand-set carriages)."""

    feasible: bool
    chains: list[ChainResolution]
    d: np.ndarray  # (3,)
    eta: np.ndarray  # (3,) degrees
    lengths: np.ndarray  # (3, 2)
    leg_status: list[list[str]]
    condition_number: Optional[float]
    message: str
    mode: str  # "auto" or "manual"

    @property
    def q(self) -> np.ndarray:
        """Actuator vector ``q = [l_1^1..l_3^2, d_1..d_3, eta_1..eta_3 (deg)]`` (eq. (20))."""
        return np.concatenate([self.lengths.reshape(6), self.d, self.eta])

    def to_dict(self) -> dict:
        return {
            "feasible": self.feasible,
            "message": self.message,
            "mode": self.mode,
            "d": [float(v) for v in self.d],
            "eta": [float(v) for v in self.eta],
            "lengths": [[float(v) for v in row] for row in self.lengths],
            "leg_status": self.leg_status,
            "condition_number": (None if self.condition_number is None or not np.isfinite(self.condition_number)
                                 else float(self.condition_number)),
            "chains": [c.to_dict() for c in self.chains],
        }


def _describe(design: Design, chain: int, lengths: Sequence[float], margin: float) -> str:
    j = int(np.argmin(leg_margin(design, np.asarray(lengths))))
    l = float(lengths[j])
    leg = f"chain {chain + 1}, leg {j + 1}"
    if l < design.l_min:
        return f"{leg} too short by {design.l_min - l:.3g} (l = {l:.2f} < l_min = {design.l_min:g})"
    if l > design.l_max:
        return f"{leg} too long by {l - design.l_max:.3g} (l = {l:.2f} > l_max = {design.l_max:g})"
    near = "l_min" if l - design.l_min <= design.l_max - l else "l_max"
    return f"{leg} closest to {near} (margin {margin:.3g})"


def _chain_margins(design: Design, B: np.ndarray, varpi: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """Margins on a (n_eta, n_rho) grid for one chain's platform points ``B`` (2, 3)."""
    c, s = np.cos(varpi)[:, None], np.sin(varpi)[:, None]
    m = np.full((varpi.size, rho.size), np.inf)
    for j in range(2):
        lat = LEG_SIGN[j] * design.b / 2.0
        dx = B[j, 0] - (c * rho[None, :] - s * lat)
        dy = B[j, 1] - (s * rho[None, :] + c * lat)
        l = np.sqrt(dx * dx + dy * dy + B[j, 2] ** 2)
        m = np.minimum(m, np.minimum(l - design.l_min, design.l_max - l))
    return m


def _best_carriage(design: Design, B: np.ndarray, chain: int) -> tuple[float, float]:
    """Arg-max of the chain margin over the strokes: returns (d, eta_deg)."""
    e_lo, e_hi = np.radians(design.eta_limits)
    r_lo, r_hi = design.rho_limits
    lo_e, hi_e, lo_r, hi_r = e_lo, e_hi, r_lo, r_hi
    n_e = 1 if hi_e <= lo_e else 73
    n_r = 1 if hi_r <= lo_r else 61
    best = (0.5 * (e_lo + e_hi), 0.5 * (r_lo + r_hi))
    for _ in range(3):
        eta = np.linspace(lo_e, hi_e, n_e) if n_e > 1 else np.array([lo_e])
        rho = np.linspace(lo_r, hi_r, n_r) if n_r > 1 else np.array([lo_r])
        m = _chain_margins(design, B, GAMMA[chain] + eta, rho)
        k = np.unravel_index(int(np.argmax(m)), m.shape)
        best = (float(eta[k[0]]), float(rho[k[1]]))
        de = (hi_e - lo_e) / max(n_e - 1, 1)
        dr = (hi_r - lo_r) / max(n_r - 1, 1)
        lo_e, hi_e = max(e_lo, best[0] - 2 * de), min(e_hi, best[0] + 2 * de)
        lo_r, hi_r = max(r_lo, best[1] - 2 * dr), min(r_hi, best[1] + 2 * dr)
        n_e = 1 if hi_e <= lo_e else 21
        n_r = 1 if hi_r <= lo_r else 21
    return design.r - best[1], float(np.degrees(best[0])) + 0.0  # + 0.0: no negative zero


def _assemble(design: Design, pose: Pose, d: np.ndarray, eta: np.ndarray, mode: str) -> Resolution:
    lengths = leg_lengths(design, pose, d, eta)
    status = leg_states(design, lengths)
    chains = []
    for i in range(3):
        margin = float(leg_margin(design, lengths[i]).min())
        feasible = margin >= -1e-9
        chains.append(ChainResolution(chain=i, feasible=feasible, d=float(d[i]), eta=float(eta[i]),
                                      lengths=[float(v) for v in lengths[i]], margin=margin,
                                      leg_status=status[i], binding=_describe(design, i, lengths[i], margin)))
    feasible = all(c.feasible for c in chains)
    cond = jacobians(design, pose, d, eta).condition_number
    if feasible:
        message = "reachable"
    else:
        worst = min((c for c in chains if not c.feasible), key=lambda c: c.margin)
        where = "at the best carriage pose" if mode == "auto" else "with the carriage values set"
        message = f"unreachable: {worst.binding} {where}"
    return Resolution(feasible=feasible, chains=chains, d=d, eta=eta, lengths=lengths, leg_status=status,
                      condition_number=cond, message=message, mode=mode)


def resolve_redundancy(design: Design, pose: Pose) -> Resolution:
    """Redundancy resolution (module docstring): best carriage values per chain, leg lengths, leg
    states, the condition number of ``J`` (eq. (26)) there, and a one-line verdict."""
    B = platform_points(design, pose.position, pose.rotation)
    d = np.zeros(3)
    eta = np.zeros(3)
    for i in range(3):
        d[i], eta[i] = _best_carriage(design, B[i], i)
    return _assemble(design, pose, d, eta, "auto")


def inverse_kinematics(design: Design, pose: Pose, d: Sequence[float], eta_deg: Sequence[float]) -> Resolution:
    """IK with hand-set carriage values (validated against the strokes): leg lengths and states."""
    dd, ee = check_carriage(design, d, eta_deg)
    return _assemble(design, pose, dd, ee, "manual")
