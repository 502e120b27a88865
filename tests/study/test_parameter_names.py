"""A parameter's name is the study's (issue 55): the OV-7 studies name their
output arm as DOMAIN.md does, so the tolerance table, the sweep's variables,
the DXF drawing's dimensions and the results files call its length and angle
"output arm.length" and "output arm.angle", never the plan's automatic label of
an unnamed group ("Attach[2]": its type and position, a name no study wrote)."""

import re

import pytest

from pipeline.model.groups.attach import Attach
from pipeline.study.reader import load_study
from pipeline.study.tolerance_spec import ToleranceSpec

from conftest import STUDIES

OV7 = sorted(p.name for p in STUDIES.glob("ov7_*.toml"))
AUTOMATIC = re.compile(r"^Attach\[\d+\]\.")     # model.mechanism.group_label of an unnamed one


def test_the_ov7_studies_are_found():
    assert {"ov7_base.toml", "ov7_synthesis.toml", "ov7_search.toml"} <= set(OV7)


@pytest.mark.parametrize("name", OV7)
def test_no_table_of_an_ov7_study_names_a_parameter_attach(name):
    """The names a user reads: every parameter of the compiled mechanism (the
    results files' and the DXF's), every toleranced dimension and every sweep
    variable's parameter."""
    study = load_study(STUDIES / name)
    plan = study.mechanism.compile()
    names = list(plan.par_names)
    tolerance = study.tolerance or ToleranceSpec()       # none: ISO 2768-f
    names += [d.param for d in tolerance.dimensions(study.mechanism)]
    if study.sweep is not None:
        names += [v.param for v in study.sweep.variables]
    assert [n for n in names if AUTOMATIC.match(n)] == []


@pytest.mark.parametrize("name", OV7)
def test_the_ov7_output_arm_is_named_and_places_an_output_point(name):
    """Each OV-7 study's attach group is its output arm (DOMAIN.md: the eyelet's
    arm on the output rocker, L78/U578 of mechanism B, P8 -> P9 of mechanism A),
    named "output arm", and it places the working point."""
    study = load_study(STUDIES / name)
    arms = [g for g in study.mechanism.groups if isinstance(g, Attach)]
    if not arms:                  # the slider variants of mechanism B have no arm
        pytest.skip(f"{name} has no attach group")
    assert [g.name for g in arms] == ["output arm"]
    assert arms[0].point == study.output.working_point
    plan = study.mechanism.compile()
    assert {"output arm.length", "output arm.angle"} <= set(plan.par_names)
