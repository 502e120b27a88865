"""The [tolerance] section of a study: how far each dimension of a built
machine may lie from the drawing, and how the builds are drawn.

    [tolerance]
    class = "f"               # ISO 2768-1 class of the default tolerances: f | m | c
    distribution = "normal"   # normal: the tolerance is 3 sigma | uniform: within +-tolerance
    samples = 4096            # builds drawn (scrambled Sobol; a power of 2 balances best)
    seed = 1
    [tolerance.dimensions]    # +- tolerances that differ from the class's (mm, deg)
    "crank.length" = 0.02     # a mechanism parameter, or a sweep variable's name
    "P6.x" = { tolerance = 0.05, distribution = "uniform" }
    [tolerance.constraints]   # a scene's: what a build must meet (a sweep's are [sweep.constraints])
    stroke = { min = 12.0, max = 14.0 }
    [tolerance.robust]        # what a search minimises for robustness (robust_* metrics)
    quantile = 0.95
    builds = 64               # builds per design

The toleranced dimensions are the drawing's: every link length (also an
attached point's distance and a cam rocker's arm), every coordinate of a fixed
pivot, every angle (an attached point's, a guide's, the crank's mounting
phase phiM0: exact by default) and every guide offset.  Not toleranced: masses and inertias,
assembly modes, the continuation's start angles, gear ratios and an input's
motion law (a cam's profile has tolerances of its own).

Default tolerances, ISO 2768-1 (general tolerances for linear and angular
dimensions without individual tolerance indications), by the nominal size:

* a length or an offset: the linear table at the dimension's size (an offset
  below 0.5 mm takes the first row);
* a fixed pivot's x and y: the linear table at the pivot's distance from the
  origin (the frame's datum; a pivot at the origin, closer than 0.5 mm, is the
  datum itself and exact);
* an angle: the angular table at the length of its shorter leg: an attached
  point's distance for its angle, the crank's length for phiM0, 50 mm (the
  50-120 mm row) for a guide.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..base import limits as lim

DISTRIBUTIONS = ("normal", "uniform")

# ISO 2768-1: (upper limit of the nominal size in mm, +- tolerance in mm) per class
LINEAR = {
    "f": ((3, 0.05), (6, 0.05), (30, 0.1), (120, 0.15), (400, 0.2), (1000, 0.3), (2000, 0.5),
          (math.inf, 0.5)),
    "m": ((3, 0.1), (6, 0.1), (30, 0.2), (120, 0.3), (400, 0.5), (1000, 0.8), (2000, 1.2),
          (math.inf, 2.0)),
    "c": ((3, 0.2), (6, 0.3), (30, 0.5), (120, 0.8), (400, 1.2), (1000, 2.0), (2000, 3.0),
          (math.inf, 4.0)),
}
# ISO 2768-1 angular tolerances, the same for f and m: (shorter leg up to mm, +- deg)
ANGULAR = {
    "f": ((10, 1.0), (50, 0.5), (120, 20 / 60), (400, 10 / 60), (math.inf, 5 / 60)),
    "c": ((10, 1.5), (50, 1.0), (120, 0.5), (400, 0.25), (math.inf, 10 / 60)),
}
ANGULAR["m"] = ANGULAR["f"]
CLASSES = tuple(LINEAR)
DATUM = 0.5             # mm: a pivot closer to the origin is the frame's datum (exact)
GUIDE_LEG = 50.0        # mm: the shorter leg of a guide's angle (the 50-120 mm row)

KINDS = ("length", "coordinate", "angle")
SAMPLES = 4096
MAX_SAMPLES = 1 << 20


@dataclass(frozen=True)
class Dimension:
    param: str          # the compiled plan's parameter name (P6.x, triad.L23, crank.phiM0)
    kind: str           # length | coordinate | angle
    nominal: float      # in the study's units (mm, deg)
    tolerance: float    # +- in the study's units; 0: exact (not drawn)
    distribution: str   # normal (tolerance = 3 sigma) | uniform
    factor: float       # plan units per study unit (pi/180 for an angle)
    source: str         # "ISO 2768-f, 30-120 mm" or "study"

    @property
    def units(self):
        return "deg" if self.kind == "angle" else "mm"

    @property
    def sigma(self):
        """The standard deviation of the dimension's deviation (study units)."""
        if self.distribution == "normal":
            return self.tolerance / 3.0
        return self.tolerance / math.sqrt(3.0)


@dataclass(frozen=True)
class RobustSpec:
    quantile: float = 0.95
    builds: int = 64


@dataclass(frozen=True)
class ToleranceSpec:
    """How a design's builds are drawn: the ISO class of the default
    tolerances and the study's own (``overrides``: (parameter, tolerance,
    distribution)); the dimensions of a given design are ``dimensions(mech)``
    (a sweep candidate's sizes choose its size classes)."""
    iso_class: str = "f"
    distribution: str = "normal"
    overrides: tuple = ()
    samples: int = SAMPLES
    seed: int = 1
    bounds: tuple = ()          # (metric, min, max): what a build must meet (a scene's)
    robust: RobustSpec = RobustSpec()
    metrics: tuple = ()         # the metrics of every build (empty: every one the mechanism has)

    def dimensions(self, mech):
        """Every toleranced dimension of design ``mech`` (Dimension)."""
        dims = {d.param: d for d in drawing_dimensions(mech, mech.compile(), self.iso_class,
                                                       self.distribution)}
        for param, tol, dist in self.overrides:
            d = dims[param]
            dims[param] = Dimension(d.param, d.kind, d.nominal, tol, dist, d.factor, "study")
        return tuple(dims.values())


def drawn(dimensions):
    """The dimensions with a tolerance (the exact ones are not drawn)."""
    return tuple(d for d in dimensions if d.tolerance > 0.0)


def _iso(table, size):
    for upper, tol in table:
        if size <= upper:
            return tol
    return table[-1][1]


def _size_words(table, size):
    lower = 0.0
    for upper, _ in table:
        if size <= upper:
            return f"{lower:g}-{upper:g} mm" if math.isfinite(upper) else f"over {lower:g} mm"
        lower = upper
    return ""


def drawing_dimensions(mech, plan, iso_class="f", distribution="normal"):
    """Every toleranced dimension of the mechanism, with its ISO 2768-1
    default tolerance (see the module's text)."""
    law_params = set()
    for label, g in zip(plan.group_names[1:], mech.groups):
        law = getattr(g, "law", None)
        if law is not None:
            law_params.update(f"{label}.{k}" for k in law.FIELDS)
    out = []
    names = plan.par_names
    for j, name in enumerate(names):
        if name.startswith("S[") or name in law_params:
            continue
        owner, _, key = name.rpartition(".")
        value = float(plan.par[j])
        if key in ("x", "y") and owner in mech.fixed:
            x, y = mech.fixed[owner]
            size = math.hypot(x, y)
            tol = 0.0 if size < DATUM else _iso(LINEAR[iso_class], size)
            src = ("the datum (the origin)" if size < DATUM else
                   f"ISO 2768-{iso_class}, pivot {_size_words(LINEAR[iso_class], size)} "
                   "from the origin")
            out.append(Dimension(name, "coordinate", value, tol, distribution, 1.0, src))
        elif key == "length" or (key.startswith("L") and key[1:2] in "0123456789_"):
            if key == "guide_length":
                continue
            size = abs(value)
            out.append(Dimension(name, "length", value, _iso(LINEAR[iso_class], size),
                                 distribution, 1.0,
                                 f"ISO 2768-{iso_class}, {_size_words(LINEAR[iso_class], size)}"))
        elif key.endswith("offset"):
            size = abs(value)
            out.append(Dimension(name, "length", value, _iso(LINEAR[iso_class], size),
                                 distribution, 1.0,
                                 f"ISO 2768-{iso_class}, {_size_words(LINEAR[iso_class], size)}"))
        elif key == "phiM0":
            out.append(Dimension(name, "angle", value * 180.0 / math.pi, 0.0, distribution,
                                 math.pi / 180.0, "set at assembly (the crank's timing on its "
                                 "shaft): exact unless the study gives one"))
        elif key.endswith("angle"):
            leg = _angle_leg(plan, owner, key)
            deg = value * 180.0 / math.pi
            out.append(Dimension(name, "angle", deg, _iso(ANGULAR[iso_class], leg),
                                 distribution, math.pi / 180.0,
                                 f"ISO 2768-{iso_class}, shorter leg "
                                 f"{_size_words(ANGULAR[iso_class], leg)}"))
    return tuple(out)


def _angle_leg(plan, owner, key):
    """The shorter leg (mm) an angle is measured over (see the module's text)."""
    for leg in (f"{owner}.length",):
        if leg in plan.par_names:
            return abs(float(plan.par[plan.param(leg)]))
    return GUIDE_LEG


def parse_tolerance(root, mech, output, sweep=None) -> ToleranceSpec:
    """Read [tolerance] of a study (``root``: the study's top Section); a study
    without one gets ``ToleranceSpec()``: the ISO 2768-f defaults."""
    from .sweep_spec import _check_available
    from ..model.metric_catalogue import METRICS
    sec = root.table("tolerance")
    plan = mech.compile()
    iso_class = sec.string("class", "f", choices=CLASSES)
    distribution = sec.string("distribution", "normal", choices=DISTRIBUTIONS)
    dims = {d.param: d for d in drawing_dimensions(mech, plan, iso_class, distribution)}
    aliases = {v.name: v.param for v in sweep.variables} if sweep is not None else {}
    overrides = []
    if sec.has("dimensions"):
        ds = sec.table("dimensions")
        for key in list(ds.data):
            ds.key_name(key, maximum=2 * lim.MAX_NAME_LENGTH)
            param = aliases.get(key, key)
            if param not in dims:
                raise ds.error(key, f"no toleranced dimension {key!r}; known: "
                                    f"{', '.join(dims)}")
            d = dims[param]
            if isinstance(ds.data[key], dict):
                t = ds.table(key)
                tol = t.number("tolerance")
                dist = t.string("distribution", distribution, choices=DISTRIBUTIONS)
                t.done()
                where = t
            else:
                tol, dist, where = ds.number(key), distribution, ds
            if not tol >= 0.0:
                raise where.error(key if where is ds else "tolerance",
                                  f"a tolerance is +- a distance or an angle (>= 0), got {tol:g}")
            limit = 10.0 if d.kind == "angle" else max(1.0, 0.1 * abs(d.nominal))
            if tol > limit:
                raise where.error(key if where is ds else "tolerance",
                                  f"+-{tol:g} {d.units} on {param} = {d.nominal:g} {d.units} "
                                  f"is not a manufacturing tolerance (at most {limit:g} "
                                  f"{d.units} here)")
            dims[param] = Dimension(d.param, d.kind, d.nominal, tol, dist, d.factor, "study")
            overrides.append((param, tol, dist))
        ds.done()
    metrics = ()
    if sec.has("metrics"):
        from ..model.metric_catalogue import TOLERANCED_METRICS
        metrics = sec.names("metrics")
        for m in metrics:
            if m not in TOLERANCED_METRICS:
                raise sec.error("metrics", f"{m!r} is not a metric of a build; known: "
                                           f"{', '.join(TOLERANCED_METRICS)}")
            _check_available(sec, "metrics", m, mech, output)
    samples = sec.integer("samples", SAMPLES, minimum=2, maximum=MAX_SAMPLES,
                          why="a million builds resolve a 1e-3 yield")
    seed = sec.integer("seed", 1, minimum=0)
    bounds = ()
    if sec.has("constraints"):
        if sweep is not None:
            raise sec.error("constraints", "a sweep's builds meet its [sweep.constraints]; "
                                           "give them there")
        bounds = _parse_bounds(sec.table("constraints"), mech, output, METRICS, _check_available)
    robust = RobustSpec()
    if sec.has("robust"):
        r = sec.table("robust")
        q = r.number("quantile", 0.95)
        if not 0.0 < q < 1.0:
            raise r.error("quantile", f"a quantile lies between 0 and 1, got {q:g}")
        robust = RobustSpec(q, r.integer("builds", 64, minimum=8, maximum=4096,
                                         why="a robust objective per design"))
        r.done()
    sec.done()
    if not drawn(tuple(dims.values())):
        raise sec.error("dimensions", "every dimension is exact: nothing to draw")
    return ToleranceSpec(iso_class, distribution, tuple(overrides), samples, seed, bounds, robust,
                         tuple(metrics))


def _parse_bounds(cons, mech, output, metrics, check_available):
    """[tolerance.constraints]: metric = { min = ..., max = ... } (either or both)."""
    out = []
    for key in list(cons.data):
        if key not in metrics:
            cons.key_name(key)
            raise cons.error(key, f"unknown metric {key!r}; known: {', '.join(metrics)}")
        check_available(cons, key, key, mech, output)
        b = cons.table(key)
        lo = b.number("min", -math.inf) if b.has("min") else -math.inf
        hi = b.number("max", math.inf) if b.has("max") else math.inf
        b.done()
        if not (b.has("min") or b.has("max")):
            raise b.error("", "give min, max or both")
        if not lo < hi:
            raise b.error("max", f"the bounds are empty: min {lo:g} >= max {hi:g}")
        out.append((key, lo, hi))
    cons.done()
    return tuple(out)
