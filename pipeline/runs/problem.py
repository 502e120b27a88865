"""The problem a sweep's worker evaluates: plain arrays and the sweep's
settings (picklable), the generated kernels on first use; the notice around
the first evaluation, which compiles a new mechanism's kernels, is
``compiler.notice``'s."""

from __future__ import annotations

import math
import threading
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from ..kernels import config as kc
from ..kernels import sweep as ks
from ..study.sampling import draw_checked
from ..study.sweep_spec import SweepSpec, parameter_rows


_DRAWS_LOCK = threading.Lock()


@contextmanager
def _told(watch, n):
    """Around the evaluation of ``n`` rows: the share of ``watch``
    (``builds.Watch``) that is told of them (None without a watch), asked first
    whether to stop, and told at the end that they are done."""
    share = None if watch is None else watch.share(n)
    if share is not None:
        share.check()
    yield share
    if share is not None:
        share.reached(1.0)


@dataclass
class SweepProblem:
    """Everything a worker needs to evaluate a chunk: plain arrays and the spec
    (picklable; no study objects, no expressions)."""
    spec: SweepSpec
    plan: object
    phis: np.ndarray
    phi_close: float
    tols: np.ndarray
    rocker: tuple            # (pivot, point) names of the output rocker
    dwell_w: int
    omega1: float
    eps1: float
    loads: np.ndarray
    work_point: int = -1     # point index of the working point (peak_acceleration)
    law: np.ndarray | None = None   # the motion law at the grid's positions (law_error)
    law_best: bool = True    # the law shifted to fit best (align = "best")
    device: str = "cpu"      # cpu | gpu (resolved: never auto)
    robust: object = None    # pipeline.runs.builds.RobustBuilds: the robust metrics asked
    friction: object = None  # pipeline.runs.sweep_friction.SweepFriction: [mechanism.friction]

    @property
    def has_margin(self) -> bool:
        """Whether the plan has a class III group (its singularity margin is a constraint)."""
        return self.plan.has_continued

    @property
    def kernels(self):
        """The mechanism's generated kernels (compiled on first use, then cached)."""
        from ..compiler import kernels_for
        return kernels_for(self.plan, self.rocker)

    def settings(self):
        s = self.spec
        return ks.settings(s.stroke_radius, self.dwell_w, s.wants_forces, s.stroke_bounds[0],
                           s.stroke_bounds[1], s.margin_min, self.omega1, self.eps1,
                           want_peaks=s.wants_peaks, work_point=self.work_point,
                           want_transmission=s.wants_transmission,
                           law=self.law if s.wants_law else None, law_best=self.law_best,
                           want_equilibrium=s.wants("equilibrium_residual"),
                           want_shaking=s.wants("peak_shaking_force", "peak_shaking_moment"))

    @property
    def device_name(self):
        """'cpu', or the GPU the kernels run on (pipeline.runs.gpu.describe)."""
        if self.device == "cpu":
            return "cpu"
        from .gpu import describe
        return describe()

    def gpu(self):
        """The sweep's CUDA kernels on this process's GPU (made once; not pickled)."""
        g = self.__dict__.get("_gpu")
        if g is None:
            from .gpu import BATCH, GpuSweep
            # a launch no larger than a chunk: device memory follows --chunk-size
            g = self.__dict__["_gpu"] = GpuSweep(self, batch=min(BATCH, self.spec.chunk_size))
        return g

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("_gpu", None)
        state.pop("_draws", None)
        return state

    def evaluate_rows(self, pars, parallel=True, n_jobs=None, watch=None):
        """Status and metric rows (N_METRICS) of the parameter rows ``pars``: on
        the GPU (device 'gpu'), else on ``n_jobs`` threads (all cores by
        default), or on the calling thread only (``parallel=False``: a Dask
        task).  ``watch`` (``builds.Watch``): told of the rows done as the
        work goes (the robust metrics' builds, slice by slice), and asked
        between two slices whether to stop."""
        with _told(watch, len(pars)) as share:
            if self.device == "gpu":
                status, metrics = self.gpu().evaluate_rows(pars)
            else:
                from ..compiler.parallel import run_rows
                n = pars.shape[0]
                status = np.zeros(n, np.int8)
                metrics = np.full((n, ks.N_METRICS), np.nan)
                run_rows(self.kernels.evaluate, np.ascontiguousarray(pars), self.phis,
                         self.phi_close, self.tols, self.settings(), self.loads, status,
                         metrics, n_jobs=n_jobs if parallel else 1)
            if self.robust is not None or self.friction is not None:
                # the robust metrics' columns after the kernels', then the friction's
                from ..model.metric_catalogue import N_ROBUST_ROW, N_ROW
                width = N_ROW if self.friction is not None else N_ROBUST_ROW
                metrics = np.concatenate([metrics, np.full((len(status),
                                                            width - ks.N_METRICS), np.nan)],
                                         axis=1)
            if self.friction is not None:   # before the robust builds: they read its peaks
                self.friction.fill(self, pars, status, metrics, N_ROBUST_ROW, n_jobs, parallel,
                                   share if self.robust is None else None)
            if self.robust is not None:
                self.robust.fill(np.ascontiguousarray(pars, float), status, metrics, n_jobs,
                                 parallel, share)
        return status, metrics

    def draw_chunk(self, chunk, draw=None):
        """(x, rejected draws per triangle, parameter rows) of chunk ``chunk``; on
        the GPU, a Sobol sweep's are drawn there and its parameter rows stay there
        (``gpu_draws``: the same bits).  ``draw(chunk)``: (x, rejected) as
        ``draw_checked`` gives them, drawn elsewhere (``draw_ahead``)."""
        draws = self._device_draws()
        if draws is not None:
            return draws.draw(chunk)
        x, rejected = draw_checked(self.spec, chunk) if draw is None else draw(chunk)
        return x, rejected, parameter_rows(self.plan, self.spec, x)

    def _device_draws(self):
        """The device's draws (made once), or None where the host draws: not on
        the GPU, another sampler, or robust metrics or friction, whose stages
        read the rows on the host."""
        if self.device != "gpu" or self.robust is not None or self.friction is not None:
            return None
        with _DRAWS_LOCK:
            draws = self.__dict__.get("_draws")
            if draws is None:
                from .gpu_draws import DeviceDraws, applies
                if not applies(self.spec):
                    return None
                draws = self.__dict__["_draws"] = DeviceDraws(self)
        return draws

    def evaluate_chunk(self, chunk, parallel=True, n_jobs=None, watch=None, drawn=None):
        """(chunk, x, status, metrics, rejected draws per triangle, kept); ``drawn``:
        the chunk's ``draw_chunk``, where the caller drew it ahead.  ``kept``:
        None, or where the GPU kept the feasible rows only (``_keeps_on_device``)
        their indices, ``metrics`` their rows alone."""
        x, rejected, pars = self.draw_chunk(chunk) if drawn is None else drawn
        if self._keeps_on_device():
            with _told(watch, len(pars)):
                status, metrics, kept = self.gpu().evaluate_kept(pars)
            return chunk, x, status, metrics, rejected, kept
        status, metrics = self.evaluate_rows(pars, parallel, n_jobs, watch)
        return chunk, x, status, metrics, rejected, None

    def _keeps_on_device(self):
        """Whether a chunk's feasible rows are judged and gathered on the GPU
        (``gpu_kept``): a store-feasible sweep there, without robust metrics or
        friction (whose stages read every row's metrics on the host)."""
        return (self.device == "gpu" and self.spec.store == "feasible"
                and self.robust is None and self.friction is None)


def _sweep_tolerances(tols):
    """The sweep's tolerances: ``tols`` (the defaults if None), a walk stopped at
    its first failure (T_GO_ON 0: after it a scene's walk solves on, to show what
    can be shown, which a sweep never reads; the same numbers)."""
    tols = kc.default_tolerances() if tols is None else np.array(tols, dtype=np.float64)
    tols[kc.T_GO_ON] = 0.0
    return tols


def plain_problem(study, spec: SweepSpec, tols=None, device="cpu") -> SweepProblem:
    """The sweep's problem of ``study`` under ``spec``: plain arrays a worker
    evaluates (its robust metrics' builds are ``runs.sweep.build_problem``'s)."""
    from ..solve.reactions import sample_loads
    from ..solve.scene import revolution_angles
    mech = study.mechanism
    plan = mech.compile()
    crank = mech.crank
    phis = revolution_angles(crank, spec.positions)
    out = study.output
    law = out.motion_law
    return SweepProblem(
        spec=spec, plan=plan, phis=phis, phi_close=crank.phi0 + crank.rot * 2 * math.pi,
        tols=_sweep_tolerances(tols),
        rocker=(out.rocker[0], out.rocker[1]),
        dwell_w=int(round(out.dwell_deg * spec.positions / 360)),
        omega1=crank.omega1, eps1=crank.eps1,
        loads=sample_loads(mech, phis) if mech.loads else np.zeros((len(phis), 0, 3)),
        work_point=plan.point(out.working_point),
        law=None if law is None else law.on_grid(crank, phis),
        law_best=True if law is None else law.best, device=device)

