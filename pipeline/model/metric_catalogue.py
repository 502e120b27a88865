"""The catalogue of a sweep's metrics: one entry per metric, the one place that
says what it is.

Each entry names the metric, its units (UDUNITS) and description (the results
file's ``units`` and ``long_name``), the stage of the kernels that computes it,
the column of the kernels' metric row it is read from (``pipeline.kernels.sweep``
``M_*``) with the conversion to its units, and its sense: every objective is
minimised, so a metric for which larger is better is no objective and names
the one to minimise instead; a rounding-level quantity (a residual) says so,
and the tests comparing two paths of the kernels compare it absolutely.  The
study format (``sweep_spec``), the stored columns (``objectives``,
``sweep_file``), the summary, the docs and those tests read it.

Adding a metric is one entry here plus the kernel code that fills its column
(a new ``M_*`` column of ``pipeline.kernels.sweep`` and its lines in the
generated skeleton); the journal records the width of the metric row, so a
journal written with other columns is refused instead of being mixed in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..kernels import sweep as ks

# the stages of the kernels (pipeline.kernels.sweep): "positions" (stage 1), "law"
# (stage 1, with [output.motion_law]), "kinematics", "transmission", "forces" (stage
# 2, candidates that meet the stroke and margin constraints); "robust": a design's
# builds within the study's [tolerance] (pipeline.runs.builds.RobustBuilds), for
# the designs that meet their constraints, in columns after the kernels' own;
# "friction": with [mechanism.friction], the candidates of the force stage on the
# careful path (pipeline.runs.sweep_friction), in columns after the robust ones
STAGES = ("positions", "law", "kinematics", "transmission", "forces", "robust", "friction")

# the robust metrics' columns, after the kernels' N_METRICS: (name, the metric of the
# builds it is a quantile of; "" for the yield)
ROBUST = (("robust_dwell_error", "dwell_error"), ("robust_peak_reaction", "peak_reaction"),
          ("robust_law_error", "law_error"), ("build_yield", ""))
ROBUST_COLUMN = {name: ks.N_METRICS + k for k, (name, _) in enumerate(ROBUST)}
ROBUST_OF = dict(ROBUST)
N_ROBUST_ROW = ks.N_METRICS + len(ROBUST)      # a metric row with the robust columns
# the friction metrics' columns, after the robust ones (pipeline.runs.sweep_friction)
FRICTION = ("friction_loss", "peak_pv")
FRICTION_COLUMN = {name: N_ROBUST_ROW + k for k, name in enumerate(FRICTION)}
N_ROW = N_ROBUST_ROW + len(FRICTION)    # a metric row with the robust and friction columns
# with [mechanism.friction] these force peaks are those with friction (the friction
# stage replaces the kernels' frictionless ones)
WITH_FRICTION = ("peak_reaction", "peak_joint", "peak_phi", "peak_M_bal")
_QUANTILE = ("the [tolerance.robust] quantile (default the 95th percentile) of {m} over the "
             "design's builds within the study's [tolerance] (default ISO 2768-f, the "
             "reference design's size classes; a build that cannot assemble counts as "
             "infinitely bad); only designs that meet their constraints carry it, NaN elsewhere")
RAD_TO_DEG = 180.0 / math.pi


@dataclass(frozen=True)
class Metric:
    name: str
    units: str
    long_name: str
    stage: str
    column: int                 # of the kernels' metric row (pipeline.kernels.sweep.M_*)
    factor: float = 1.0         # stored value = row[column] * factor (+ offset)
    offset: float = 0.0
    larger_is_better: str = ""  # the metric to minimise instead (then no objective)
    rounding: bool = False      # a rounding-level quantity (a residual, units 1): two paths
                                # of the kernels agree on it absolutely, not relatively

    def values(self, metrics):
        """The stored values of this metric from metric rows (n, N_METRICS)."""
        v = metrics[:, self.column] * self.factor
        return v + self.offset if self.offset else v


CATALOGUE = (
    Metric("dwell_error", "1", "dwell error: best window range / revolution range",
           "positions", ks.M_DWELL),
    Metric("stroke", "mm", "stroke of the working point: radius x rocker swing",
           "positions", ks.M_STROKE),
    Metric("singularity_margin", "1",
           "min |det J| / (4 L23 L46 L57 max(L34, L35)) over the revolution (a class III "
           "group with a slider: / (L23 L46 max(L34, L35)))",
           "positions", ks.M_MARGIN),
    Metric("dwell_start", "deg", "crank angle phi1 where the best dwell window starts",
           "positions", ks.M_DWELL_START, RAD_TO_DEG),
    Metric("newton_iterations", "1", "mean Newton iterations per position",
           "positions", ks.M_NEWTON_MEAN),
    Metric("peak_reaction", "N", "largest joint reaction over all joints and positions",
           "forces", ks.M_PEAK_R),
    Metric("peak_joint", "1", "index of the joint with the peak reaction",
           "forces", ks.M_PEAK_JOINT),
    Metric("peak_phi", "deg", "crank angle phi1 of the peak reaction",
           "forces", ks.M_PEAK_PHI, RAD_TO_DEG),
    Metric("peak_M_bal", "N*m", "largest |balancing moment| over the revolution",
           "forces", ks.M_PEAK_MBAL),
    Metric("peak_acceleration", "m/s^2",
           "largest |acceleration| of the working point at the operating speed, the largest "
           "of the grid's positions (not refined between them: within O(step^2) of the "
           "scene's refined peak)",
           "kinematics", ks.M_PEAK_ACC),
    Metric("peak_eps", "1/s^2",
           "largest |angular acceleration| of the output rocker at the operating speed, the "
           "largest of the grid's positions (not refined between them)",
           "kinematics", ks.M_PEAK_EPS),
    Metric("min_transmission_angle", "deg",
           "smallest transmission angle (two-link dyads at the middle joint, class III leads, the "
           "slider dyads' force against the driven member's motion) over the revolution, the "
           "smallest of the grid's positions (not refined between them)",
           "transmission", ks.M_MIN_TRANS, RAD_TO_DEG,
           larger_is_better="transmission_deviation"),
    Metric("transmission_deviation", "deg",
           "90 deg - min_transmission_angle: the largest deviation of a transmission angle "
           "from 90 deg (an objective to minimise)",
           "transmission", ks.M_MIN_TRANS, -RAD_TO_DEG, 90.0),
    Metric("law_error", "1",
           "RMS deviation of the normalised rocker angle (0 at the dwell, 1 at the full "
           "swing) from the motion law over the revolution",
           "law", ks.M_LAW_RMS),
    Metric("law_error_max", "1",
           "largest deviation of the normalised rocker angle from the motion law over the "
           "revolution",
           "law", ks.M_LAW_MAX),
    Metric("law_shift", "deg",
           "cycle-angle shift of the motion law that fits best (align = best; 0 for align = "
           "fixed): the mounting phase phiM0 - rot x law_shift puts the design on the law as "
           "given",
           "law", ks.M_LAW_SHIFT, RAD_TO_DEG),
    Metric("equilibrium_residual", "1",
           "worst relative virtual-power residual of the kinetostatics over the revolution: at "
           "each position |M_bal omega1 + sum over moving links (F . v_S + M omega)| / the "
           "largest |term| (M_bal omega1, each link's F . v_S and M omega; F, M: its gravity, "
           "inertia force and moment and external loads at its centre of mass), every term "
           "divided by omega1 (the same ratio, defined at omega1 = 0 too); a position where "
           "every term is exactly 0 (nothing moves, e.g. a cam follower's dwell: the sum is 0 "
           "too) counts 0; elsewhere the ratio is at most the number of terms",
           "forces", ks.M_EQUILIBRIUM, rounding=True),
    Metric("peak_shaking_force", "N",
           "largest |shaking force| on the frame over the revolution: the moving links' inertia "
           "forces sum(-m a_S) = -d/dt sum(m v_S) (gravity and external loads apart) at the "
           "operating speed, the largest of the grid's positions (not refined between them)",
           "forces", ks.M_SHAKING_F),
    Metric("peak_shaking_moment", "N*m",
           "largest |shaking moment| on the frame about the crank's pivot over the revolution: "
           "sum(-J_S eps + (S - O) x (-m a_S)) = -d/dt of the angular momentum about O (gravity "
           "and external loads apart), the largest of the grid's positions (not refined between "
           "them)",
           "forces", ks.M_SHAKING_M),
    Metric("robust_dwell_error", "1", _QUANTILE.format(m="dwell_error"), "robust",
           ROBUST_COLUMN["robust_dwell_error"]),
    Metric("robust_peak_reaction", "N", _QUANTILE.format(m="peak_reaction"), "robust",
           ROBUST_COLUMN["robust_peak_reaction"]),
    Metric("robust_law_error", "1", _QUANTILE.format(m="law_error"), "robust",
           ROBUST_COLUMN["robust_law_error"]),
    Metric("build_yield", "1",
           "share of the design's builds within the study's [tolerance] that assemble and "
           "meet the constraints (the designs that meet them nominally; NaN elsewhere)",
           "robust", ROBUST_COLUMN["build_yield"], larger_is_better="build_loss"),
    Metric("build_loss", "1", "1 - build_yield: the share of builds lost (an objective to "
           "minimise)", "robust", ROBUST_COLUMN["build_yield"], -1.0, 1.0),
    Metric("friction_loss", "W",
           "mean power lost to Coulomb friction in the joints and slides over the revolution "
           "at the operating speed ([mechanism.friction]; the mean over the grid's positions, "
           "as a scene's friction_loss); with friction peak_reaction, peak_joint, peak_phi "
           "and peak_M_bal are those with friction too",
           "friction", FRICTION_COLUMN["friction_loss"]),
    Metric("peak_pv", "MPa*m/s",
           "largest p*v of the plain bearings (p = |R| / (d l), v = |relative omega| d / 2 at "
           "the pin's surface) over the revolute joints and the grid's positions, with "
           "friction ([mechanism.friction]; not refined between the positions)",
           "friction", FRICTION_COLUMN["peak_pv"]),
)

BY_NAME = {m.name: m for m in CATALOGUE}

# the forms the rest of the package reads
METRICS = {m.name: (m.units, m.long_name, m.stage) for m in CATALOGUE}
# the metrics a build's quality is read from in a tolerance analysis (indices, angles of
# peaks and residuals are not quantities to tolerance)
TOLERANCED_METRICS = ("stroke", "dwell_error", "law_error", "singularity_margin",
                      "min_transmission_angle", "peak_acceleration", "peak_reaction",
                      "peak_M_bal", "friction_loss", "peak_pv")
# stored when a study names no metrics (in this order: the results file's)
DEFAULT_METRICS = ("dwell_error", "peak_reaction", "stroke", "singularity_margin",
                   "dwell_start", "peak_joint", "peak_phi", "peak_M_bal", "newton_iterations")
NOT_OBJECTIVES = {m.name: m.larger_is_better for m in CATALOGUE if m.larger_is_better}


def metric_values(metrics, name):
    """The stored values (in the metric's units) of metric ``name`` from the
    kernels' metric rows ``metrics`` (n, N_METRICS)."""
    return BY_NAME[name].values(metrics)


def markdown_table() -> str:
    """The catalogue as the Markdown table of the guide's page docs/guide/metrics.md (a
    test keeps the two equal: ``python -m pipeline.model.metric_catalogue >
    docs/guide/metrics.md`` after a change)."""
    rows = ["# Sweep metrics", "",
            "Generated from `pipeline/model/metric_catalogue.py` (`python -m "
            "pipeline.model.metric_catalogue > docs/guide/metrics.md`); every objective is "
            "minimised.", "",
            "| metric | units | stage | objective | what |", "|---|---|---|---|---|"]
    for m in CATALOGUE:
        sense = f"no: minimise `{m.larger_is_better}`" if m.larger_is_better else "yes"
        what = m.long_name.replace("|", "\\|")      # |x| would split the table's cells
        rows.append(f"| `{m.name}` | {m.units} | {m.stage} | {sense} | {what} |")
    return "\n".join(rows) + "\n"


if __name__ == "__main__":   # pragma: no cover - the docs' generator
    print(markdown_table(), end="")
