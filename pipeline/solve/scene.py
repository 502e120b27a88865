"""A scene: one mechanism analysed over a revolution (tables and dense curves).

Pure computation over the compiled plan; writing files is ``pipeline.results.storage``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..kernels import config as kc
from ..compiler import kernels_for, plan_path, scene_kernels_for
from ..compiler.notice import INSTALLATION, MECHANISM, compile_notice
from ..kernels.geometry import link_angles
from ..model.mechanism import Plan

ORDER = {"positions": kc.POSITIONS, "velocities": kc.VELOCITIES,
         "accelerations": kc.ACCELERATIONS, "forces": kc.ACCELERATIONS}


@dataclass
class Curves:
    """Kinematics at a sequence of crank angles (analogs with respect to phi1)."""
    phi: np.ndarray          # rad
    pos: np.ndarray          # (n, n_points, 2) mm
    d1: np.ndarray           # mm/rad
    d2: np.ndarray           # mm/rad^2
    status: np.ndarray       # (n,) int8
    margin: np.ndarray       # (n, n_groups)
    iterations: np.ndarray   # (n,)
    links: np.ndarray        # (n, n_links, 3): angle rad, analogs 1/rad, 1/rad^2
    overall: int
    fail_phi: float = math.nan   # rad: where the walk first failed, located between positions
    fail_group: int = -1         # the group that failed there (-1: none, or the closure)
    forces: object = None    # pipeline.solve.reactions.Reactions when computed
    extra: dict = field(default_factory=dict)


def revolution_angles(crank, n, closing_row=False):
    """phi1_k = phi0 + rot * 2 pi k / n, k = 0..n-1 (and k = n if closing_row)."""
    k = np.arange(n + 1 if closing_row else n, dtype=np.float64)
    return crank.phi0 + crank.rot * 2.0 * math.pi * k / n


def solve_curves(plan: Plan, phis, order, tols=None, par=None, close_at=math.nan) -> Curves:
    """Kinematics of ``plan`` at crank angles ``phis`` by continuation."""
    tols = kc.default_tolerances() if tols is None else tols
    par = plan.par if par is None else par
    out = _outputs(plan, len(phis))
    fail = np.empty(2)
    args = (np.ascontiguousarray(par, dtype=np.float64),
            np.ascontiguousarray(phis, dtype=np.float64), float(close_at), int(order), tols,
            *out, fail)
    # the plan path (kernels compiled once per installation, the same bits) where the
    # mechanism's groups are on it: a new mechanism's scene waits for no compile
    overall = plan_path.revolution(plan, *args)
    if overall is None:
        overall = kernels_for(plan).revolution(*args)
    return _curves(plan, phis, order, out, overall, fail_phi=float(fail[0]),
                   fail_group=int(fail[1]))


def _outputs(plan, n):
    """The walk's outputs for ``n`` positions: pos, d1, d2 (NaN where not
    computed), status, margin, iterations."""
    pos, d1, d2 = (np.full((n, plan.n_points, 2), np.nan) for _ in range(3))
    return pos, d1, d2, np.zeros(n, np.int8), np.zeros((n, plan.n_groups)), np.zeros(n)


def _curves(plan, phis, order, out, overall, **failure) -> Curves:
    """Curves of the walk's outputs ``out`` (``_outputs``), its links' angles added."""
    pos, d1, d2 = out[:3]
    links = np.full((len(pos), len(plan.link_a), 3), np.nan)
    link_angles(pos, d1, d2, plan.link_a, plan.link_b, int(order), links)
    return Curves(np.asarray(phis, float), *out, links, int(overall), **failure)


class Continuation:
    """A walk over ``phis`` that goes on from any of its positions: ``row(m, phi)``
    is the last row of ``solve_curves(plan, [*phis[:m], phi], order, tols)``, to the
    bit, for one step of the walk instead of m + 1 (the continuation's state after
    each position kept: ``kernels.walk.walk_states``): a refined peak's trial
    angles.  The row's ``overall`` is its own status (the watch's verdict on the
    windows before it, which ``solve_curves``' overall would also carry, is not
    looked at).  ``of`` gives None off the plan path (the walk from the start
    then)."""

    def __init__(self, plan, phis, order, tols, K):
        from ..kernels.walk import compile_revolution, walk_states
        compile_revolution()
        self.plan, self.phis, self.order, self.tols, self.K = plan, phis, int(order), tols, K
        self.advance, start = plan_path.first_class()
        self.states = np.empty((len(phis), int(K[3]), kc.N_STATE))
        walk_states(self.advance, start, K, plan.n_points, plan.n_groups, phis, self.order,
                    tols, self.states)

    @classmethod
    def of(cls, plan, phis, order, tols):
        K = plan_path.plan_constants(plan) if plan_path.covers(plan) else None
        phis = np.ascontiguousarray(phis, dtype=np.float64)
        return None if K is None or not len(phis) else cls(plan, phis, order, tols, K)

    def row(self, m, phi) -> Curves:
        """The walk through the first ``m`` positions (1 <= m <= len(phis)) on to
        ``phi``: its last row."""
        from ..kernels.walk import walk_on
        if not 1 <= m <= len(self.phis):
            raise ValueError(f"a walk goes on from one of its {len(self.phis)} positions, "
                             f"not after {m}")
        out = _outputs(self.plan, 1)
        st = walk_on(self.advance, self.K, self.states[m - 1], float(self.phis[m - 1]),
                     float(phi), self.order, self.tols, *out)
        return _curves(self.plan, [float(phi)], self.order, out, st)


@dataclass
class SceneResult:
    study: object
    plan: Plan
    table: Curves
    dense: Curves
    tolerances: np.ndarray
    dynamics: list | None = None     # solve.crank_motion.CaseResult per case, if the study asks
    peaks: list | None = None        # pipeline.solve.peaks.Peak, refined between grid positions
    motion: dict | None = None       # dwell error and stroke of the output rocker
    reduced: object = None           # solve.reduced_dynamics.Reduced for a study with dynamics
    counterweight: object = None     # solve.shaking.Counterweight, with forces
    flywheel: object = None          # solve.flywheel.Flywheel: [dynamics.flywheel]
    # per dynamics case: {"samples"[, "steady"]: solve.motion_forces.MotionForces}
    motion_forces: dict | None = None
    cyclogram: object = None         # solve.cyclogram.Cyclogram: phases and phase errors

    @property
    def status(self):
        """The scene's status: the dense revolution (which also checks closure),
        then the friction's (FRICTION_LOCK)."""
        kin = self.dense.overall if self.dense.overall != kc.OK else self.table.overall
        return kin if kin != kc.OK else self._locked()[0]

    def _locked(self):
        """(status, the curves' friction) of the first curves whose friction
        locks: the dense revolution's, then the table's."""
        for c in (self.dense, self.table):
            fr = getattr(c.forces, "friction", None)
            if fr is not None and fr.overall != kc.OK:
                return fr.overall, fr
        return kc.OK, None

    @property
    def failure(self):
        """None for an OK scene; else where it fails first: {status, phi_deg (the
        crank angle, located between positions), group (its name, or "closure"),
        points (the group's points)}."""
        c = self.dense if self.dense.overall != kc.OK else self.table
        if c.overall == kc.OK:
            st, fr = self._locked()
            if st == kc.OK:
                return None
            e = fr.fail_element          # a joint, or a slide after the joints
            nj = len(self.plan.joint_names)
            where = ([self.plan.point_names[int(self.plan.joint_point[e])]] if 0 <= e < nj
                     else [])
            return {"status": kc.STATUS_NAMES[st], "phi_deg": math.degrees(fr.fail_phi),
                    "group": fr.element_names[e] if e >= 0 else "friction", "points": where}
        g = c.fail_group
        names = self.plan.point_names
        return {"status": kc.STATUS_NAMES[c.overall], "phi_deg": math.degrees(c.fail_phi),
                "group": self.plan.group_names[g] if g >= 0 else "closure",
                "points": [names[int(i)] for i in self.plan.gidx[g] if i >= 0] if g >= 0 else []}


def check_centres_of_mass(study):
    """Refuse a study whose CAD reports put a centre of mass far outside its link
    (``study.cad_report.check_placed``), the links' points solved at the crank's
    first position (phi0) of the mechanism as declared: where a study is run,
    before it computes or writes anything.  A mechanism that does not assemble
    there is not checked here (its run reports where it fails)."""
    if not study.cad_bodies:
        return
    from ..study.cad_report import check_placed
    mech = study.mechanism
    plan = mech.compile()
    curves = solve_curves(plan, [mech.crank.phi0], kc.POSITIONS)
    if curves.status[0] != kc.OK:
        return
    pos = curves.pos[0]
    check_placed(study.cad_bodies, mech, lambda p: tuple(pos[plan.point(p)]))


def run_scene(study, tols=None) -> SceneResult:
    """Tables at the study's table positions (closing row included) and dense
    curves over one revolution, with the forces if the study asks for them."""
    plan = study.mechanism.compile()
    out = study.output
    order = ORDER[out.analysis]
    tols = kc.default_tolerances() if tols is None else tols
    crank = study.mechanism.crank
    forces = out.analysis == "forces"
    if forces:
        from .friction import scene_forces_with_friction

        def kinematics(phis):
            return solve_curves(plan, phis, kc.ACCELERATIONS, tols)
    # the first solve (the table's few positions) compiles a new mechanism's kernels, or
    # on the plan path those of the installation (once): said as a compile, with its
    # seconds, where it takes more than a second
    covered = plan_path.covers(plan, forces)
    with compile_notice(INSTALLATION if covered else MECHANISM):
        if not covered:                              # (else the generated module's forces
            scene_kernels_for(plan, forces=forces)   # compile beside meanwhile)
        table = solve_curves(plan, revolution_angles(crank, out.table_positions, True), order,
                             tols)
        if forces:
            table.forces = scene_forces_with_friction(study.mechanism, plan, table, kinematics)
    dense_phis = revolution_angles(crank, out.dense_positions)
    dense = solve_curves(plan, dense_phis, order, tols,
                         close_at=crank.phi0 + crank.rot * 2.0 * math.pi)
    if forces:
        dense.forces = scene_forces_with_friction(study.mechanism, plan, dense, kinematics)
    return SceneResult(study, plan, table, dense, tols)


def real_motion(curves: Curves, omega1, eps1):
    """Point velocities (m/s) and accelerations (m/s²), link omega (1/s) and
    eps (1/s^2) from the analogs: v = r' w, a = r'' w^2 + r' eps."""
    v = curves.d1 * omega1 / 1000.0
    a = (curves.d2 * omega1 ** 2 + curves.d1 * eps1) / 1000.0
    om = curves.links[:, :, 1] * omega1
    ep = curves.links[:, :, 2] * omega1 ** 2 + curves.links[:, :, 1] * eps1
    return v, a, om, ep


def batch_revolutions(study, pars, positions, order=kc.ACCELERATIONS, with_forces=False,
                      tols=None, n_jobs=None):
    """One revolution of every parameter row of ``pars`` (candidates of the
    study's mechanism) on all cores, reduced to (status, peak |r''| of the
    working point [mm/rad^2], peak joint reaction [N])."""
    from .reactions import sample_loads
    mech = study.mechanism
    plan = mech.compile()
    phis = revolution_angles(mech.crank, positions)
    tols = kc.default_tolerances() if tols is None else tols
    loads = sample_loads(mech, phis) if mech.loads else np.zeros((positions, 0, 3))
    n = pars.shape[0]
    status = np.zeros(n, np.int8)
    acc = np.zeros(n)
    peak = np.zeros(n)
    from ..compiler.parallel import run_rows
    run_rows(kernels_for(plan).batch, np.ascontiguousarray(pars), phis, int(order), tols,
             plan.point(study.output.working_point), bool(with_forces), mech.crank.omega1,
             mech.crank.eps1, loads, status, acc, peak, n_jobs=n_jobs)
    return status, acc, peak
