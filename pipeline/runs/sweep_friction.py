"""A sweep's or a search's metrics with friction in the joints
([mechanism.friction]): the careful path, candidate by candidate.

For every candidate that reaches the force stage (status OK, the stroke and
margin constraints met: the kernels' ``M_FORCES_DONE``), its kinematics with
second analogs at the grid's positions (the generated ``revolution``, by
continuation) and, at each position, the reactions with friction by Newton
from the frictionless solution (``kernels.friction.friction_revolution``).
Its row then carries the friction metrics (``friction_loss``, ``peak_pv``)
and the kernels' force peaks replaced by those with friction (peak_reaction,
peak_joint, peak_phi, peak_M_bal); a candidate whose friction locks at a
position is FRICTION_LOCK, its crank angle located between the positions as
a scene locates it (``solve.friction.bisect_lock``), its joint or slide in
the fail_group column (the results file names them).

Why not the lanes: the friction's Newton iteration (a dense solve of the
3 x bodies unknowns per step, its determinant for the lock) is not the
closed form the force lanes vectorise; ``benchmarks/bench_friction.py``
measures what it costs against the same sweep without friction.
"""

from __future__ import annotations

import math

import numpy as np

from ..kernels import config as kc
from ..kernels import sweep as ks

# the friction metrics' columns, after the robust ones (model.metric_catalogue)
LOSS, PEAK_PV = 0, 1
N_FRICTION = 2
SLICE = 64          # candidates per slice: progress told, an interruption answered


class SweepFriction:
    """The friction stage of a sweep's problem (picklable: plain arrays)."""

    def __init__(self, mechanism, plan):
        spec = mechanism.friction
        self.spec = spec
        self.mechanism = mechanism      # its external loads between the positions (a lock)
        self.names = tuple(plan.joint_names) + tuple(plan.slide_names)
        d = np.asarray(spec.diameters(), float)
        self.radius = d * 0.5e-3                                  # m
        self.pin_area = d * np.asarray(spec.lengths(), float)     # mm^2
        self.block = np.asarray(spec.block_lengths(), float).reshape(len(plan.slide_names))

    def fill(self, problem, pars, status, rows, column0, n_jobs=None, parallel=True,
             watch=None):
        """The friction columns (from ``column0``) and the force peaks with
        friction of the rows that reached the force stage; ``status`` set to
        FRICTION_LOCK where a candidate locks."""
        idx = np.flatnonzero((status == kc.OK) & (rows[:, ks.M_FORCES_DONE] == 1.0))
        if not len(idx):
            return
        from ..compiler.parallel import default_jobs
        workers = 1 if not parallel else (default_jobs() if n_jobs is None else int(n_jobs))
        # the first on this thread: the kernels compile or load once, before any thread
        # shares them (numba's compile of the walk is not for two threads at once)
        self._rows(problem, pars, idx[:1], status, rows, column0)
        idx = idx[1:]
        for lo in range(0, len(idx), SLICE * workers):
            if watch is not None:
                watch.check()
            part = idx[lo:lo + SLICE * workers]
            if workers == 1 or len(part) == 1:
                self._rows(problem, pars, part, status, rows, column0)
            else:
                from concurrent.futures import ThreadPoolExecutor
                with ThreadPoolExecutor(workers) as pool:   # the kernels release the GIL
                    list(pool.map(lambda p: self._rows(problem, pars, p, status, rows,
                                                       column0),
                                  np.array_split(part, workers)))
            if watch is not None:
                watch.reached((lo + len(part)) / len(idx))

    def _rows(self, problem, pars, part, status, rows, column0):
        from ..kernels.friction import friction_revolution
        plan = problem.plan
        n = len(problem.phis)
        npnt, ng = plan.n_points, plan.n_groups
        nb, nj, ns = len(plan.body_names), len(plan.joint_names), len(plan.slide_names)
        m = 3 * nb
        pos, d1, d2 = (np.empty((n, npnt, 2)) for _ in range(3))
        st, margin, iters, fail = np.zeros(n, np.int8), np.zeros((n, ng)), np.zeros(n), \
            np.empty(2)
        a0, jac = np.empty((m, m)), np.empty((m, m))
        b0, res, x = np.empty(m), np.empty(m), np.empty(m)
        sense, fric, speed = np.empty(nj + ns), np.empty(nj + ns), np.empty(nj + ns)
        body_loads, R, S = np.empty((nb, 3)), np.empty((nj, 2)), np.empty((ns, 2))
        found, out = np.empty(4), np.empty(9)
        revolution = problem.kernels.revolution
        for i in part:
            par = pars[i]
            overall = revolution(par, problem.phis, problem.phi_close, kc.ACCELERATIONS,
                                 problem.tols, pos, d1, d2, st, margin, iters, fail)
            if overall != kc.OK:    # the kernels' own positions assembled: not expected
                status[i] = overall
                rows[i, ks.M_FAIL_PHI] = fail[0]
                rows[i, ks.M_FAIL_GROUP] = fail[1]
                continue
            friction_revolution(*self._args(problem, par, pos, d1, d2), a0, b0, jac, res, x,
                                sense, body_loads, R, S, fric, speed, found, out)
            if out[0] != kc.OK:
                phi, element = self._locate(problem, par, int(out[7]), int(out[8]))
                status[i] = int(out[0])
                rows[i, ks.M_FAIL_PHI] = phi
                rows[i, ks.M_FAIL_GROUP] = problem.plan.n_groups + element if element >= 0 \
                    else math.nan
                for c in (ks.M_PEAK_R, ks.M_PEAK_JOINT, ks.M_PEAK_PHI, ks.M_PEAK_MBAL):
                    rows[i, c] = math.nan
                continue
            rows[i, column0 + LOSS] = out[1]
            rows[i, column0 + PEAK_PV] = out[2]
            rows[i, ks.M_PEAK_R] = out[3]
            rows[i, ks.M_PEAK_JOINT] = out[4]
            rows[i, ks.M_PEAK_PHI] = out[5]
            rows[i, ks.M_PEAK_MBAL] = out[6]

    def _args(self, problem, par, pos, d1, d2, phis=None, loads=None):
        plan = problem.plan
        return (problem.phis if phis is None else phis, pos, d1, d2, float(problem.omega1),
                float(problem.eps1), plan.gravity, par, plan.body_com, plan.body_turn,
                plan.body_mass_off, plan.joint_point, plan.joint_bodies, plan.slide_bodies,
                plan.slide_dir, plan.slide_angle, int(plan.crank_body), plan.load_body,
                plan.load_point, problem.loads if loads is None else loads,
                float(self.spec.revolute), self.radius, float(self.spec.slide), self.block,
                self.pin_area, REL_TOL, MAX_ITER)

    def _locate(self, problem, par, k, element):
        """(crank angle [rad], element) of the first lock, between positions
        k - 1 and k (``solve.friction.bisect_lock``)."""
        from ..solve.friction import bisect_lock
        from ..solve.reactions import sample_loads
        from ..solve.scene import solve_curves
        phis = problem.phis
        if k == 0:
            return float(phis[0]), element
        prefix = np.asarray(phis[:k], float)

        def state(mid):
            c = solve_curves(problem.plan, np.append(prefix, mid), kc.ACCELERATIONS,
                             problem.tols, par, problem.phi_close)
            if c.status[-1] != kc.OK:
                return False, -1
            out = np.empty(9)
            self._one(problem, par, c, mid, sample_loads(self.mechanism, np.array([mid])), out)
            return out[0] == kc.OK, int(out[8])
        return bisect_lock(float(phis[k - 1]), float(phis[k]), element, state)

    def _one(self, problem, par, c, phi, loads, out):
        from ..kernels.friction import friction_revolution
        plan = problem.plan
        nb, nj, ns = len(plan.body_names), len(plan.joint_names), len(plan.slide_names)
        m = 3 * nb
        friction_revolution(*self._args(problem, par, c.pos[-1:], c.d1[-1:], c.d2[-1:],
                                        np.array([phi]), loads),
                            np.empty((m, m)), np.empty(m), np.empty((m, m)), np.empty(m),
                            np.empty(m), np.empty(nj + ns), np.empty((nb, 3)),
                            np.empty((nj, 2)), np.empty((ns, 2)), np.empty(nj + ns),
                            np.empty(nj + ns), np.empty(4), out)


REL_TOL = 1e-12     # as a scene's (solve.friction)
MAX_ITER = 50
