"""A scene's results file: its layout in HDF5 (the mechanism, the table and
dense curves, the forces and the dynamics cases), written through the plain
array-and-attribute layer of ``pipeline.results.storage``.  The computing
modules (``solve.reactions``, ``solve.crank_motion``) hand over their results;
only this module writes them."""

from __future__ import annotations

import io
import math
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np

from ..kernels import config as kc
from ..base.files import replacing
from ..solve.reactions import slide_action
from ..solve.scene import real_motion
from ..solve.crank_motion import ACCEPTED_ERROR_RAD, STATUS_NAMES
from .storage import (STATUS_ENUM, attr_text, coordinate, hdf5_image, put, status_table,
                      variables, write_root_attrs)


def _curves(g, res, curves, study):
    plan = res.plan
    crank = study.mechanism.crank
    v, a, om, ep = real_motion(curves, crank.omega1, crank.eps1)
    nv = plan.n_visible
    put(g, "phi1", np.rad2deg(curves.phi), "deg", "crank angle phi1", dims=("phi1",))
    put(g, "status", curves.status.astype(STATUS_ENUM), "1", "position status",
        dims=("phi1",), codes=status_table())
    xy = ("phi1", "point", "axis")
    put(g, "position", curves.pos[:, :nv], "mm", "point position", dims=xy)
    put(g, "position_analog", curves.d1[:, :nv], "mm/rad", "velocity analog dr/dphi1", dims=xy)
    put(g, "acceleration_analog", curves.d2[:, :nv], "mm/rad²",
        "acceleration analog d2r/dphi1^2", dims=xy)
    put(g, "velocity", v[:, :nv], "m/s", "point velocity", dims=xy)
    put(g, "acceleration", a[:, :nv], "m/s²", "point acceleration", dims=xy)
    put(g, "link_angle", np.rad2deg(curves.links[:, :, 0]), "deg", "link angle",
        dims=("phi1", "link"))
    put(g, "link_omega", om, "1/s", "link angular velocity", dims=("phi1", "link"))
    put(g, "link_eps", ep, "1/s²", "link angular acceleration", dims=("phi1", "link"))
    put(g, "margin", curves.margin, "1", "distance from a toggle position per group",
        dims=("phi1", "group"))
    put(g, "newton_iterations", curves.iterations, "1", "Newton iterations (class III groups)",
        dims=("phi1",))
    com = np.asarray(plan.body_com, np.int64)
    if com.size:   # the centres of mass (the thesis's PS, VS, AS tables)
        sb = ("phi1", "body", "axis")
        put(g, "com_position", curves.pos[:, com], "mm", "centre-of-mass position", dims=sb)
        put(g, "com_position_analog", curves.d1[:, com], "mm/rad",
            "centre-of-mass velocity analog dS/dphi1", dims=sb)
        put(g, "com_acceleration_analog", curves.d2[:, com], "mm/rad²",
            "centre-of-mass acceleration analog d2S/dphi1^2", dims=sb)
        put(g, "com_velocity", v[:, com], "m/s", "centre-of-mass velocity", dims=sb)
        put(g, "com_acceleration", a[:, com], "m/s²", "centre-of-mass acceleration", dims=sb)
    if curves.forces is not None:
        _reactions(g, curves.forces)


def _reactions(g, r, along="phi1"):
    """The reactions of a scene (``solve.reactions.Reactions``) at the positions of group
    ``g``, along its coordinate ``along`` (the crank angle; the time along a motion)."""
    put(g, "reactions", r.R, "N", "joint reaction (force of the first body on the second)",
        dims=(along, "joint", "axis"), joints=list(r.joint_names))
    put(g, "M_bal", r.M_bal, "N·m", "balancing moment the main shaft delivers (on the crank; "
        "with inputs besides the crank, plus their shares)", dims=(along,))
    if r.slide.shape[1]:
        put(g, "slide_reactions", r.slide, ["N", "N·m"],
            "prismatic pair: normal force N of the guide on the slider (along the slide's "
            "direction turned +90 deg) and couple C, at the slider's centre of mass",
            dims=(along, "slide", "slide_component"), slides=list(r.slide_names))
        put(g, "slide_action", slide_action(r.slide), "mm",
            "where the normal force acts: e = C/N, its distance from the slider's centre "
            "of mass along the slide's direction (NaN where N = 0)",
            dims=(along, "slide"), slides=list(r.slide_names))
    if r.input_names:
        put(g, "input_drive", r.drive[:, :, 0], list(r.drive_units),
            "drive of each input besides the crank: a moment on a rotary input, a force "
            "along the guide of a slider input", dims=(along, "input"),
            inputs=list(r.input_names))
        put(g, "input_share", r.drive[:, :, 1], "N·m",
            "each input's share of M_bal: its drive times dq/dphi1", dims=(along, "input"),
            inputs=list(r.input_names))
    put(g, "body_loads", r.body_loads, ["N", "N", "N·m"],
        "applied and inertia loads reduced to the centre of mass",
        dims=(along, "body", "load_component"), bodies=list(r.body_names))
    if r.residual is not None:
        put(g, "equilibrium_residual", r.residual, "1",
            "relative virtual-power residual: |M_bal omega1 + sum over moving links (F . v_S + "
            "M omega)| / its largest term (0 where every term is 0)", dims=(along,))
    if getattr(r, "friction", None) is not None:
        _friction_curves(g, r, along)
    if r.shaking is not None:
        put(g, "shaking_force", r.shaking[:, :2], "N",
            "shaking force on the frame: the moving links' inertia forces sum(-m a_S) = "
            "-d/dt sum(m v_S), gravity and external loads apart", dims=(along, "axis"))
        put(g, "shaking_force_magnitude", r.shaking_magnitude, "N", "|shaking force| on the frame",
            dims=(along,))
        put(g, "shaking_moment", r.shaking[:, 2], "N·m",
            f"shaking moment on the frame about the crank's pivot {r.shaking_about}: "
            "sum(-J_S eps + (S - O) x (-m a_S)) = -d/dt of the angular momentum about it, "
            "gravity and external loads apart", dims=(along,), about=r.shaking_about)


def _dynamics_case(group, res, motion_forces=None):
    """Datasets of one dynamics case (``solve.crank_motion.CaseResult``) under group/<case
    name> (and the fine tail under .../tail), with its kinetostatics along the motion
    (``solve.motion_forces.case_forces``) under .../forces and .../steady_forces."""
    g = group.create_group(res.name)
    c = res.case
    g.attrs["method"] = res.method
    g.attrs["status"] = STATUS_NAMES[res.status]
    # the motion's own error estimate (crank_motion.integrate) and the step it was run with
    g.attrs["dt_used"] = res.dt
    g.attrs["error_phi1_rad"] = res.error_phi1
    g.attrs["error_omega1_rad_per_s"] = res.error_omega1
    g.attrs["accepted_error_phi1_rad"] = ACCEPTED_ERROR_RAD
    g.attrs["note"] = res.note
    g.attrs["M1"] = c.M1.text
    g.attrs["damping"] = c.damping
    g.attrs["phi_start_deg"] = math.degrees(c.phi_start)
    g.attrs["omega_start"] = c.omega_start
    g.attrs["t_end"] = c.t_end
    g.attrs["dt"] = c.dt
    g.attrs["sample_dt"] = c.sample_dt
    g.attrs["equation"] = "J(phi) phi'' + (1/2) J'(phi) phi'^2 + b phi' = Q(phi) + M1"
    for k, v in res.summary().items():
        if v is not None:
            g.attrs[f"summary_{k}"] = v
    for grp, (t, p, w, e) in ((g, (res.t, res.phi1, res.omega1, res.eps1)),
                              (g.create_group("tail"), (res.tail_t, res.tail_phi1,
                                                        res.tail_omega1, res.tail_eps1))):
        put(grp, "t", t, "s", "time", dims=("t",))
        put(grp, "phi1", np.rad2deg(p), "deg", "crank angle phi1", dims=("t",))
        put(grp, "omega1", w, "rad/s", "crank angular velocity omega1", dims=("t",))
        put(grp, "eps1", e, "rad/s²", "crank angular acceleration eps1", dims=("t",))
    g["tail"].attrs["description"] = "every integration step of the last seconds"
    for rec in (motion_forces or {}).values():
        _motion_forces(g.create_group(MOTION_FORCE_GROUPS[rec.record]), rec)
    return g


# the groups of a dynamics case that hold its kinetostatics along the motion
MOTION_FORCE_GROUPS = {"samples": "forces", "steady": "steady_forces"}


def _motion_forces(g, rec):
    """The kinetostatics along one record of a dynamics case
    (``solve.motion_forces.MotionForces``), along the time."""
    g.attrs["long_name"] = (
        "joint reactions, slide forces and the balancing moment along the crank's actual "
        "motion (omega1(t), eps1(t) of the equation of motion), " + (
            "at every recorded sample of the case" if rec.record == "samples" else
            "at every integration step of the last whole revolutions of the steady rotation"))
    put(g, "t", rec.t, "s", "time", dims=("t",))
    put(g, "phi1", np.rad2deg(rec.phi1), "deg", "crank angle phi1", dims=("t",))
    put(g, "omega1", rec.omega1, "rad/s", "crank angular velocity omega1", dims=("t",))
    put(g, "eps1", rec.eps1, "rad/s²", "crank angular acceleration eps1", dims=("t",))
    put(g, "status", rec.status.astype(STATUS_ENUM), "1", "position status", dims=("t",),
        codes=status_table())
    _reactions(g, rec.forces, along="t")


def _reduced(group, red):
    """The crank's reduced dynamics (``solve.reduced_dynamics.Reduced``) in ``group``."""
    group.attrs["long_name"] = ("reduced dynamics of the crank: J(phi) phi'' + (1/2) "
                                "J'(phi) phi'^2 = Q(phi) + M1, loads at t = 0")
    group.attrs["equilibria_deg"] = [p for p, _ in red.equilibria] or [np.nan]
    group.attrs["equilibria_stable"] = [bool(st) for _, st in red.equilibria] or [False]
    put(group, "phi1", np.degrees(red.phi), "deg", "crank angle phi1", dims=("phi1",))
    put(group, "J", red.J, "kg·m²", "reduced moment of inertia J(phi)", dims=("phi1",))
    put(group, "half_dJ", red.half_dJ, "kg·m²", "(1/2) dJ/dphi", dims=("phi1",))
    put(group, "Q", red.Q, "N·m", "generalised force without M1", dims=("phi1",))


def _counterweight(group, cw):
    """The crank's counterweight (``solve.shaking.Counterweight``) in ``group``."""
    pivot, tip = cw.crank
    group.attrs["long_name"] = ("the point mass on the crank that minimises the peak |shaking "
                                "force| over the dense positions: m_c r_c at the angle from the "
                                f"crank line {pivot}->{tip}")
    put(group, "phi1", np.rad2deg(cw.phi), "deg", "crank angle phi1", dims=("phi1",))
    put(group, "mass_radius", np.float64(cw.mass_radius), "kg·mm",
        "counterweight: its mass times its radius, m_c r_c")
    put(group, "angle", np.float64(cw.angle), "deg",
        f"counterweight: its angle from the crank line {pivot}->{tip}, counter-clockwise")
    for key, value, what in (("peak_before", cw.before, "without"),
                             ("peak_after", cw.after, "with")):
        put(group, key, np.float64(value), "N",
            f"peak |shaking force| over the positions {what} the counterweight")
        put(group, f"{key}_phi1", np.float64(getattr(cw, f"{key[5:]}_phi1")), "deg",
            f"crank angle phi1 of the peak |shaking force| {what} the counterweight")
    put(group, "shaking_force", cw.force_after, "N",
        "shaking force on the frame with the counterweight", dims=("phi1", "axis"))


def _flywheel(group, fw):
    """A dynamics case's flywheel (``solve.flywheel.Flywheel``) in ``group``."""
    group.attrs["long_name"] = ("the moment of inertia to add on the crank shaft for the "
                                f"steady rotation of case {fw.case!r} to have the target "
                                "coefficient of non-uniformity")
    group.attrs["case"] = fw.case
    if fw.refused:             # none sized: why (one line naming the study file and field)
        group.attrs["not_sized"] = fw.refused
        return
    group.attrs["body"] = fw.J_body
    put(group, "J_add", np.float64(fw.J_add), "kg·m²",
        "moment of inertia added on the crank shaft (to the crank body's J_S)")
    for key, what in (("target", "asked for"), ("delta", "with the flywheel"),
                      ("delta_without", "without the flywheel")):
        put(group, key, np.float64(getattr(fw, key)), "1",
            f"coefficient of non-uniformity (omega_max - omega_min) / omega_mean, {what}")
    for key in ("omega_min", "omega_max", "omega_mean"):
        put(group, key, np.float64(getattr(fw, key)), "rad/s",
            f"{key.replace('_', ' ')} of the steady rotation with the flywheel")


# the tolerance vector's entries (kernels.config T_*), named, with their units
TOLERANCES = (("newton_tol", "1"), ("newton_maxiter", "1"), ("newton_step", "rad"),
              ("singular", "1"), ("jump", "rad"), ("substep", "rad"), ("close", "rad"),
              ("assembly_slack", "1"), ("step_change", "rad"), ("min_step", "1"),
              ("first_step", "1"), ("watch", "1"), ("touch", "1"), ("locate", "rad"),
              ("go_on", "1"))


def parameter_units(name) -> str:
    """The unit of a compiled mechanism parameter (angles in the plan are rad)."""
    key = name.rsplit(".", 1)[-1]
    if key in ("x", "y", "length", "offset", "guide_length") or (
            key.startswith("L") and key[1:2] in "0123456789_"):
        return "mm"
    if key in ("angle", "phiM0", "a0", "b0", "phi_start") or key.endswith("angle"):
        return "rad"
    if key in ("start", "stroke"):            # a slider input's law
        return "mm"
    return {"mass": "kg", "J_S": "kg·m²"}.get(key, "1")


def _coordinates(f, plan, study):
    """The file's named dimensions (dimension scales at the root)."""
    coordinate(f, "point", list(plan.point_names[:plan.n_visible]), "1", "point")
    coordinate(f, "axis", ["x", "y"], "1", "component")
    coordinate(f, "link", list(study.output.link_labels), "1", "link")
    coordinate(f, "group", list(plan.group_names), "1", "structural group")
    j = coordinate(f, "joint", list(plan.joint_names), "1", "joint")
    from ..solve.reactions import joint_where     # the bodies each joins and its point
    j.attrs["where"] = np.array(joint_where(plan), dtype=h5py.string_dtype())
    coordinate(f, "slide", list(plan.slide_names), "1", "prismatic pair")
    coordinate(f, "input", list(plan.input_names), "1", "input besides the crank")
    coordinate(f, "body", list(plan.body_names), "1", "body")
    coordinate(f, "load_component", ["Fx", "Fy", "M"], "1", "force x, force y, moment")
    coordinate(f, "slide_component", ["N", "C"], "1", "normal force, couple")
    coordinate(f, "parameter", list(plan.par_names), "1", "compiled mechanism parameter")
    coordinate(f, "tolerance", [n for n, _ in TOLERANCES], "1", "solver tolerance")
    from ..model.mechanism import transmission_items
    coordinate(f, "dyad", [label for label, _, _ in transmission_items(study.mechanism)], "1",
               "transmission angle: a two-link dyad's (A-B-C, at the middle joint B), a class III "
               "lead's (J-P: the lead against the line to the meet of the other two leads), or a "
               "sliding pair's (each group type's: pipeline.model.mechanism.transmission_items)")


PEAK_DIMS = {"velocity": "point", "acceleration": "point", "omega": "link", "eps": "link",
             "reaction": "joint", "slide_normal": "slide", "slide_couple": "slide",
             "min_transmission_angle": "dyad"}


PEAK_WHAT = {"slide_normal": "peak |N| (a slide's normal force)",
             "slide_couple": "peak |C| (a slide's couple)",
             "shaking_force": "peak |shaking force| on the frame",
             "shaking_moment": "peak |shaking moment| on the frame about the crank's pivot"}


def _peaks(g, peaks, output=None):
    """Per quantity: the peak of every point, link or joint, its crank angle
    and the largest grid sample it was refined from."""
    g.attrs["long_name"] = ("peaks over the revolution, refined between the dense positions "
                            "by a bounded 1-D maximiser on the exact kinematics")
    by = {}
    for p in peaks:
        by.setdefault(p.quantity, []).append(p)
    for q, ps in by.items():
        dims = (PEAK_DIMS[q],) if q in PEAK_DIMS else None
        val = np.array([p.value for p in ps]) if dims else np.float64(ps[0].value)
        phi = np.array([p.phi1 for p in ps]) if dims else np.float64(ps[0].phi1)
        grid = np.array([p.grid_value for p in ps]) if dims else np.float64(ps[0].grid_value)
        what = q.replace("_", " ") if q.startswith("min_") else PEAK_WHAT.get(q, f"peak |{q}|")
        d = put(g, q, val, ps[0].unit, what, dims=dims)
        if not dims:
            d.attrs["item"] = ps[0].item     # crank (M_bal), frame (shaking)
        put(g, f"{q}_phi1", phi, "deg", f"crank angle phi1 of the {what}", dims=dims)
        put(g, f"{q}_grid", grid, ps[0].unit, f"{what} among the dense positions only",
            dims=dims)
        if q == "reaction" and output is not None:   # pin sizing from the peak reactions
            from ..solve.reactions import pin_diameter
            pins = output.pins([p.item for p in ps])
            put(g, "pin_length", [ln for ln, _ in pins], "mm", "pin length (in bending)",
                dims=dims)
            put(g, "pin_sigma", [sg for _, sg in pins], "MPa", "allowable bending stress",
                dims=dims)
            put(g, "pin_d_min", [float(pin_diameter(p.value, ln, sg))
                                 for p, (ln, sg) in zip(ps, pins)], "mm",
                "smallest pin diameter: (32 R l / (pi sigma))^(1/3)", dims=dims)


def peaks_table(f):
    """Every stored peak of the open scene file ``f`` as a DataFrame (what
    `pipeline export` writes to peaks.csv and `pipeline compare` reads):
    quantity, item, value, unit, crank angle, the largest grid sample it was
    refined from, and for a joint the pin diameter."""
    import pandas as pd

    from ..solve.reactions import pin_diameter
    g = f["peaks"]
    rows = []
    for q in variables(g):
        if q.endswith(("_phi1", "_grid")) or q.startswith("pin_"):
            continue
        d = g[q]
        unit = str(attr_text(d.attrs.get("units", "")))
        if d.ndim == 0:     # M_bal (the crank), the shaking force and moment (the frame)
            items, vals = [str(attr_text(d.attrs.get("item", "crank")))], [float(d[()])]
            phis, grid = [float(g[f"{q}_phi1"][()])], [float(g[f"{q}_grid"][()])]
        else:
            scale = d.dims[0][0]
            items = [str(attr_text(x)) for x in scale[()]]
            vals, phis, grid = d[()], g[f"{q}_phi1"][()], g[f"{q}_grid"][()]
        dmin = g["pin_d_min"][()] if (q == "reaction" and "pin_d_min" in g) else None
        for n, (it, v, ph, gv) in enumerate(zip(items, vals, phis, grid)):
            d = float("nan")
            if q == "reaction":
                d = float(dmin[n]) if dmin is not None else float(pin_diameter(v))
            rows.append((q, it, float(v), unit, float(ph), float(gv), d))
    df = pd.DataFrame(rows, columns=["quantity", "item", "value", "unit", "phi1", "grid_value",
                                     "d_min"])
    df.attrs["units"] = {"phi1": "deg", "d_min": "mm"}
    return df


def _cyclogram(f, cg):
    """The phase errors of the machine's cyclogram (``solve.cyclogram.Cyclogram``):
    /cyclogram with the boundaries of the output organ's phases as its dimension."""
    from ..solve.cyclogram import BOUNDARIES
    g = f.create_group("cyclogram")
    ring = cg.output_ring
    g.attrs["long_name"] = (f"the machine's cyclogram: where the design's output phases begin "
                            f"against the required phases of {ring.organ} (DOMAIN.md section 9)")
    g.attrs["organ"] = ring.organ
    g.attrs["align"] = cg.align
    g.attrs["turn"] = cg.turn
    g.attrs["description"] = (
        "crank travel tau = rot (phi1 - phi0) in deg, 0 at the first dense position; the "
        "cycle angle psi = tau - turn (align = best: the required dwell turned to start "
        "where the design's does; fixed: turn = -phase)")
    coordinate(g, "boundary", list(BOUNDARIES), "1",
               "boundary of the output's phases: where its dwell, forward and back swing begin")
    put(g, "actual", cg.actual, "deg",
        "crank travel tau where the design's phase begins", dims=("boundary",))
    put(g, "required", cg.required, "deg",
        "crank travel tau where the required phase begins (its cycle angle + turn)",
        dims=("boundary",))
    put(g, "phase_error", cg.error, "deg",
        f"phase error of the design against {ring.organ}'s required phases: actual - required "
        "boundary, in (-180, 180]; positive: the design's phase begins later in the cycle",
        dims=("boundary",))


def _friction_curves(g, r, along):
    """The friction of a scene's positions ([mechanism.friction], ``solve.friction``):
    per joint and slide its friction load, relative speed and loss, per pin its
    bearing pressure, sliding speed and p*v, and M_bal without friction."""
    fr = r.friction
    nj = len(r.joint_names)
    pj = (along, "joint")
    put(g, "friction_status", fr.status.astype(STATUS_ENUM), "1",
        "friction status (FRICTION_LOCK: a self-locking joint or slide, or the friction's "
        "Newton iteration does not converge; its forces NaN)", dims=(along,),
        codes=status_table())
    put(g, "M_bal_frictionless", fr.M_bal_frictionless, "N·m",
        "balancing moment without friction (M_bal is with it)", dims=(along,))
    put(g, "friction_moment", fr.moment, "N·m",
        "friction moment on the joint's second body, f (d/2) |R| against its rotation "
        "relative to the first", dims=pj)
    put(g, "relative_omega_analog", fr.speed_analog[:, :nj], "1",
        "relative angular velocity analog of the joint's second body against its first "
        "(omega_rel / omega1, from the kinematics)", dims=pj)
    put(g, "friction_loss", fr.loss[:, :nj], "W",
        "power lost in the joint: -friction moment x relative angular velocity", dims=pj)
    put(g, "bearing_pressure", fr.pressure, "MPa", "pin bearing pressure p = |R| / (d l)",
        dims=pj)
    put(g, "sliding_speed", fr.sliding_speed, "m/s",
        "sliding speed at the pin's surface v = |omega_rel| d / 2", dims=pj)
    put(g, "pv", fr.pv, "MPa·m/s", "bearing p*v", dims=pj)
    if r.slide.shape[1]:
        ps = (along, "slide")
        put(g, "slide_friction_force", fr.force, "N",
            "friction force on the slider along the slide's direction, f |N| (or f times "
            "the block's two end loads) against its sliding", dims=ps,
            slides=list(r.slide_names))
        put(g, "sliding_analog", fr.speed_analog[:, nj:], "mm/rad",
            "sliding velocity analog of the slider against its guide along the slide's "
            "direction (from the kinematics)", dims=ps, slides=list(r.slide_names))
        put(g, "slide_friction_loss", fr.loss[:, nj:], "W",
            "power lost in the slide: -friction force x relative sliding velocity", dims=ps,
            slides=list(r.slide_names))
    put(g, "friction_loss_total", fr.total_loss, "W", "power lost in every joint and slide",
        dims=(along,))


def _friction_summary(f, res):
    """/friction: the scene's friction over its dense revolution: the data, the mean
    loss and efficiency, each pin's peaks of p, v and p*v and their crank angles."""
    fr = res.dense.forces.friction
    spec = fr.spec
    g = f.create_group("friction")
    g.attrs["long_name"] = ("Coulomb friction in the joints ([mechanism.friction]) over the "
                            "dense revolution at the operating speed")
    g.attrs["status"] = kc.STATUS_NAMES[fr.overall]
    if fr.overall != kc.OK:
        g.attrs["lock_phi1_deg"] = np.degrees(fr.fail_phi)
        g.attrs["lock_element"] = fr.element_names[fr.fail_element] \
            if fr.fail_element >= 0 else ""
    put(g, "revolute_coefficient", np.float64(spec.revolute), "1",
        "Coulomb coefficient at the revolute joints")
    put(g, "slide_coefficient", np.float64(spec.slide), "1",
        "Coulomb coefficient at the prismatic pairs")
    for key, value, unit, what in (("p_max", spec.p_max, "MPa", "allowed bearing pressure"),
                                   ("pv_max", spec.pv_max, "MPa·m/s", "allowed p*v")):
        if value is not None:
            put(g, key, np.float64(value), unit, what)
    put(g, "pin_diameter", np.asarray(spec.diameters(), float), "mm", "pin diameter d",
        dims=("joint",))
    put(g, "pin_length", np.asarray(spec.lengths(), float), "mm", "pin bearing length l",
        dims=("joint",))
    if spec.blocks:
        put(g, "block_length", np.asarray(spec.block_lengths(), float), "mm",
            "block length along its guide (0: not given)", dims=("slide",))
    put(g, "mean_loss", np.float64(fr.mean_loss()), "W",
        "mean power lost in friction over the revolution")
    put(g, "efficiency", np.float64(fr.efficiency()), "1",
        "mean power to the external loads / mean power the drive delivers (NaN: the loads "
        "do no work over a revolution)")
    rows = np.array([b[1:] for b in fr.bearings(res.dense.phi)], float).reshape(-1, 7)
    for c, (key, unit, what) in enumerate((
            ("peak_pressure", "MPa", "peak bearing pressure p (refined between positions)"),
            ("peak_pressure_phi1", "deg", "crank angle phi1 of the peak p"),
            ("peak_sliding_speed", "m/s", "peak sliding speed v (refined between positions)"),
            ("peak_sliding_speed_phi1", "deg", "crank angle phi1 of the peak v"),
            ("peak_pv", "MPa·m/s", "peak p*v (refined between positions)"),
            ("peak_pv_phi1", "deg", "crank angle phi1 of the peak p*v"),
            ("mean_pv", "MPa·m/s", "mean p*v over the revolution"))):
        put(g, key, rows[:, c], unit, what, dims=("joint",))


def write_scene(res, path):
    """Write a scene result; returns the path."""
    path = Path(path)
    with replacing(path) as tmp, hdf5_image(tmp) as f:
        _scene_into(f, res)
    return path


@contextmanager
def scene_in_memory(res):
    """The scene result as an HDF5 file in memory, opened read-only: what a
    command reads back from a scene it solved for itself (``pipeline compare
    --candidate``, the report's comparison) leaves nothing on the disk, so a
    kill leaves nothing behind."""
    buf = io.BytesIO()
    with h5py.File(buf, "w") as f:
        _scene_into(f, res)
    with h5py.File(buf, "r") as f:
        yield f


def _scene_into(f, res):
    """The scene result's groups and attributes, written into the open file ``f``."""
    study = res.study
    plan = res.plan
    write_root_attrs(f, "scene", study, status=kc.STATUS_NAMES[res.status])
    m = f.create_group("mechanism")
    m.attrs["point_names"] = list(plan.point_names[:plan.n_visible])
    m.attrs["link_labels"] = list(study.output.link_labels)
    m.attrs["working_point"] = study.output.working_point
    m.attrs["omega1"] = study.mechanism.crank.omega1
    m.attrs["eps1"] = study.mechanism.crank.eps1
    _coordinates(f, plan, study)
    put(m, "parameters", plan.par, [parameter_units(n) for n in plan.par_names],
        "compiled parameter vector", dims=("parameter",), names=list(plan.par_names))
    put(m, "tolerances", res.tolerances, [u for _, u in TOLERANCES], "solver tolerances",
        dims=("tolerance",))
    for name, curves in (("table", res.table), ("dense", res.dense)):
        _curves(f.create_group(name), res, curves, study)
    if res.dynamics:
        for case in res.dynamics:
            _dynamics_case(f.require_group("dynamics"), case,
                           (res.motion_forces or {}).get(case.name))
    if res.peaks:
        _peaks(f.create_group("peaks"), res.peaks, study.output)
    if res.reduced is not None:
        _reduced(f.create_group("reduced_dynamics"), res.reduced)
    if getattr(res.dense.forces, "friction", None) is not None:
        _friction_summary(f, res)
    if res.counterweight is not None:
        _counterweight(f.create_group("counterweight"), res.counterweight)
    if getattr(res, "flywheel", None) is not None:
        _flywheel(f.create_group("flywheel"), res.flywheel)
    if res.motion:
        g = f.create_group("motion")
        g.attrs["long_name"] = ("the output rocker's dwell and stroke (DOMAIN.md section "
                                "9), and its law error with [output.motion_law]")
        g.attrs["dwell_deg"] = res.motion["dwell_deg"]
        put(g, "dwell_error", np.float64(res.motion["dwell_error"]), "1",
            "dwell error: best window range / revolution range")
        put(g, "dwell_start", np.float64(res.motion["dwell_start"]), "deg",
            "crank angle phi1 where the best dwell window starts")
        put(g, "stroke", np.float64(res.motion["stroke"]), "mm",
            "stroke of the working point: radius x rocker swing")
        if "law_error" in res.motion:      # [output.motion_law]
            from ..model.metric_catalogue import METRICS
            g.attrs["law_align"] = res.motion["law_align"]
            for key in ("law_error", "law_error_max", "law_shift"):
                put(g, key, np.float64(res.motion[key]), METRICS[key][0], METRICS[key][1])
    cg = getattr(res, "cyclogram", None)
    if cg is not None and cg.error is not None:
        _cyclogram(f, cg)
