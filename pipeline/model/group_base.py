"""The base of a group type: the hooks every type of ``[[mechanism.groups]]``
answers (pymoo-style: one base class, a folder per type, one name-to-class
table derived from them in ``pipeline.model.groups``).

The structural groups (Assur groups) are each a folder of
``pipeline.group_types``; the attached points and the inputs, the mechanism's
own elements, are modules of ``pipeline.model.groups``.  A group type is the
frozen dataclass of the declared group (its fields are the model's, angles in
rad) and, as class attributes and methods, everything the package needs to
know about that type:

* ``TYPE``: the study's ``type``; ``SOLVES`` (``SOLVES_LISTS``): the study
  keys that name (list) the points it solves (for the parser's "solved later");
* ``parse``: its study fields and their errors (``Fields`` gives the shared
  helpers: a known point, a link, a point defined here, the assembly mode);
* ``reads``/``writes``: the points it needs and the points it solves;
* ``plan_row``: its row of the compiled plan (group code, point indices,
  parameters; the compiler picks the row's emitter by its code);
* ``input_row``: for an input besides the crank, its entry of the plan's inputs;
* ``transmission``: its transmission angle items (``pipeline.solve.peaks``);
* ``segments``: the links drawn for it (``pipeline.views.plots``);
* ``guides``, ``same_directions``, ``carried``: its sliding pairs and the
  geometry the study's slide check reduces directions through.

Nothing here imports the model, the study reader or the compiler: they import
this package.
"""

from __future__ import annotations

import math

PARALLEL_SIN = 1e-9     # |sin| of the angle between two guides below this: parallel
HALF = 0.5 * math.pi


def deg(angle):
    return f"{math.degrees(angle):g} deg"


def along_words(link, angle):
    return f"along {link[0]}->{link[1]} + {deg(angle)}" if link else f"at {deg(angle)}"


def guide_words(link, angle):
    """A guide's direction in a message: along a link, or absolute."""
    return along_words(link, angle) + ("" if link else " (absolute)")


def host(point, link, fixed):
    """The points a guide's body carries: its link, else its point (None: the
    ground, a guide of fixed direction through a fixed point)."""
    return link if link else (None if point in fixed else (point,))


def link_points(pt, link):
    """Point indices of an optional link (-1, -1 for none)."""
    return (pt(link[0]), pt(link[1])) if link else (-1, -1)


class GroupType:
    """The hooks of a group type (see the module docstring); the defaults are
    those of a group without sliding pairs, inputs or drawn links."""
    TYPE = ""               # the study's `type`
    SOLVES = ()             # study keys naming the points it solves
    SOLVES_LISTS = ()       # study keys listing points it solves

    @classmethod
    def parse(cls, g, f, name):
        """The group from its study table ``g`` (a ``pipeline.study.section.Section``),
        ``f`` the parser's ``Fields``, ``name`` the group's name ("" if none)."""
        raise NotImplementedError

    def reads(self):
        raise NotImplementedError

    def writes(self):
        raise NotImplementedError

    def plan_row(self, pt):
        """(group code, point indices, [(key, value)]) of the plan; ``pt``
        gives a point's index (a new one for a point solved here)."""
        raise NotImplementedError

    def input_row(self, pt):
        """(input kind, law code, point indices) for an input besides the crank."""
        return None

    def driven_body(self, mech):
        """The body an input's drive acts on (-1: none)."""
        return -1

    def transmission(self):
        """(label, kind, data) items of ``pipeline.model.mechanism.transmission_items``."""
        return []

    def segments(self):
        """(a, b) point-name pairs drawn for the group."""
        return []

    def guides(self, fixed):
        """Its sliding pairs: (point, (link, angle), host, words, keys): the
        slider carries ``point``; the guide runs along ``link`` turned by
        ``angle`` (absolute where link is None); host: the points the guide's
        body carries (None: the ground); keys: its parameters whose sum is
        that angle."""
        return []

    def same_directions(self):
        """[((a, b), (link, angle))]: a->b runs along ``link`` turned by
        ``angle`` (modulo 180 deg), by the group's geometry."""
        return []

    def carried(self, pts):
        """Points a body carrying ``pts`` carries through this group."""
        return ()
