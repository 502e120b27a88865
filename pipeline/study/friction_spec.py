"""[mechanism.friction]: Coulomb friction in the joints and the bearings' sizes.

    [mechanism.friction]
    revolute = 0.08                 # Coulomb coefficient at every revolute joint
    slide = 0.10                    # at every prismatic pair
    pin_diameter = 10.0             # mm, every revolute joint's pin ...
    pins = { P2 = 8.0 }             # ... and where one differs (its point or joint: R2)
    pin_length = 12.0               # mm, every pin's bearing length ...
    pin_lengths = { P2 = 10.0 }     # ... and where one differs
    block_length = 40.0             # mm, every slider's length along its guide (optional)
    blocks = { "needle bar" = 30.0 }  # ... per slider body where one differs
    p_max = 25.0                    # MPa: allowed bearing pressure (optional)
    pv_max = 1.5                    # MPa*m/s: allowed p*v (optional)

Without ``block_length`` a slide's friction is f |N| (the couple C is taken by
the block without edge loads).  Read into ``model.friction.Friction``."""

from __future__ import annotations

from ..base import limits as lim
from ..base.errors import StudyError
from ..model.friction import Friction
from .section import Section, _quote


def parse_friction(sec: Section, mech) -> Friction:
    """The friction of the mechanism ``mech`` (its bodies declared: the joints
    and slides are its plan's)."""
    if not mech.bodies:
        raise sec.error("", "friction acts on the joint reactions: declare the mass data "
                            "([[mechanism.bodies]]) for the force analysis")
    plan = mech.compile()
    if plan.n_inputs:
        raise sec.error("", "friction with inputs besides the crank "
                            f"({', '.join(plan.input_names)}) is not computed yet: remove the "
                            "section or the inputs")
    f_rev = sec.number("revolute", within=lim.FRICTION)
    # the coefficient at the slides is required where the mechanism has slides
    f_slide = sec.number("slide", *(() if plan.slide_names else (0.0,)), within=lim.FRICTION)
    joints = list(plan.joint_names)
    points = [plan.point_names[int(i)] for i in plan.joint_point]
    need = () if joints else (10.0,)       # required where the mechanism has joints
    d0 = sec.number("pin_diameter", *need, within=lim.LENGTH)
    l0 = sec.number("pin_length", *need, within=lim.LENGTH)
    diam = _per_joint(sec, "pins", d0, joints, points)
    length = _per_joint(sec, "pin_lengths", l0, joints, points)
    sliders = [mech.bodies[int(q)].name for _, q in plan.slide_bodies]
    b0 = sec.number("block_length", 0.0, within=lim.BLOCK_LENGTH)
    blocks = [b0] * len(sliders)
    if sec.has("blocks"):
        t = sec.table("blocks")
        for key in list(t.data):
            if key not in sliders:
                raise t.error(key, f"no slide has the slider {_quote(key)}; sliders: "
                                   f"{', '.join(map(_quote, sliders)) or 'none'}")
            blocks[sliders.index(key)] = t.number(key, within=lim.LENGTH)
        t.done()
    p_max = sec.number("p_max", within=lim.PRESSURE) if sec.has("p_max") else None
    pv_max = sec.number("pv_max", within=lim.PV) if sec.has("pv_max") else None
    sec.done()
    return Friction(revolute=f_rev, slide=f_slide,
                    pins=tuple(zip(joints, diam, length)),
                    blocks=tuple(zip(plan.slide_names, blocks)), p_max=p_max, pv_max=pv_max)


def _per_joint(sec: Section, key, default, joints, points):
    """Per joint: ``default`` where the table ``key`` does not name it (by its
    point, P2, or its name, R2)."""
    out = [default] * len(joints)
    if not sec.has(key):
        return out
    t = sec.table(key)
    given = {}
    for k in list(t.data):
        if k in points:
            j = points.index(k)
        elif k in joints:
            j = joints.index(k)
        else:
            raise t.error(k, f"no revolute joint at {_quote(k)}; joints: "
                             + ", ".join(f"{p} ({n})" for p, n in zip(points, joints)))
        if j in given:
            raise t.error(k, f"joint {joints[j]} is given twice ({_quote(given[j])} and "
                             f"{_quote(k)})")
        given[j] = k
        out[j] = t.number(k, within=lim.LENGTH)
    t.done()
    return out


# what computes friction today: the paths that do not refuse a study with [mechanism.friction]
WITH_FRICTION = ("friction is computed for scenes (the losses, M_bal with friction, the "
                 "bearings' p and p*v, the crank dynamics and flywheel), sweeps and searches "
                 "(friction_loss, peak_pv)")


def refuse_friction(study, what, source=None, hint="remove the section for a frictionless run"):
    """Refuse a study with [mechanism.friction] on a path whose numbers would be
    frictionless: one line naming the file (``source``, else the study's), the
    field, ``what`` would be frictionless and what computes friction."""
    if study.mechanism.friction is None:
        return
    raise StudyError(source or study.path, "mechanism.friction",
                     f"{what} frictionless (friction is not computed there yet): {WITH_FRICTION}; "
                     f"{hint}")
