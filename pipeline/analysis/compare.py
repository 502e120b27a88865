"""Designs side by side (`pipeline compare`, ``pipeline.compare``, the report's
comparison): the quantities a designer compares, read from each design's scene
file as ``pipeline run`` stored them, matched row by row.

The rows, in order (each with its unit; a peak with the crank angle where it
happens and the point, joint or dyad it belongs to):

* the output rocker's stroke [mm] and dwell error [1] (``/motion``);
* the working point's peak |v| [m/s] and |a| [m/s²] (``/peaks``);
* the smallest transmission angle over every dyad and class III lead [deg];
* the peak |R| of every joint and the largest of them [N];
* the peak |M_bal| [N·m];
* the smallest pin diameter d_min of every joint and the largest [mm]
  (``/peaks/pin_d_min``: (32 R_max l / (pi sigma))^(1/3), DOMAIN.md section 5);
* the peak shaking force [N] and moment [N·m] on the frame;
* with joint friction ([mechanism.friction], ``/friction``): the mean power lost
  in friction over a revolution [W] and the largest peak p*v of the pins
  [MPa*m/s] (the reactions and M_bal above are then the friction-inclusive
  ones; a note says so where the designs differ in friction).

Matching.  A row is compared (with the change against the first design) only
where every design has it.  Joints are matched by their position in the list
when every design has the same number of joints (R1 with R1, or with the
other mechanism's first joint whatever its name); otherwise each design's
joints are listed under their own names, each row with that design's values
only, and only the largest |R| and the largest d_min are compared.  A
quantity that some designs lack (a scene without a force analysis has no
reactions, M_bal, pins or shaking; a mechanism without an output rocker has
no stroke or dwell error) is shown for the designs that have it and named in
a note as not compared; when no row is compared at all, the comparison is
refused, naming what each design has.

A sweep's design is compared with the sweep's reference design by re-running
both as scenes (``candidate.candidate_scene``, solved by ``pipeline run``'s
own ``solve.scene_study.solve_scene`` and read back through its file format):
the same numbers ``pipeline run`` would store for each.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..base.files import fault_point
from ..results.scene_file import peaks_table
from ..results.storage import attr_text, open_results
from ..base.errors import ResultsError


@dataclass
class Design:
    """What a comparison reads of one design (a scene results file)."""
    label: str
    source: str
    status: str
    omega1: float                 # rad/s
    working_point: str
    dwell_deg: float              # the dwell window, deg (NaN: no output rocker)
    motion: dict                  # stroke [mm], dwell_error [1] (empty: no output rocker)
    peaks: object                 # DataFrame of ``results.scene_file.peaks_table``
    pins: dict                    # joint -> (length mm, allowable stress MPa)
    phi: np.ndarray               # dense crank angles, deg
    path: np.ndarray              # (n, 2) working point's position, mm
    joints: list = field(default_factory=list)
    reaction: np.ndarray | None = None   # (n, n_joints) |R|, N
    M_bal: np.ndarray | None = None      # (n,) N·m
    candidate: str | None = None         # a sweep's design: its candidate number
    # with [mechanism.friction]: {"mean_loss": (W, None, None), "peak_pv": (MPa*m/s, phi1
    # deg, joint)}; None: frictionless
    friction: dict | None = None

    @property
    def has_forces(self):
        return self.reaction is not None


def read_design(path, label=None, source=None) -> Design:
    """One design from its scene results file (``pipeline run`` of a scene study)."""
    path = Path(path)
    with open_results(path) as f:
        kind = str(attr_text(f.attrs.get("kind")))
        if kind == "sweep":
            raise ResultsError(path, "is a sweep: compare one of its designs with its reference "
                                     f"design by `pipeline compare {path} --candidate ID` (a "
                                     "number or 'knee')")
        if kind != "scene":
            raise ResultsError(path, f"is a {kind} result; `pipeline compare` reads scene "
                                     "results files (`pipeline run` of a scene study)")
    with open_results(path, "scene") as f:
        try:
            return design_of(f, label or path.stem, source or path)
        except ResultsError:
            raise
        except (OSError, ValueError, KeyError, TypeError, IndexError) as e:   # h5py's words
            why = " ".join(str(e).split()) or type(e).__name__
            raise ResultsError(path, f"is damaged: {why}") from None


def design_of(f, label, source) -> Design:
    """One design from an open scene results file ``f``."""
    m = f["mechanism"]
    wp = str(attr_text(m.attrs["working_point"]))
    names = [str(attr_text(x)) for x in m.attrs["point_names"]]
    d = f["dense"]
    phi = d["phi1"][()]
    pos = d["position"][:, names.index(wp)]
    peaks = peaks_table(f) if "peaks" in f else _no_peaks()
    motion, dwell = {}, math.nan
    if "motion" in f:
        g = f["motion"]
        motion = {k: float(g[k][()]) for k in ("stroke", "dwell_error") if k in g}
        dwell = float(g.attrs.get("dwell_deg", math.nan))
    joints, reaction, M_bal, pins = [], None, None, {}
    if "reactions" in d:
        R = d["reactions"][()]
        joints = [str(attr_text(x)) for x in d["reactions"].attrs["joints"]]
        reaction = np.hypot(R[..., 0], R[..., 1])
        M_bal = d["M_bal"][()]
        if "peaks/pin_length" in f:
            pins = dict(zip(joints, zip(f["peaks/pin_length"][()].tolist(),
                                        f["peaks/pin_sigma"][()].tolist())))
    status = str(attr_text(f.attrs.get("status", "?")))
    return Design(label, str(source), status, float(m.attrs["omega1"]),
                  wp, dwell, motion, peaks, pins, phi, pos, joints, reaction, M_bal,
                  friction=_friction(f, joints))


def _friction(f, joints):
    """What a comparison reads of a scene's /friction (None: frictionless): the
    mean loss and the largest of the pins' peak p*v, with its crank angle and pin."""
    if "friction" not in f:
        return None
    g = f["friction"]
    out = {"mean_loss": (float(g["mean_loss"][()]), None, None)}
    pv = g["peak_pv"][()]
    if pv.size and np.isfinite(pv).any():
        j = int(np.nanargmax(pv))
        out["peak_pv"] = (float(pv[j]), float(g["peak_pv_phi1"][j]), joints[j])
    return out


def _no_peaks():
    import pandas as pd
    return pd.DataFrame(columns=["quantity", "item", "value", "unit", "phi1", "grid_value",
                                 "d_min"])


# ----------------------------------------------------------------- the rows
@dataclass
class Row:
    """One compared quantity: per design its value (None: the design has no
    such quantity), the crank angle of the peak (deg; None: not a peak) and the
    point, joint or dyad it belongs to."""
    key: str                # machine name: stroke, reaction[0], reaction[R1@ov7_base], ...
    family: str             # what a note names when the row is not compared
    quantity: str           # for people
    unit: str
    values: list
    phi1: list
    items: list

    @property
    def compared(self):
        return all(v is not None for v in self.values)

    def change(self, k):
        """Design k against the first: (difference, relative difference), or None."""
        if not self.compared or k == 0:
            return None
        a, b = self.values[0], self.values[k]
        return b - a, (b - a) / abs(a) if a else math.nan


@dataclass
class Comparison:
    designs: list
    rows: list
    notes: list

    @property
    def labels(self):
        return [d.label for d in self.designs]

    def table(self):
        """The rows as a DataFrame: quantity, unit, and per design its value,
        crank angle and item; per later design the change against the first
        (units in ``df.attrs["units"]``)."""
        import pandas as pd
        cols = {"quantity": [r.quantity for r in self.rows], "unit": [r.unit for r in self.rows],
                "compared": [r.compared for r in self.rows]}
        units = {"quantity": "", "unit": "", "compared": ""}
        for k, lab in enumerate(self.labels):
            cols[lab] = [np.nan if r.values[k] is None else r.values[k] for r in self.rows]
            cols[f"{lab} phi1"] = [np.nan if r.phi1[k] is None else r.phi1[k] for r in self.rows]
            cols[f"{lab} item"] = [r.items[k] or "" for r in self.rows]
            units.update({lab: "(unit)", f"{lab} phi1": "deg", f"{lab} item": ""})
            if k:
                ch = [r.change(k) for r in self.rows]
                cols[f"{lab} - {self.labels[0]}"] = [c[0] if c else np.nan for c in ch]
                cols[f"{lab} / {self.labels[0]} - 1"] = [c[1] if c else np.nan for c in ch]
                units.update({f"{lab} - {self.labels[0]}": "(unit)",
                              f"{lab} / {self.labels[0]} - 1": "1"})
        df = pd.DataFrame(cols)
        df.attrs["units"] = units
        return df


def _peak(design, quantity, item=None):
    """(value, phi1, item) of a stored peak, or None."""
    df = design.peaks
    sel = df[df["quantity"] == quantity]
    if item is not None:
        sel = sel[sel["item"] == item]
    if sel.empty:
        return None
    r = sel.iloc[0]
    return float(r["value"]), float(r["phi1"]), str(r["item"])


def _extreme(design, quantity, column="value", smallest=False):
    """(value, phi1, item) of the largest (smallest) of a quantity's peaks."""
    df = design.peaks
    sel = df[df["quantity"] == quantity]
    if sel.empty or not np.isfinite(sel[column].to_numpy(float)).any():
        return None
    v = sel[column].to_numpy(float)
    k = int(np.nanargmin(v) if smallest else np.nanargmax(v))
    r = sel.iloc[k]
    return float(r[column]), float(r["phi1"]), str(r["item"])


def _row(key, family, quantity, unit, cells):
    return Row(key, family, quantity, unit, [c[0] if c else None for c in cells],
               [c[1] if c else None for c in cells], [c[2] if c else None for c in cells])


FAMILY_WHY = {
    "motion": "no output rocker ([output] rocker) or a revolution that does not assemble",
    "working point": "no peaks (the scene does not assemble over the revolution)",
    "transmission": "no dyad or class III lead",
    "reactions": "no force analysis ([output] analysis = \"forces\" needs [[mechanism.bodies]])",
    "shaking": "no shaking force stored",
    "friction": "no joint friction ([mechanism.friction])",
}


def compare_designs(designs) -> Comparison:
    """The rows of ``designs`` (a list of ``Design``, the first the base) and
    the notes on what is not compared; refused when no row is compared."""
    if len(designs) < 2:
        raise ValueError("compare needs two designs or more")
    _unique_labels(designs)
    rows = []
    for key, quantity, unit in (("stroke", "stroke", "mm"), ("dwell_error", "dwell error", "1")):
        cells = [(d.motion[key], None, f"{d.dwell_deg:g} deg window" if key == "dwell_error"
                  else None) if key in d.motion else None for d in designs]
        rows.append(_row(key, "motion", quantity, unit, cells))
    for q, unit in (("velocity", "m/s"), ("acceleration", "m/s²")):
        rows.append(_row(f"working_point_{q}", "working point",
                         f"peak |{'v' if q == 'velocity' else 'a'}| working point", unit,
                         [_peak(d, q, d.working_point) for d in designs]))
    rows.append(_row("min_transmission_angle", "transmission", "smallest transmission angle",
                     "deg", [_extreme(d, "min_transmission_angle", smallest=True)
                             for d in designs]))
    notes = []
    rows += _joint_rows(designs, notes)
    rows.append(_row("M_bal", "reactions", "peak |M_bal|", "N·m",
                     [_peak(d, "M_bal") for d in designs]))
    rows.append(_row("shaking_force", "shaking", "peak shaking force", "N",
                     [_peak(d, "shaking_force") for d in designs]))
    rows.append(_row("shaking_moment", "shaking", "peak shaking moment", "N·m",
                     [_peak(d, "shaking_moment") for d in designs]))
    for key, quantity, unit in (("mean_loss", "mean friction loss", "W"),
                                ("peak_pv", "largest peak p*v", "MPa·m/s")):
        rows.append(_row(f"friction_{key}", "friction", quantity, unit,
                         [(d.friction or {}).get(key) for d in designs]))
    rows = [r for r in rows if any(v is not None for v in r.values)]
    if not any(r.compared for r in rows):
        have = "; ".join(f"{d.source} ({d.status}): " + (", ".join(
            dict.fromkeys(r.family for r in rows if r.values[k] is not None)) or "nothing")
            for k, d in enumerate(designs))
        raise ValueError(f"nothing to compare: no quantity is in every design ({have})")
    notes[:0] = _left_out(designs, rows)
    notes += _context(designs)
    return Comparison(list(designs), rows, notes)


def _unique_labels(designs):
    seen = {}
    for d in designs:
        n = seen.get(d.label, 0)
        seen[d.label] = n + 1
        if n:
            d.label = f"{d.label} ({n + 1})"


def _joint_rows(designs, notes):
    """Peak |R| and d_min per joint, matched by position where every design has
    as many joints, else under each design's own names; then the largest."""
    with_f = [d for d in designs if d.has_forces]
    counts = sorted({len(d.joints) for d in with_f})
    rows = []
    per_joint = []      # (key, quantity, cells) for |R| and d_min
    if len(with_f) == len(designs) and len(counts) == 1:
        names = [d.joints for d in designs]
        for j in range(counts[0]):
            same = len({n[j] for n in names}) == 1
            label = names[0][j] if same else " / ".join(n[j] for n in names)
            per_joint.append((f"[{j}]", label, [j] * len(designs)))
        if any(n != names[0] for n in names):
            notes.append("joints matched by their position in each list: " + "; ".join(
                " = ".join(f"{n[j]} ({d.label})" for n, d in zip(names, designs))
                for j in range(counts[0])))
    else:
        for k, d in enumerate(designs):
            for j, name in enumerate(d.joints):
                cols = [None] * len(designs)
                cols[k] = j
                label = f"{name} ({d.label})" if len(with_f) > 1 else name
                per_joint.append((f"[{name}@{d.label}]", label, cols))
        if len(with_f) > 1:
            notes.append("joints not matched one to one (" + ", ".join(
                f"{d.label} has {len(d.joints)}" for d in with_f) + "): each design's joints "
                "are listed under its own names; the largest |R| and d_min are compared")
    for column, key, quantity, unit in (("value", "reaction", "peak |R|", "N"),
                                        ("d_min", "pin_d_min", "pin d_min", "mm")):
        for tag, label, cols in per_joint:
            cells = [_joint(d, j, column) for d, j in zip(designs, cols)]
            rows.append(_row(f"{key}{tag}", "reactions", f"{quantity} {label}", unit, cells))
        rows.append(_row(f"{key}_max", "reactions", f"largest {quantity}", unit,
                         [_extreme(d, "reaction", column) for d in designs]))
    return rows


def _joint(design, j, column):
    if j is None or not design.has_forces:
        return None
    df = design.peaks
    sel = df[(df["quantity"] == "reaction") & (df["item"] == design.joints[j])]
    if sel.empty:
        return None
    r = sel.iloc[0]
    return float(r[column]), float(r["phi1"]), str(r["item"])


def _left_out(designs, rows):
    """One note per family of rows not compared: which designs lack it, why."""
    lacking = {}
    for fam in dict.fromkeys(r.family for r in rows):
        rs = [r for r in rows if r.family == fam]
        if not all(r.compared for r in rs):
            lacking[fam] = [d for k, d in enumerate(designs)
                            if all(r.values[k] is None for r in rs)]
    what = {"reactions": "reactions, pin diameters and M_bal", "motion": "stroke and dwell error",
            "friction": "friction loss and p*v"}
    if lacking.get("shaking") and set(map(id, lacking["shaking"])) <= set(
            map(id, lacking.get("reactions", []))):      # no forces: no shaking either
        what["reactions"] = "reactions, pin diameters, M_bal and the shaking force and moment"
        del lacking["shaking"]
    out = []
    for fam, missing in lacking.items():
        if missing:
            out.append(f"not compared: {what.get(fam, fam)}; "
                       f"{', '.join(d.label for d in missing)} "
                       f"{'has' if len(missing) == 1 else 'have'} {FAMILY_WHY.get(fam, 'none')}")
    return out


def _context(designs):
    """Notes on conditions that differ between the designs."""
    out = []
    w = {d.omega1 for d in designs}
    if len(w) > 1:
        out.append("the designs run at different speeds (omega1 " + ", ".join(
            f"{d.omega1:g} rad/s ({d.label})" for d in designs) + "): inertia loads grow "
            "with omega1^2")
    dw = {d.dwell_deg for d in designs if math.isfinite(d.dwell_deg)}
    if len(dw) > 1:
        out.append("the dwell errors are over different windows (" + ", ".join(
            f"{d.dwell_deg:g} deg ({d.label})" for d in designs) + ")")
    pins = {p for d in designs for p in d.pins.values()}
    if pins:
        out.append("pins in bending: " + ", ".join(f"l = {ln:g} mm, sigma = {sg:g} MPa"
                                                   for ln, sg in sorted(pins))
                   + " (d_min = (32 R_max l / (pi sigma))^(1/3))")
    rubbing = [d.label for d in designs if d.friction is not None]
    if rubbing and len(rubbing) < len(designs):
        out.append("the reactions and M_bal of " + ", ".join(rubbing) + " include joint "
                   "friction ([mechanism.friction]), the others' do not")
    bad = [d for d in designs if d.status != "OK"]
    for d in bad:
        out.append(f"{d.label}: status {d.status}, only what it stores is compared")
    return out


# ----------------------------------------------------------------- entry points
def compare_files(paths) -> Comparison:
    """Scene results files side by side, the first the base."""
    return compare_designs([read_design(p) for p in paths])


def candidate_designs(path, candidate) -> list:
    """A sweep's reference design and its design ``candidate`` (a number or
    'knee'), each re-run as a scene (``candidate.candidate_scene``) and read
    back from a scene file in memory (nothing on the disk for a kill to leave)."""
    from ..results.scene_file import scene_in_memory
    from ..solve.scene_study import solve_scene
    from .candidate import candidate_scene
    if str(candidate).strip().lower() in ("reference", "ref"):
        raise ValueError("--candidate reference: the reference design is what a candidate is "
                         "compared with; give a candidate number or 'knee'")
    out = []
    for cid in ("reference", candidate):
        study, label, number = candidate_scene(path, cid)
        with scene_in_memory(solve_scene(study)) as f:
            out.append(design_of(f, label, f"{path} {label}"))
        out[-1].candidate = number
        fault_point("design-compared")     # the tests' kill -9: nothing on the disk to leave
    return out


def compare_candidate(path, candidate) -> Comparison:
    """A sweep's design ``candidate`` against the sweep's reference design."""
    return compare_designs(candidate_designs(path, candidate))
