"""Redundancy resolution: for a pose, the carriage values ``(d_i, eta_i)`` of each chain that keep
both of its legs furthest inside their limits (our documented definition).

Per chain ``i`` we maximise the margin

    m_i(eta, d) = min_j min(l_i^j - l_min, l_max - l_i^j)            (length units)

over the strokes ``eta in [eta_lo, eta_hi]``, ``d in [0, d_s]`` (a dense grid followed by two
zoom-in refinements around the best cell; deterministic). The chain is feasible when the best
margin is ``>= 0`` (within 1e-9). When it is not, the carriage pose of the least violation is
reported with the leg and the limit it fails ("leg 2 too long by 3.2"). The chains are
independent: each one's carriage only moves its own two legs.

The grid search can miss a thin feasible set of carriage poses (narrower than a grid cell). So
that ``ik`` never contradicts the workspace engine, a chain the search leaves infeasible is
tested with the engine's own exact-in-``d`` test (:mod:`kinematics.feasibility`, the same arc
samples): if some sample serves the chain, the carriage pose of largest margin inside its feasible
``rho`` intervals is used instead. The search itself is within a stated tolerance of the best
margin (tests: a 201 x 201 brute-force grid over the strokes).

With joint options (:mod:`kinematics.joints`) the margin-optimal carriage poses are checked
against the cones (J1) and the leg clearances; when they violate one, the engine's witness
configuration (:func:`kinematics.interference.clear_configuration`) is used when there is one,
so ``ik`` agrees with the engine there too. The report then carries every leg's cone angles and
the smallest distance between two legs.

Note: the workspace engine samples ``eta`` at a fixed spacing, this optimiser searches ``eta``
continuously, so at the very boundary of the workspace the optimiser can find poses that the
engine's one-sided sampling error misses (never the reverse).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from .design import Design
from .feasibility import ChainTables, chain_search, default_n_eta, feasible_rho
from .geometry import GAMMA, LEG_SIGN, base_points, platform_points
from .interference import clear_configuration, segment_distance
from .inverse import check_carriage, leg_lengths, leg_margin, leg_states
from .jacobian import jacobians
from .joints import Joints, cone_angles, cone_table
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
    condition_number: float | None
    message: str
    mode: str  # "auto" or "manual"
    joints: Joints = dataclasses.field(default_factory=Joints)
    cone_angles: np.ndarray | None = None  # (3, 2, 2) degrees at the U and S joints (joint options)
    min_leg_distance: float | None = None  # smallest distance between two legs' axes (interference)

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
            "joints": self.joints.to_dict(),
            "cone_angles": None if self.cone_angles is None else np.round(self.cone_angles, 6).tolist(),
            "min_leg_distance": self.min_leg_distance,
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


def _best_carriage(design: Design, B: np.ndarray, chain: int, starts: int = 1) -> tuple[float, float]:
    """Arg-max of the chain margin over the strokes: returns (d, eta_deg). A 73 x 61 grid, then
    two 21 x 21 zoom-ins around each of its ``starts`` best cells (the margin can have several
    local maxima); the best refined point wins."""
    e_lo, e_hi = np.radians(design.eta_limits)
    r_lo, r_hi = design.rho_limits
    n_e = 1 if e_hi <= e_lo else 73
    n_r = 1 if r_hi <= r_lo else 61
    eta = np.linspace(e_lo, e_hi, n_e) if n_e > 1 else np.array([e_lo])
    rho = np.linspace(r_lo, r_hi, n_r) if n_r > 1 else np.array([r_lo])
    m = _chain_margins(design, B, GAMMA[chain] + eta, rho)
    order = np.argsort(m, axis=None)[::-1][:starts]
    best_m, best = -np.inf, (float(eta[0]), float(rho[0]))
    for flat in order:
        k = np.unravel_index(int(flat), m.shape)
        cur = (float(eta[k[0]]), float(rho[k[1]]))
        de = (e_hi - e_lo) / max(n_e - 1, 1)
        dr = (r_hi - r_lo) / max(n_r - 1, 1)
        cur_m = float(m[k])
        for _ in range(2):
            lo_e, hi_e = max(e_lo, cur[0] - 2 * de), min(e_hi, cur[0] + 2 * de)
            lo_r, hi_r = max(r_lo, cur[1] - 2 * dr), min(r_hi, cur[1] + 2 * dr)
            ne = 1 if hi_e <= lo_e else 21
            nr = 1 if hi_r <= lo_r else 21
            ee = np.linspace(lo_e, hi_e, ne) if ne > 1 else np.array([lo_e])
            rr = np.linspace(lo_r, hi_r, nr) if nr > 1 else np.array([lo_r])
            mm = _chain_margins(design, B, GAMMA[chain] + ee, rr)
            kk = np.unravel_index(int(np.argmax(mm)), mm.shape)
            if mm[kk] >= cur_m:
                cur, cur_m = (float(ee[kk[0]]), float(rr[kk[1]])), float(mm[kk])
            de = (hi_e - lo_e) / max(ne - 1, 1)
            dr = (hi_r - lo_r) / max(nr - 1, 1)
        if cur_m > best_m:
            best_m, best = cur_m, cur
    return design.r - best[1], float(np.degrees(best[0])) + 0.0  # + 0.0: no negative zero


def _engine_carriage(design: Design, B: np.ndarray, chain: int, joints: Joints, rotation: np.ndarray,
                     eta_step: float):
    """The engine's test for one chain (module docstring): ``(d, eta_deg)`` of largest margin inside
    the feasible rho intervals of the first arc sample that serves the chain, or ``None``."""
    tab = ChainTables(design, default_n_eta(design, eta_step))
    jc = cone_table(design, joints, rotation)
    b1, b2 = B
    k = chain_search(*b1, *b2, tab.cos_t[chain], tab.sin_t[chain], tab.hb, tab.rho_lo, tab.rho_hi, tab.lmin2,
                     tab.lmax2, jc[chain], tab.n_eta // 2)
    if k < 0:
        return None
    pieces = np.zeros((4, 2))
    n = feasible_rho(*b1, *b2, tab.cos_t[chain, k], tab.sin_t[chain, k], tab.hb, tab.rho_lo, tab.rho_hi,
                     tab.lmin2, tab.lmax2, jc[chain], pieces)
    rho = np.concatenate([np.linspace(pieces[m, 0], pieces[m, 1], 101) for m in range(n)])
    varpi = np.array([GAMMA[chain] + np.radians(tab.eta_deg[k])])
    best = float(rho[int(np.argmax(_chain_margins(design, B, varpi, rho)[0]))])
    return design.r - best, float(tab.eta_deg[k])


def _pair_distance(dp: np.ndarray, b: np.ndarray) -> float:
    """Smallest distance between the axes of two of the six legs."""
    legs = [(dp[i, j], b[i, j]) for i in range(3) for j in range(2)]
    best = np.inf
    for x in range(6):
        for y in range(x + 1, 6):
            best = min(best, segment_distance(*legs[x][0], *legs[x][1], *legs[y][0], *legs[y][1]))
    return float(best)


def _assemble(design: Design, pose: Pose, d: np.ndarray, eta: np.ndarray, mode: str,
              joints: Joints | None = None) -> Resolution:
    joints = joints or Joints()
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
    where = "at the best carriage pose" if mode == "auto" else "with the carriage values set"
    angles, gap, joint_problem = None, None, ""
    if not joints.is_default:
        b = platform_points(design, pose.position, pose.rotation)
        dp = base_points(design, d, eta)
        angles = cone_angles(design, joints, pose.rotation, b, dp, eta)
        for col, name, lim in ((0, "U", joints.theta_u), (1, "S", joints.theta_s)):
            if lim is not None and angles[:, :, col].max() > lim + 1e-7:
                i, j = (int(k) for k in np.unravel_index(int(np.argmax(angles[:, :, col])), (3, 2)))
                joint_problem = joint_problem or (f"chain {i + 1}, leg {j + 1}: {name} joint at "
                                                  f"{angles[i, j, col]:.1f}° > theta_{name} = {lim:g}°")
        if joints.min_distance > 0.0:
            gap = _pair_distance(dp, b)
            if gap < joints.min_distance - 1e-7:
                joint_problem = joint_problem or (f"two legs {gap:.2f} apart < leg_diameter + clearance = "
                                                  f"{joints.min_distance:g}")
    if feasible and not joint_problem:
        message = "reachable"
    elif not feasible:
        worst = min((c for c in chains if not c.feasible), key=lambda c: c.margin)
        message = f"unreachable: {worst.binding} {where}"
    else:
        message = f"unreachable: {joint_problem} {where}"
    return Resolution(feasible=feasible and not joint_problem, chains=chains, d=d, eta=eta, lengths=lengths,
                      leg_status=status, condition_number=cond, message=message, mode=mode, joints=joints,
                      cone_angles=angles, min_leg_distance=gap)


def resolve_redundancy(design: Design, pose: Pose, joints: Joints | None = None,
                       eta_step: float = 0.5) -> Resolution:
    """Redundancy resolution (module docstring): the best carriage values of each chain at a pose.

    Parameters
    ----------
    design : Design
        The mechanism's dimensions.
    pose : Pose
        Platform position and orientation.
    joints : Joints, optional
        Joint cones and leg interference, the workspace engine's options, so that the verdict agrees
        with the engine.
    eta_step : float, optional
        Largest spacing of the arc samples, degrees (the engine's option).

    Returns
    -------
    Resolution
        The carriage values ``d`` and ``eta`` per chain, the leg lengths and states, the condition
        number of ``J`` (eq. (26)) there, and a one-line verdict ``message``.

    Examples
    --------
    >>> import paraspace as ps
    >>> r = ps.resolve_redundancy(ps.Design(), ps.Pose(0.0, 0.0, 130.0))
    >>> r.feasible, [round(c.d, 1) for c in r.chains]
    (True, [9.4, 9.4, 9.4])
    """
    joints = joints or Joints()
    B = platform_points(design, pose.position, pose.rotation)
    d = np.zeros(3)
    eta = np.zeros(3)
    for i in range(3):
        d[i], eta[i] = _best_carriage(design, B[i], i)
        varpi = np.array([GAMMA[i] + np.radians(eta[i])])
        if _chain_margins(design, B[i], varpi, np.array([design.r - d[i]]))[0, 0] < -1e-9:
            found = _engine_carriage(design, B[i], i, Joints(), pose.rotation, eta_step)
            if found is not None:
                d[i], eta[i] = found
    res = _assemble(design, pose, d, eta, "auto", joints)
    if not res.feasible and not joints.is_default and all(c.feasible for c in res.chains):
        conf = clear_configuration(design, joints, pose.position, pose.rotation, default_n_eta(design, eta_step))
        if conf is not None:
            res = _assemble(design, pose, conf[0], conf[1], "auto", joints)
    return res


def inverse_kinematics(design: Design, pose: Pose, d: Sequence[float], eta_deg: Sequence[float],
                       joints: Joints | None = None) -> Resolution:
    """Inverse kinematics with hand-set carriage values (validated against the strokes).

    Parameters
    ----------
    design : Design
        The mechanism's dimensions.
    pose : Pose
        Platform position and orientation.
    d : sequence of 3 floats
        Linear carriage positions ``d_1, d_2, d_3``, in ``[0, d_s]``.
    eta_deg : sequence of 3 floats
        Arc carriage positions ``eta_1, eta_2, eta_3``, degrees, inside the arc stroke.
    joints : Joints, optional
        With joint options, also the cone angles and the legs' clearances.

    Returns
    -------
    Resolution
        Leg lengths (eq. (15)) and their states, feasibility and a one-line verdict.

    Raises
    ------
    ParameterError
        A carriage value outside its stroke (named ``d_1`` .. ``eta_3``, with the valid range).

    Examples
    --------
    >>> import paraspace as ps
    >>> ik = ps.inverse_kinematics(ps.Design(), ps.Pose(0.0, 0.0, 130.0), [30.0] * 3, [0.0] * 3)
    >>> ik.feasible, round(ik.chains[0].lengths[0], 4)
    (True, 133.9284)
    """
    dd, ee = check_carriage(design, d, eta_deg)
    return _assemble(design, pose, dd, ee, "manual", joints)
