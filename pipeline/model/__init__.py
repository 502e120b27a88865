"""The model layer: a mechanism declared once (frozen dataclasses,
``mechanism``) and compiled once into the arrays the kernels read (``Plan``);
one module per group type (``groups/``, with its table ``GROUP_TYPES``); the
required motion law (``motion_law``); the catalogue of a sweep's metrics
(``metrics``).

The names of the flat package's ``pipeline.model`` stay importable from here
for one release (``from pipeline.model import Mechanism``); inside the package,
import them from ``pipeline.model.mechanism``.
"""

from .mechanism import (GIDX_WIDTH, PPR, PRP, RPP, RPR, RRP, RRR, Attach, Body,  # noqa: F401
                        CentreOfMass, ClassIII, ClassIIISlider, Crank, Group, GroupType, Law,
                        Load, Mechanism, Plan, RotaryInput, Slide, SliderInput,
                        compile_mechanism, group_label, natural_key)
