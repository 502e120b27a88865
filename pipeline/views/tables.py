"""Results files as tables (pandas DataFrames), for the Python API and for
`pipeline export`.

* a sweep: one row per candidate (design variables, status name, feasibility,
  constraint violation, Pareto front, metrics, constraints);
* a scene: its points, links, reactions (the joints' Rx, Ry, |R|; each
  slide's normal force N, couple C and the point of action e = C/N of
  ``reactions.slide_action``; the shaking force and moment on the frame; the
  equilibrium residual; M_bal), with joint friction its friction table (per
  joint the friction moment, relative angular velocity analog, loss, bearing
  pressure p, sliding speed v and p*v; per slide its friction force, sliding
  analog and loss; the total loss and M_bal without friction), peaks and
  dynamics motion tables, at every computed position.

Column names are plain (``L12``, ``P8_x``); the units of every column are in
``df.attrs["units"]``, and ``with_units(df)`` gives headers such as
``V8_x [m/s]`` for files meant for people.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..base.files import safe_name
from ..kernels import config as kc
from ..results.scene_file import peaks_table
from ..base.units import unit_text
from ..results.storage import attr_text, candidate_ids, open_results, read_units, variables
from ..base.errors import ResultsError


def with_units(df: pd.DataFrame) -> pd.DataFrame:
    """A copy whose headers carry their units: ``name [unit]`` (none for text
    columns and counts)."""
    units = df.attrs.get("units", {})
    # one style of units (N·m, m/s²), a file written before it too
    return df.rename(columns={c: f"{c} [{unit_text(units[c])}]" for c in df.columns
                              if units.get(c)})


def joint_labels(index, joints) -> np.ndarray:
    """The joints' names (R1, ...) of the stored joint indices ``index`` (a
    sweep's peak_joint); "" where there is none (NaN, out of range)."""
    index = np.asarray(index, float)
    names = np.array(list(joints) + [""], dtype=object)
    ok = np.isfinite(index) & (index >= 0) & (index < len(joints))
    return names[np.where(ok, np.nan_to_num(index, nan=-1.0), len(joints)).astype(np.int64)]


def _frame(cols: dict, units: dict) -> pd.DataFrame:
    df = pd.DataFrame(cols)
    df.attrs["units"] = {c: units.get(c, "") for c in df.columns}
    return df


# ----------------------------------------------------------------- sweeps
def candidates(path, *, feasible=False, front=None) -> pd.DataFrame:
    """The candidates of a sweep file: all, only the feasible ones, or those of
    Pareto fronts 1 .. ``front``.  The rows equal the HDF5 datasets."""
    from ..analysis.ranking import ranking
    from ..analysis.fronts import variable_units
    with open_results(path, "sweep") as f:
        p = f["candidates/params"]
        names = [str(attr_text(x)) for x in p.attrs["names"]]
        vunits = variable_units(p)
        X = p[()]
        status = f["candidates/status"][()]
        feas = f["candidates/feasible"][()]
        rk = ranking(f)
        cols = {"candidate": candidate_ids(f),
                "status": pd.Categorical.from_codes(
                    np.where(status >= 0, status, kc.NOT_EVALUATED).astype(int),
                    [kc.STATUS_NAMES[k] for k in sorted(kc.STATUS_NAMES)]),
                "feasible": feas, "cv": f["candidates/cv"][()],
                "front": rk.rank, "fail_phi": f["candidates/fail_phi"][()]}
        units = {"cv": "1", "front": "", "fail_phi": "deg"}
        if "candidates/fail_group" in f:     # format 1.2: the group that failed, by name
            fg = f["candidates/fail_group"]
            groups = np.array([str(attr_text(x)) for x in fg.attrs.get("groups", [])] + [""],
                              dtype=object)
            idx = fg[()].astype(np.int64)
            cols["fail_group"] = groups[np.where((idx >= 0) & (idx < len(groups) - 1), idx, -1)]
            units["fail_group"] = ""
        if "candidates/generation" in f:     # an adaptive search: who proposed the design
            cols["generation"] = f["candidates/generation"][()]
            units["generation"] = ""
        for j, n in enumerate(names):
            cols[n] = X[:, j]
            units[n] = vunits[j]
        joints = [str(attr_text(j)) for j in f["metrics"].attrs.get("joint_names", [])]
        for m in variables(f["metrics"]):
            cols[m] = f[f"metrics/{m}"][()]
            units[m] = str(attr_text(f[f"metrics/{m}"].attrs.get("units", "")))
            if m == "peak_joint" and joints:      # the joint by name, as a scene's CSV: R1
                cols[m], units[m] = joint_labels(cols[m], joints), ""
        g = f["candidates/constraints"]
        cn = [str(attr_text(n)) for n in g.attrs.get("names", [])]
        cu = read_units(g, len(cn))
        G = g[()]
        for j, n in enumerate(cn):
            cols[f"g_{n}"] = G[:, j]
            units[f"g_{n}"] = cu[j] if j < len(cu) else ""
    df = _frame(cols, units)
    if feasible:
        df = df[df["feasible"]]
    if front is not None:
        if front < 1:
            raise ValueError(f"--front must be at least 1, got {front}")
        df = df[(df["front"] >= 1) & (df["front"] <= front)]
    df.attrs["units"] = units | {"candidate": "", "status": "", "feasible": ""}
    return df


# ----------------------------------------------------------------- scenes
def _short(name, letter):
    """P9 -> V9 (velocity columns), other names -> V[name]."""
    if name.startswith("P") and name[1:].isdigit():
        return f"{letter}{name[1:]}"
    return f"{letter}[{name}]"


def scene_tables(path, every=1) -> dict:
    """{name: DataFrame} of a scene file at every computed position (every
    ``every``-th): points, links, and reactions, peaks, counterweight,
    cyclogram (the output's phase boundaries and errors, deg of the cycle
    angle), motion_<case> where the file has them."""
    if every < 1:
        raise ValueError(f"--every must be at least 1, got {every}")
    out = {}
    with open_results(path) as f:
        if attr_text(f.attrs["kind"]) != "scene":
            raise ResultsError(path, f"is a {attr_text(f.attrs['kind'])} result; its table is "
                                     "`pipeline export FILE --csv DIR` (candidates.csv)")
        m = f["mechanism"]
        names = [str(attr_text(x)) for x in m.attrs["point_names"]]
        links = [str(attr_text(x)) for x in m.attrs["link_labels"]]
        d = f["dense"]
        rows = slice(None, None, every)
        phi = d["phi1"][rows]
        cols, units = {"phi1": phi}, {"phi1": "deg"}
        pos, vel, acc = d["position"][rows], d["velocity"][rows], d["acceleration"][rows]
        for i, n in enumerate(names):
            for key, arr, unit in ((n, pos, "mm"), (_short(n, "V"), vel, "m/s"),
                                   (_short(n, "A"), acc, "m/s²")):
                for k, ax in enumerate("xy"):
                    cols[f"{key}_{ax}"] = arr[:, i, k]
                    units[f"{key}_{ax}"] = unit
        out["points"] = _frame(cols, units)
        cols, units = {"phi1": phi}, {"phi1": "deg"}
        ang, om, ep = d["link_angle"][rows], d["link_omega"][rows], d["link_eps"][rows]
        for j, lab in enumerate(links):
            for key, arr, unit in (("phi", ang, "deg"), ("omega", om, "1/s"),
                                   ("eps", ep, "1/s²")):
                cols[f"{key}_{lab}"] = arr[:, j]
                units[f"{key}_{lab}"] = unit
        out["links"] = _frame(cols, units)
        if "com_position" in d:
            bodies = [str(attr_text(x)) for x in d["com_position"].dims[1][0][()]]
            cols, units = {"phi1": phi}, {"phi1": "deg"}
            S, VS, AS = d["com_position"][rows], d["com_velocity"][rows], \
                d["com_acceleration"][rows]
            L = d["body_loads"][rows] if "body_loads" in d else None
            for b, name in enumerate(bodies):
                for key, arr, unit in ((f"S[{name}]", S, "mm"), (f"VS[{name}]", VS, "m/s"),
                                       (f"AS[{name}]", AS, "m/s²")):
                    for k, ax in enumerate("xy"):
                        cols[f"{key}_{ax}"] = arr[:, b, k]
                        units[f"{key}_{ax}"] = unit
                if L is not None:   # applied and inertia loads reduced to S
                    for k, (comp, unit) in enumerate((("Fx", "N"), ("Fy", "N"), ("M", "N·m"))):
                        cols[f"{comp}[{name}]"] = L[:, b, k]
                        units[f"{comp}[{name}]"] = unit
            out["bodies"] = _frame(cols, units)
        if "reactions" in d:
            from ..solve.reactions import joint_peaks
            cols, units = {"phi1": phi}, {"phi1": "deg"}
            mag, joints = reaction_columns(d, rows, cols, units)
            out["reactions"] = _frame(cols, units)
            if "peaks" not in f:       # a file written before refined peaks: grid peaks
                peaks = pd.DataFrame(joint_peaks(d["phi1"][()], mag, joints),
                                     columns=["joint", "R_max", "phi1", "d_min"])
                peaks.attrs["units"] = {"joint": "", "R_max": "N", "phi1": "deg", "d_min": "mm"}
                out["peaks"] = peaks
        if "friction_status" in d:     # [mechanism.friction]: the joints' friction
            out["friction"] = friction_table(d, rows)
        if "peaks" in f:
            out["peaks"] = peaks_table(f)
        if "counterweight" in f:      # one row: m_c r_c, its angle, the peaks before and after
            g = f["counterweight"]
            keys = ("mass_radius", "angle", "peak_before", "peak_before_phi1", "peak_after",
                    "peak_after_phi1")
            out["counterweight"] = _frame({k: [float(g[k][()])] for k in keys},
                                          {k: str(attr_text(g[k].attrs["units"])) for k in keys})
        if "cyclogram" in f:          # the output's phase boundaries against the required cycle
            g = f["cyclogram"]
            turn = float(g.attrs["turn"])
            cols = {"boundary": [str(attr_text(x)) for x in g["boundary"][()]],
                    "design": np.mod(g["actual"][()] - turn, 360.0),
                    "required": np.mod(g["required"][()] - turn, 360.0),
                    "phase_error": g["phase_error"][()]}
            out["cyclogram"] = _frame(cols, {"design": "deg", "required": "deg",
                                             "phase_error": "deg"})
        if "dynamics" in f:
            out.update(motion_tables(f["dynamics"]))
        if "reduced_dynamics" in f:
            g = f["reduced_dynamics"]
            cols = {c: g[c][()] for c in ("phi1", "J", "half_dJ", "Q")}
            out["reduced"] = _frame(cols, {c: str(attr_text(g[c].attrs["units"]))
                                           for c in cols})
    return out


# a scene's friction datasets per joint (then per slide): (dataset, column's name)
FRICTION_JOINT_COLUMNS = (("friction_moment", "M_f"), ("relative_omega_analog", "omega_rel'"),
                          ("friction_loss", "loss"), ("bearing_pressure", "p"),
                          ("sliding_speed", "v"), ("pv", "pv"))
FRICTION_SLIDE_COLUMNS = (("slide_friction_force", "F_f"), ("sliding_analog", "s_rel'"),
                          ("slide_friction_loss", "loss"))


def friction_table(d, rows) -> pd.DataFrame:
    """A scene's friction at the rows ``rows`` of its dense curves ``d``
    (``results.scene_file._friction_curves``): the status, per joint and per
    slide its columns (``M_f[R2]``, ``pv[R2]``, ``F_f[slider]``), the total
    loss and M_bal without friction, each with its dataset's units."""
    from ..solve.reactions import slide_label
    cols = {"phi1": d["phi1"][rows],
            "friction_status": [kc.STATUS_NAMES.get(int(s), str(int(s)))
                                for s in d["friction_status"][rows]]}
    units = {"phi1": "deg", "friction_status": ""}
    joints = [str(attr_text(x)) for x in d["reactions"].attrs["joints"]]
    groups = [(joints, FRICTION_JOINT_COLUMNS)]
    if "slide_friction_force" in d:
        slides = [slide_label(str(attr_text(x)))
                  for x in d["slide_friction_force"].attrs["slides"]]
        groups.append((slides, FRICTION_SLIDE_COLUMNS))
    for names, columns in groups:
        for key, short in columns:
            data, unit = d[key][rows], str(attr_text(d[key].attrs.get("units", "")))
            for j, name in enumerate(names):
                cols[f"{short}[{name}]"] = data[:, j]
                units[f"{short}[{name}]"] = unit
    for key in ("friction_loss_total", "M_bal_frictionless"):
        cols[key] = d[key][rows]
        units[key] = str(attr_text(d[key].attrs.get("units", "")))
    return _frame(cols, units)


def joint_headers(f, joints) -> dict:
    """{joint: its column header}: 'R2 (crank 1-2 / lead 2-3 at P2)', the
    bodies it joins and its point as the pictures name them (ASCII); the bare
    name for a file written before the scene files stored them."""
    import unicodedata
    out = {j: j for j in joints}
    if "joint" in f and "where" in f["joint"].attrs:
        names = [str(attr_text(x)) for x in f["joint"][()]]
        for name, w in zip(names, f["joint"].attrs["where"]):
            w = unicodedata.normalize("NFKD", str(attr_text(w))).encode("ascii", "ignore")
            if name in out:
                out[name] = f"{name} ({w.decode()})"
    return out


def reaction_columns(d, rows, cols, units):
    """The force columns of a group ``d`` holding a ``Reactions`` (a scene's
    dense curves, or a dynamics case's forces along the motion) at the rows
    ``rows``, added to ``cols`` and ``units``: every joint's components and
    magnitude, the slides' N, C and e, the inputs' drives, the shaking force
    and moment, the equilibrium residual and M_bal.  Returns (|R| at every
    row, the joint names)."""
    R = d["reactions"][()]
    joints = [str(attr_text(x)) for x in d["reactions"].attrs["joints"]]
    where = joint_headers(d.file, joints)
    mag = np.hypot(R[..., 0], R[..., 1])
    for j, name in enumerate(joints):
        head = where[name]
        cols[f"{head} x"] = R[rows, j, 0]
        cols[f"{head} y"] = R[rows, j, 1]
        cols[head] = mag[rows, j]
        units.update({f"{head} x": "N", f"{head} y": "N", head: "N"})
    if "slide_reactions" in d:     # prismatic pairs: N, C and where N acts
        from ..solve.reactions import slide_action, slide_label
        S = d["slide_reactions"][rows]
        E = slide_action(S)
        for k, name in enumerate(d["slide_reactions"].attrs["slides"]):
            lab = slide_label(str(attr_text(name)))
            cols[f"N[{lab}]"], cols[f"C[{lab}]"] = S[:, k, 0], S[:, k, 1]
            cols[f"e[{lab}]"] = E[:, k]
            units.update({f"N[{lab}]": "N", f"C[{lab}]": "N·m", f"e[{lab}]": "mm"})
    if "input_drive" in d:        # inputs besides the crank: drive and share
        from ..results.storage import read_units
        D = d["input_drive"][rows]
        H = d["input_share"][rows]
        names = [str(attr_text(x)) for x in d["input_drive"].attrs["inputs"]]
        du = read_units(d["input_drive"], len(names))
        for k, name in enumerate(names):
            cols[f"drive[{name}]"], cols[f"share[{name}]"] = D[:, k], H[:, k]
            units.update({f"drive[{name}]": du[k], f"share[{name}]": "N·m"})
    if "shaking_force" in d:      # on the frame; the moment about the crank's pivot
        F = d["shaking_force"][rows]
        cols["shaking_Fx"], cols["shaking_Fy"] = F[:, 0], F[:, 1]
        cols["shaking_F"] = d["shaking_force_magnitude"][rows]
        cols["shaking_M"] = d["shaking_moment"][rows]
        units.update({"shaking_Fx": "N", "shaking_Fy": "N", "shaking_F": "N",
                      "shaking_M": "N·m"})
    if "equilibrium_residual" in d:
        cols["equilibrium_residual"] = d["equilibrium_residual"][rows]
        units["equilibrium_residual"] = "1"
    cols["M_bal"] = d["M_bal"][rows]
    units["M_bal"] = "N·m"
    return mag, joints


def motion_tables(group) -> dict:
    """{"motion_<case>": DataFrame(t, phi1, omega1, eps1)} from the stored
    dynamics group (units in ``df.attrs["units"]``)."""
    out = {}
    for name in group:
        g = group[name]
        df = pd.DataFrame({"t": g["t"][()], "phi1": g["phi1"][()], "omega1": g["omega1"][()],
                           "eps1": g["eps1"][()]})
        df.attrs["units"] = {c: str(g[c].attrs.get("units", "")) for c in df.columns}
        out[f"motion_{safe_name(name, 'case')}"] = df
        for sub, tag in (("forces", "forces"), ("steady_forces", "steady_forces")):
            if sub in g:         # the kinetostatics along the motion
                h = g[sub]
                cols = {c: h[c][()] for c in ("t", "phi1", "omega1", "eps1")}
                units = {c: str(attr_text(h[c].attrs.get("units", ""))) for c in cols}
                reaction_columns(h, slice(None), cols, units)
                out[f"motion_{safe_name(name, 'case')}_{tag}"] = _frame(cols, units)
    return out
