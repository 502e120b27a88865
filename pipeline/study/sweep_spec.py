"""The [sweep] section of a sweep study, and how candidates are drawn from it.

Candidates are drawn per chunk, in NumPy, outside the kernels: chunk c of a
study with seed s uses ``SeedSequence(s).spawn(n_chunks)[c]`` (uniform, Latin
hypercube) or the points c*chunk .. (c+1)*chunk-1 of one scrambled Sobol
sequence seeded by s.  A chunk is therefore the same whatever the thread
count, the engine or the order in which chunks run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..base import limits as lim
from ..base.limits import (CANDIDATES_WHY, CHUNK_WHY, MAX_CANDIDATES, MAX_CHUNK, MAX_NAME_LENGTH,
                           MAX_POSITIONS, POSITIONS_WHY)

if TYPE_CHECKING:      # the type apply_design returns; model imports nothing from here
    from ..model.mechanism import Mechanism

SAMPLERS = ("uniform", "lhs", "sobol")
DEVICES = ("cpu", "gpu", "auto")     # [sweep] device, --device
STORES = ("all", "feasible")         # [sweep] store, --store

# drawing a chunk's candidates has a module of its own (pipeline.study.sampling); its
# names stay importable from here for one release
from .sampling import REDRAW_ROUNDS, draw_candidates, draw_checked, draw_unit  # noqa: E402,F401
# the metrics, their units, stages and senses: one catalogue (pipeline.model.metric_catalogue)
from ..model.metric_catalogue import DEFAULT_METRICS, METRICS, NOT_OBJECTIVES  # noqa: E402,F401
NOT_BOUNDED = {"peak_joint": "an index, not a quantity"}


@dataclass(frozen=True)
class Variable:
    name: str
    param: str          # name in the compiled plan's parameter vector
    low: float
    high: float
    units: str
    factor: float = 1.0     # the parameter's (plan) units per variable unit: pi/180 for an
                            # angle in deg (the plan holds radians)


@dataclass(frozen=True)
class MassScaling:
    body: str
    length_param: str   # characteristic length: m ~ L, J ~ L^3, lS ~ L


@dataclass(frozen=True)
class Triangle:
    """A rigid triangular link (the ternary link of a class III group) whose
    sides must satisfy the strict triangle inequality.  Known before solving,
    so a draw that breaks it is redrawn instead of evaluated (it could only be
    BAD_GEOMETRY).  Each side is a design variable's column or a fixed value."""
    label: str
    names: tuple        # parameter names of the three sides
    columns: tuple      # design-variable column of each side, -1 where fixed
    fixed: tuple        # the side's value where it is fixed

    def sides(self, x):
        return [x[:, c] if c >= 0 else np.full(x.shape[0], v)
                for c, v in zip(self.columns, self.fixed)]

    def broken(self, x):
        """Rows of ``x`` (design variables) whose triangle cannot be built."""
        a, b, c = self.sides(x)
        return ~((a < b + c) & (b < a + c) & (c < a + b))


@dataclass(frozen=True)
class SweepSpec:
    variables: tuple
    candidates: int
    seed: int
    sampler: str
    positions: int
    chunk_size: int
    metrics: tuple
    objectives: tuple
    stroke_radius: float
    stroke_bounds: tuple      # mm (min, max); (-inf, inf) where the study states none
    margin_min: float         # -inf where the study states none
    mass_model: tuple
    scheduler: str | None
    triangles: tuple = ()     # Triangle: known before solving; draws that break one are redrawn
    bounds: tuple = ()        # (metric, min, max): [sweep.constraints] metric = { min, max }
    device: str = "cpu"       # cpu | gpu | auto: where the kernels run (the numbers are the same)
    store: str = "all"        # all | feasible: the candidates' rows the file keeps

    @property
    def n_chunks(self):
        return math.ceil(self.candidates / self.chunk_size)

    def _wants(self, stage):
        return any(METRICS[m][2] == stage for m in self.metrics + self.objectives)

    def stated_constraints(self, has_margin):
        """(metric, min, max) of every constraint the study states in
        [sweep.constraints] (a side it leaves open is -/+inf); the margin's only
        where the plan has a class III group (``has_margin``).  Empty: none."""
        out = []
        if any(math.isfinite(b) for b in self.stroke_bounds):
            out.append(("stroke", *self.stroke_bounds))
        if has_margin and math.isfinite(self.margin_min):
            out.append(("singularity_margin", self.margin_min, math.inf))
        return tuple(out) + tuple(self.bounds)

    def wants(self, *names):
        """Whether the sweep stores one of the metrics ``names``."""
        return any(m in names for m in self.metrics + self.objectives)

    def nominal(self):
        """The sweep without its bounds on robust metrics (``build_yield``): the
        constraints a single build, which has no builds of its own, is held to."""
        from dataclasses import replace
        return replace(self, bounds=tuple(b for b in self.bounds
                                          if METRICS[b[0]][2] != "robust"))

    @property
    def wants_forces(self):
        """The kinetostatics (stage 2); the friction metrics are computed from it."""
        return self._wants("forces") or self._wants("friction")

    @property
    def wants_peaks(self):
        """peak_acceleration, peak_eps: second analogs at every position (stage 2)."""
        return self._wants("kinematics")

    @property
    def wants_transmission(self):
        return self._wants("transmission")

    @property
    def wants_law(self):
        return self._wants("law")

    def chunk_bounds(self, c):
        lo = c * self.chunk_size
        return lo, min(lo + self.chunk_size, self.candidates)

    def with_candidates(self, n):
        from dataclasses import replace
        n = int(n)
        if not 1 <= n <= MAX_CANDIDATES:
            raise ValueError(f"--candidates must be between 1 and {MAX_CANDIDATES:,} "
                             f"({CANDIDATES_WHY}), got {n:,}")
        return replace(self, candidates=n)


def parameter_domain(name):
    """(bound, inclusive, words) that a mechanism parameter's values must
    respect, or None (coordinates, angles, offsets: any finite value)."""
    key = name.rsplit(".", 1)[-1]
    if key in ("mass", "J_S") or (name.startswith("S[") and key == "length"):
        return (0.0, True, "a mass, a moment of inertia or a centre-of-mass distance (>= 0)")
    if key in ("length", "guide_length") or (key.startswith("L") and key[1:2] in
                                                   "0123456789_"):
        return (0.0, False, "a length (> 0)")
    return None


def parameter_range(name):
    """(range, scale): the ``limits.Range`` of a mechanism parameter's values
    as a study file gives them, and the factor to the plan's units (pi/180
    for an angle: the plan holds radians); None for a parameter without one
    (an assembly mode, an orientation)."""
    owner, _, key = name.rpartition(".")
    if key in ("x", "y"):
        return lim.OFFSET, 1.0
    if key == "mass":
        return lim.MASS, 1.0
    if key == "J_S":
        return lim.INERTIA, 1.0
    if key == "ratio":
        return lim.RATIO, 1.0
    if owner.startswith("S[") and key == "length":      # a centre of mass's distance
        return lim.OFFSET, 1.0
    if key in ("length", "guide_length") or (key.startswith("L") and key[1:2] in
                                             "0123456789_"):
        return lim.LENGTH, 1.0
    if key.endswith("offset") or key in ("start", "stroke"):
        return lim.OFFSET, 1.0
    if key.endswith("angle") or key in ("phiM0", "a0", "b0", "phi_start"):
        return lim.ANGLE, math.pi / 180.0
    return None


def parse_sweep(root, mech, output) -> SweepSpec:
    """Read [sweep] of a study (``root`` is the study's top Section)."""
    from ..model.mechanism import compile_mechanism
    from ..base.errors import StudyError
    sec = root.table("sweep")
    plan = compile_mechanism(mech)
    spread = sec.number("spread", 0.2, positive=True)
    variables = []
    vs = sec.table("variables")
    for name in list(vs.data):
        vs.key_name(name)
        v = vs.table(name)
        # a parameter is label.key (a group's, a body's or a point's label)
        param = v.name("param", maximum=2 * MAX_NAME_LENGTH)
        if param not in plan.par_names:
            close = [p for p in plan.par_names if not p.startswith("S[")]
            raise v.error("param", f"no mechanism parameter {param!r}; known: {', '.join(close)}")
        label, _, key = param.rpartition(".")
        if key == "ratio" and label in {plan.group_names[int(g)] for g in plan.input_group}:
            raise v.error("param", f"{param} is a gear ratio, a whole number (the cycle is one "
                                   "revolution of the main crank): it cannot be drawn from a "
                                   "range; run one study per ratio")
        units = v.name("units", "deg" if param.endswith(("phiM0", "angle")) else "mm")
        factor = math.pi / 180.0 if units == "deg" else 1.0
        ref = float(plan.par[plan.param(param)]) / factor
        low = v.number("min", ref - spread * abs(ref))
        high = v.number("max", ref + spread * abs(ref))
        if not low < high:
            raise v.error("max", f"the bounds are empty: min {low:g} >= max {high:g}")
        if param.endswith(".rise_angle") and not (0.0 < low * factor and high * factor
                                                  < 2.0 * math.pi):
            raise v.error("min" if not low * factor > 0.0 else "max",
                          f"{param} is the part of the cycle the rise takes: its bounds must "
                          f"lie within (0, 360) deg, got [{low:g}, {high:g}] {units}")
        domain = parameter_domain(param)
        if domain is not None and not (low >= domain[0] if domain[1] else low > domain[0]):
            if "min" in v.data:
                raise v.error("min", f"{param} is {domain[2]}, but min is {low:g}")
            raise sec.error("spread", f"{param} is {domain[2]}, but its default bounds reach "
                                      f"{low:g} (reference {ref:g} -/+ spread {spread:g}); "
                                      f"give variables.{name}.min and max")
        _check_bounds_range(sec, v, name, param, low, high, units, factor, ref, spread)
        v.done()
        variables.append(Variable(name, param, low, high, units, factor))
    vs.done()
    if not variables:
        raise sec.error("variables", "a sweep needs at least one design variable")
    metrics = tuple(sec.names("metrics", default=list(DEFAULT_METRICS)))
    objectives = tuple(sec.names("objectives", default=["dwell_error", "peak_reaction"]))
    for key, names in (("metrics", metrics), ("objectives", objectives)):
        for m in names:
            if m not in METRICS:
                raise sec.error(key, f"unknown metric {m!r}; known: {', '.join(METRICS)}")
            _check_available(sec, key, m, mech, output)
    for m in objectives:
        if m in NOT_OBJECTIVES:
            alt = NOT_OBJECTIVES[m]
            raise sec.error("objectives", f"{m} is not an objective: objectives are "
                                          f"minimised and a larger {m} is better; minimise "
                                          f"{alt} instead, or bound {m} in [sweep.constraints] "
                                          f"({m} = {{ min = ... }})")
    if len(objectives) < 1:
        raise sec.error("objectives", "at least one objective is needed")
    if output.rocker is None:
        raise StudyError(root.file, "output.rocker",
                         "a sweep needs the output rocker [pivot, point] for stroke and dwell")
    stroke, margin_min, bounds = _parse_constraints(sec.table("constraints", default={}), mech,
                                                    output)
    metrics = tuple(dict.fromkeys(metrics + objectives + tuple(b[0] for b in bounds)))
    mass_model = []
    if sec.has("mass_model"):
        bodies = {b.name for b in mech.bodies}
        mm = sec.table("mass_model")
        for body in list(mm.data):
            if body not in bodies:
                mm.key_name(body)
                raise mm.error(body, f"unknown body {body!r}")
            p = mm.name(body, maximum=2 * MAX_NAME_LENGTH)
            if p not in plan.par_names:
                raise mm.error(body, f"no mechanism parameter {p!r}")
            if not float(plan.par[plan.param(p)]) > 0.0:
                raise mm.error(body, f"the masses scale with {p} / its reference value, which "
                                     f"is {float(plan.par[plan.param(p)]):g}: choose a length "
                                     "whose reference value is positive")
            mass_model.append(MassScaling(body, p))
        mm.done()
    if any(METRICS[m][2] == "forces" for m in metrics) and not mech.bodies:
        raise sec.error("metrics", "force metrics need mass data: declare [[mechanism.bodies]]")
    positions = sec.integer("positions", 360, minimum=12, maximum=MAX_POSITIONS,
                            why=POSITIONS_WHY)
    spec = SweepSpec(
        variables=tuple(variables),
        candidates=sec.integer("candidates", 10000, minimum=1, maximum=MAX_CANDIDATES,
                               why=CANDIDATES_WHY),
        seed=sec.integer("seed", 0, minimum=0),
        sampler=sec.string("sampler", "sobol", choices=SAMPLERS),
        positions=positions,
        chunk_size=sec.integer("chunk_size", 10000, minimum=1, maximum=MAX_CHUNK,
                               why=CHUNK_WHY),
        metrics=metrics, objectives=objectives,
        stroke_radius=sec.number("stroke_radius", positive=True, within=lim.LENGTH),
        stroke_bounds=stroke, margin_min=margin_min,
        mass_model=tuple(mass_model),
        scheduler=sec.string("scheduler", "") or None,
        triangles=triangles_of(plan, variables),
        bounds=bounds,
        device=sec.string("device", "cpu", choices=DEVICES),
        store=sec.string("store", "all", choices=STORES),
    )
    if spec.triangles:
        # rejection sampling needs designs that can be built: at least 1 % of the box,
        # every triangle at once
        probe = np.random.default_rng(0).random((40000, len(variables)))
        lo = np.array([v.low for v in variables])
        hi = np.array([v.high for v in variables])
        x = lo + probe * (hi - lo)
        bad = np.zeros(len(x), bool)
        for t in spec.triangles:
            bad |= t.broken(x)
        ok = 1.0 - bad.mean()
        if ok < 0.01:
            names = ", ".join(n for t in spec.triangles for n in t.names)
            raise sec.error("variables", f"only {100 * ok:.2g} % of the bounds give buildable "
                                         f"{'; '.join(t.label for t in spec.triangles)}; "
                                         f"narrow the bounds of {names}")
    w = round(output.dwell_deg * positions / 360)
    if not 1 <= w < positions:
        raise StudyError(root.file, "output.dwell",
                         f"a {output.dwell_deg:g} deg window spans {w} of {positions} intervals")
    sec.done()
    return spec


def _check_bounds_range(sec, v, name, param, low, high, units, factor, ref, spread):
    """Refuse a design variable's bounds that leave the plausible range of its
    parameter (``parameter_range``): the bounds' own field, or ``spread``
    where the bounds are its defaults."""
    found = parameter_range(param)
    if found is None:
        return
    rng, scale = found
    for key, x in (("min", low), ("max", high)):
        if rng.holds(x * factor / scale):
            continue
        shown = f"{x:g} {units}" if units == rng.unit or not rng.unit else \
            f"{x:g} {units} ({x * factor / scale:g} {rng.unit})"
        if key in v.data:
            raise v.error(key, f"{param}: {shown} is out of range: {rng.words()}")
        raise sec.error("spread", f"{param}: its default {key} {shown} (reference {ref:g} "
                                  f"-/+ spread {spread:g}) is out of range: {rng.words()}; "
                                  f"give variables.{name}.min and max")


# with [mechanism.friction], the metrics that would still be frictionless
FRICTIONLESS_ONLY = {
    "equilibrium_residual": "the frictionless kinetostatics' residual (a scene reports the "
                            "residual with friction)",
}


def _check_available(sec, key, m, mech, output):
    """Refuse a metric the study cannot compute, naming the field."""
    friction = getattr(mech, "friction", None)
    if METRICS[m][2] == "friction" and friction is None:
        raise sec.error(key, f"{m} needs friction in the joints: declare [mechanism.friction]")
    if METRICS[m][2] == "friction" and not mech.bodies:
        raise sec.error(key, f"{m} needs mass data: declare [[mechanism.bodies]]")
    if friction is not None and m in FRICTIONLESS_ONLY:
        raise sec.error(key, f"{m} is {FRICTIONLESS_ONLY[m]}, and this mechanism has "
                             "[mechanism.friction]; leave it out")
    if METRICS[m][2] == "robust":        # a quantile of a metric over the builds: that metric's
        from ..model.metric_catalogue import ROBUST_OF
        base = ROBUST_OF.get(m, "")
        if base:
            _check_available(sec, key, base, mech, output)
            if METRICS[base][2] == "forces" and not mech.bodies:
                raise sec.error(key, f"{m} needs mass data: declare [[mechanism.bodies]]")
    if METRICS[m][2] == "law" and output.motion_law is None:
        raise sec.error(key, f"{m} needs the required motion law: declare [output.motion_law]")
    if METRICS[m][2] == "transmission":
        from ..model.mechanism import transmission_items
        if not transmission_items(mech):
            raise sec.error(key, f"{m} needs a dyad or a class III group (the "
                                 "transmission angles of pipeline.peaks); this mechanism has "
                                 "none")


def _parse_constraints(cons, mech, output):
    """[sweep.constraints]: (stroke [min, max], singularity margin minimum,
    bounds ((metric, min, max), ...)).  Besides ``stroke = [min, max]`` and
    ``singularity_margin_min``, any metric takes ``{ min = ..., max = ... }``
    (either or both), e.g. ``min_transmission_angle = { min = 30 }``."""
    bounds = []
    stroke = None
    margin_min = None
    for key in list(cons.data):
        v = cons.data[key]
        if key in ("stroke", "singularity_margin_min") and not isinstance(v, dict):
            continue
        if key not in METRICS:
            cons.key_name(key)
            raise cons.error(key, f"unknown constraint {key!r}: give stroke = [min, max], "
                                  "singularity_margin_min = ..., or a metric = { min = ..., "
                                  f"max = ... }}; metrics: {', '.join(METRICS)}")
        if key in NOT_BOUNDED:
            raise cons.error(key, f"{key} is {NOT_BOUNDED[key]}: it cannot be bounded")
        if not isinstance(v, dict):
            raise cons.error(key, f"expected {{ min = ..., max = ... }} (either or both), got "
                                  f"{type(v).__name__} {v!r:.40}")
        _check_available(cons, key, key, mech, output)
        b = cons.table(key)
        lo = b.number("min") if b.has("min") else -math.inf
        hi = b.number("max") if b.has("max") else math.inf
        b.used.update(("min", "max"))
        b.done()
        if not ("min" in b.data or "max" in b.data):
            raise b.error("", "give min, max or both")
        if not lo < hi:
            raise b.error("max", f"the bounds are empty: min {lo:g} >= max {hi:g}")
        if key == "stroke":
            stroke = (lo, hi)
        elif key == "singularity_margin":
            if "max" in b.data:
                raise b.error("max", "the singularity margin takes a minimum only")
            margin_min = lo
        else:
            bounds.append((key, lo, hi))
    # a constraint the study does not state is none (no window assumed: the OV-7
    # studies state theirs, stroke = [11, 15] and singularity_margin_min = 0.3)
    if stroke is None and cons.has("stroke"):
        stroke = cons.numbers("stroke", n=2)
        if not stroke[0] < stroke[1]:
            raise cons.error("stroke", "expected [min, max] with min < max")
    elif stroke is None:
        stroke = (-math.inf, math.inf)
    if margin_min is None:
        margin_min = cons.number("singularity_margin_min") if \
            cons.has("singularity_margin_min") else -math.inf
    elif cons.has("singularity_margin_min"):
        raise cons.error("singularity_margin_min", "given twice: singularity_margin = "
                                                   "{ min = ... } says the same")
    cons.done()
    return tuple(stroke), margin_min, tuple(bounds)


def geometry_problems(plan, par) -> list:
    """What makes the parameter row ``par`` impossible to build before any
    solving (the BAD_GEOMETRY status), in words with the lengths: a length
    that is not positive, a ternary triangle inequality that fails."""
    out = []
    for j, name in enumerate(plan.par_names):
        dom = parameter_domain(name)
        v = float(par[j])
        if dom is not None and not (v >= dom[0] if dom[1] else v > dom[0]):
            unit = " mm" if "length" in dom[2] and not dom[1] else ""
            out.append(f"{name} = {v:.6g}{unit} is not {dom[2]}")
    for name in plan.par_names:
        if not name.endswith(".L34"):
            continue
        g = name[:-4]
        try:
            a, b, c = (float(par[plan.param(f"{g}.{k}")]) for k in ("L34", "L45", "L35"))
        except (KeyError, ValueError):
            continue
        for (la, x), (lb, y), (lc, z) in ((("L45", b), ("L34", a), ("L35", c)),
                                          (("L34", a), ("L45", b), ("L35", c)),
                                          (("L35", c), ("L34", a), ("L45", b))):
            if not x < y + z:
                out.append(f"ternary link of {g!r}: {la} = {x:.6g} mm >= {lb} + {lc} = "
                           f"{y:.6g} + {z:.6g} = {y + z:.6g} mm (no triangle)")
    return out


def triangles_of(plan, variables):
    """The ternary links of the plan's class III groups whose sides are design
    variables (Triangle each)."""
    out = []
    cols = {v.param: j for j, v in enumerate(variables)}
    for name in plan.par_names:
        if not name.endswith(".L34"):
            continue
        g = name[:-4]
        names = (f"{g}.L34", f"{g}.L45", f"{g}.L35")
        if not all(n in plan.par_names for n in names) or not any(n in cols for n in names):
            continue
        out.append(Triangle(
            label=f"ternary link of {g!r}: L34 < L45 + L35, L45 < L34 + L35, L35 < L34 + L45",
            names=names, columns=tuple(cols.get(n, -1) for n in names),
            fixed=tuple(float(plan.par[plan.param(n)]) for n in names)))
    return tuple(out)


def parameter_columns(plan, spec: SweepSpec):
    """Where a candidate's row takes its values: each design variable's column
    and factor, and each mass-model body's columns (its characteristic length,
    mass, J_S, centre-of-mass arm)."""
    var_cols = np.array([plan.param(v.param) for v in spec.variables], np.int64)
    factors = np.array([float(v.factor) for v in spec.variables], np.float64)
    mass_cols = np.array([[plan.param(ms.length_param), plan.param(f"{ms.body}.mass"),
                           plan.param(f"{ms.body}.J_S"), plan.param(f"S[{ms.body}].length")]
                          for ms in spec.mass_model], np.int64).reshape(-1, 4)
    return var_cols, factors, mass_cols


def parameter_rows(plan, spec: SweepSpec, x: np.ndarray) -> np.ndarray:
    """Full kernel parameter rows for design-variable rows ``x``: the reference
    row with the variables set, then the mass model (DOMAIN.md section 9:
    m = m0 L/L0, J_S = J0 (L/L0)^3, lS = lS0 L/L0; ``kernels.candidates``)."""
    from ..kernels.candidates import parameter_rows_into
    x = np.ascontiguousarray(x, dtype=np.float64)
    var_cols, factors, mass_cols = parameter_columns(plan, spec)
    pars = np.empty((x.shape[0], plan.par.shape[0]))
    parameter_rows_into(np.ascontiguousarray(plan.par, dtype=np.float64), x, var_cols, factors,
                        mass_cols, pars)
    return pars


def apply_design(mech, spec: SweepSpec, x) -> "Mechanism":
    """The declared mechanism of one candidate (design-variable row ``x``), with
    the mass model applied: the scene path's twin of ``parameter_rows``."""
    from ..kernels.candidates import scaled_mass_data   # (numba: imported when used)
    from dataclasses import replace
    base_plan = mech.compile()
    values = {v.param: float(xi) * v.factor for v, xi in zip(spec.variables, x)}
    fixed = dict(mech.fixed)
    crank = mech.crank
    groups = list(mech.groups)
    labels = [g for g in base_plan.group_names]
    for param, val in values.items():
        owner, key = param.rsplit(".", 1)
        if owner in fixed and key in ("x", "y"):
            xy = list(fixed[owner])
            xy["xy".index(key)] = val
            fixed[owner] = tuple(xy)
        elif owner == crank.name:
            crank = replace(crank, **{key: val})
        else:
            k = labels.index(owner) - 1          # group_names[0] is the crank
            law = getattr(groups[k], "law", None)
            if law is not None and key in law.FIELDS:     # an input's law
                groups[k] = replace(groups[k], law=replace(law, **{law.FIELDS[key]: val}))
            else:
                groups[k] = replace(groups[k], **{key: val})
    out = replace(mech, fixed=fixed, crank=crank, groups=tuple(groups))
    scale = {}
    new_plan = out.compile()
    for ms in spec.mass_model:
        k = base_plan.param(ms.length_param)
        scale[ms.body] = float(new_plan.par[k] / base_plan.par[k])
    bodies = []
    for b in mech.bodies:
        if b.name in scale:
            m, J, lS = scaled_mass_data(b.mass, b.J_S, b.com.lS, scale[b.name])
            b = replace(b, mass=m, J_S=J, com=replace(b.com, lS=lS))
        bodies.append(b)
    return replace(out, bodies=tuple(bodies))
