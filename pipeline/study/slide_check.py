"""A declared slide (``[[mechanism.slides]]``) against the guide of the group
whose sliding pair it is (``check_slide``): the groups' sliding pairs and the
directions their geometry makes equal come from each group type's hooks
(``guides``, ``same_directions``, ``carried``: ``pipeline.model.groups``)."""

from __future__ import annotations

import math
from dataclasses import replace

from ..model.group_base import along_words as _along_words, deg as _deg
from ..model.mechanism import group_label

SLIDE_ANGLE_TOL = math.radians(1e-3)   # rad: two lines closer than 0.001 deg are one


def _guides(groups, fixed):
    """The sliding pairs the groups define: (who, point, (link, angle), host,
    words, params).  The slider carries ``point``; the guide's direction is
    the link a->b turned by angle, or the absolute angle (link None); host:
    the points the guide's body carries (None: the ground); params: the
    group's parameters (plan names) whose sum is that angle."""
    out = []
    for k, g in enumerate(groups):
        kind = type(g).__name__
        who = (f"the {kind} group {g.name!r}" if g.name
               else f"the {kind} group mechanism.groups[{k}]")
        label = group_label(g, k + 1)
        for point, direction, host, words, keys in g.guides(fixed):
            out.append((who, point, direction, host, words,
                        tuple(f"{label}.{key}" for key in keys)))
    return out


def _same_directions(groups):
    """{(a, b): (link, angle)}: the direction a->b is that of ``link`` turned
    by ``angle`` (the absolute angle where link is None), modulo 180 deg, by
    the groups' own geometry: an attached point, a coulisse without offset
    (pivot->block along its guide), a guide's point and the point sliding on
    it without offset (the slider dyads), the yoke's point and the block in its
    slot without offset."""
    same = {}
    for g in groups:
        for pair, direction in g.same_directions():
            same.setdefault(pair, direction)
    return same


def _reduce(direction, same, fixed):
    """A direction (link, angle) rewritten through ``same`` and the fixed
    points until its link is none (absolute) or one nothing rewrites; the
    link's ends in name order (the angle turned by 180 deg if swapped)."""
    link, angle = direction
    for _ in range(64):
        if link is None:
            return None, angle
        a, b = link
        if a in fixed and b in fixed:
            dx, dy = fixed[b][0] - fixed[a][0], fixed[b][1] - fixed[a][1]
            if dx or dy:
                return None, angle + math.atan2(dy, dx)
        if (a, b) in same:
            link, turn = same[(a, b)]
        elif (b, a) in same:
            link, turn = same[(b, a)]
            turn += math.pi
        else:
            break
        angle += turn
    return (tuple(link), angle) if link[0] <= link[1] else ((link[1], link[0]), angle + math.pi)


def _carries(body, groups):
    """The points a body is declared to carry: its joints, its centre of mass's
    base and along link, what it turns with, and the points attached to those
    (attach groups, a coulisse's guide end)."""
    pts = set(body.joints) | {body.com.base}
    pts |= set(body.com.along or ()) | set(body.turns_with or ())
    for g in groups:
        pts.update(g.carried(pts))
    return pts


def check_slide(s, slide, groups, bodies, fixed):
    """Refuse a slide whose direction contradicts the guide of the group whose
    sliding pair it is (its forces would be silently wrong).

    The pair: the slider body has the group's sliding point among its joints
    (or as its centre of mass's base), and the slide's guide is the ground for
    a guide of fixed direction through a fixed point, else a body that carries
    the guide's link (or its point).  Only one pair may match (or all matches
    agree); an ambiguous slide is not checked.  Both directions are reduced
    through the groups' geometry (``_same_directions``) and the fixed points;
    it is an error when

    * they come down to the same link (or both to absolute angles) and differ
      by more than 0.001 deg modulo 180 deg (``.angle``);
    * the slide follows a link that neither the slider nor its guide carries
      (``.along``);
    * the guide turns with a link, the slide's guide body turns (it declares
      turns_with or a centre of mass along a link), and the slide gives a fixed
      angle (``.along``).

    Anything else (e.g. another link of the guide's own body) is not flagged:
    its angle to the guide's link is not known before the kinematics.

    Returns the slide, following the guide's angle parameters (``follows``)
    where it is written along the guide's own link (or both are absolute):
    a sweep that turns the guide turns the slide with it."""
    by_name = {b.name: b for b in bodies}
    slider = by_name[slide.slider]
    guide = by_name[slide.guide] if slide.guide else None
    guide_pts = _carries(guide, groups) if guide else None
    same = _same_directions(groups)
    matches = []
    for who, point, direction, host, words, params in _guides(groups, fixed):
        if point not in slider.joints and point != slider.com.base:
            continue
        if (host is None) != (guide is None) or (host and not set(host) <= guide_pts):
            continue
        matches.append((who, point, _reduce(direction, same, fixed), words, direction, params))
    if not matches:
        return slide
    (who, point, (glink, gangle), words, direction, params) = matches[0]
    for m in matches[1:]:
        if m[2][0] != glink or abs(math.sin(m[2][1] - gangle)) > math.sin(SLIDE_ANGLE_TOL):
            return slide    # ambiguous: the slider carries the sliding point of two pairs
    slink, sangle = _reduce((slide.along, slide.angle), same, fixed)
    says = _along_words(slide.along, slide.angle) if slide.along else _deg(slide.angle)
    guide_words = f"{who} guides {point} {words}"
    if slink == glink:
        if abs(math.sin(sangle - gangle)) > math.sin(SLIDE_ANGLE_TOL):
            raise s.error("angle", f"{guide_words}; this slide says {says} (lines "
                                   f"{_fold_deg(sangle - gangle):.4g} deg apart: the slide's "
                                   "normal force would be taken across the wrong line)")
        if params and slide.along == direction[0]:
            # written along the guide's own link (or both absolute): the slide turns with
            # the guide's parameters when a sweep varies them
            return replace(slide, follows=params, follows_declared=direction[1])
        return slide
    if slide.along and not (set(slide.along) <= fixed.keys()):
        pts = _carries(slider, groups) | (guide_pts or set(fixed))
        if not set(slide.along) <= pts:
            a, b = slide.along
            raise s.error("along", f"this slide follows {a}->{b}, a link of neither the slider "
                                   f"{slide.slider!r} nor its guide "
                                   f"{slide.guide or 'ground'!r}; {guide_words}")
    if slink is None and glink is not None and guide is not None and \
            (guide.turns_with or guide.com.along):
        raise s.error("along", f"{guide_words}, turning with its body {guide.name!r}; this "
                               f"slide gives the fixed direction {_deg(slide.angle)} (give "
                               "along = [a, b], a link of the guide's body, and the angle "
                               "from it)")
    return slide


def _fold_deg(angle):
    """The angle between two lines that differ by ``angle``, in [0, 90] deg."""
    return math.degrees(math.atan2(abs(math.sin(angle)), abs(math.cos(angle))))
