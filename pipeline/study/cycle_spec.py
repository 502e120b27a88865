"""[cycle]: the machine's cyclogram, the required phases of its organs
(``pipeline.model.cycle``), read with errors that name the file, the field and
the reason::

    [cycle]
    output = "eyelet"          # the organ the mechanism's output drives
    [[cycle.organs]]
    name = "eyelet"
    phases = [{ from = 240, to = 30, kind = "dwell" },
              { from = 30, to = 130, kind = "forward" },
              { from = 130, to = 240, kind = "back" }]
    [[cycle.organs]]
    name = "needle"
    phases = [{ from = 0, to = 100, kind = "rise" }, ...]
"""

from __future__ import annotations

from ..base.limits import ANGLE
from ..model.cycle import ALIGN, KINDS, OUTPUT_KINDS, Cycle, Organ, OrganPhase, output_shaped
from ..model.motion_law import check_turn
from .section import _closest, _quote

MAX_ORGANS = 8          # rings of one cyclogram: more are unreadable on one page
MAX_PHASES = 24         # phases of one organ (the thesis's busiest organ has 6)


def parse_cycle(sec, output) -> Cycle:
    """[cycle] (``sec``: a ``Section``); ``output``: the study's OutputSpec (its
    motion law may already state the output organ's phases)."""
    items = sec.tables("organs")
    if not items:
        raise sec.error("organs", "at least one organ is needed")
    if len(items) > MAX_ORGANS:
        raise sec.error("organs", f"at most {MAX_ORGANS} organs (rings of one cyclogram), "
                                  f"got {len(items)}")
    organs, where = [], {}
    for it in items:
        name = it.name("name")
        if name in where:
            raise it.error("name", f"organ {_quote(name)} is declared twice (first at "
                                   f"{where[name]})")
        where[name] = it.path("name")
        organs.append(Organ(name, _phases(it)))
        it.done()
    law = getattr(output, "motion_law", None)
    law_phases = bool(getattr(law, "phases", ()))
    out = sec.name("output", "")
    if out and out in where:    # (declared here, its phases are the cyclogram's, law or not)
        organ = organs[[o.name for o in organs].index(out)]
        if not output_shaped(p.kind for p in organ.phases):
            raise sec.error("output", f"organ {_quote(out)} is compared with the design's "
                                      f"phases: give it one each of {', '.join(OUTPUT_KINDS)}, "
                                      "in that order round the turn")
    elif out and not law_phases:
        near = _closest(out, where)
        raise sec.error("output", f"no organ named {_quote(out)}" + (
            f"; did you mean {_quote(near)}?" if near else
            f" (declared: {', '.join(map(_quote, where))})"))
    given = [k for k in ("align", "phase") if sec.has(k)]
    if law_phases and given and out not in where:
        raise sec.error(given[0], "[output.motion_law] places the cycle (its align and "
                                  "phase): give them there")
    align = sec.string("align", "best", choices=ALIGN)
    phase = sec.number("phase", 0.0, within=ANGLE)
    sec.done()
    return Cycle(organs=tuple(organs), output=out, align=align, phase=phase)


def _phases(it):
    """An organ's phases: contiguous round the turn, one turn in all."""
    items = it.tables("phases")
    if not items:
        raise it.error("phases", "at least one phase is needed")
    if len(items) > MAX_PHASES:
        raise it.error("phases", f"at most {MAX_PHASES} phases, got {len(items)}")
    raw = []
    for p in items:
        start = p.number("from", within=ANGLE)
        end = p.number("to", within=ANGLE)
        kind = p.string("kind", choices=KINDS)
        length = (end - start) % 360.0
        if not length > 0.0 and len(items) > 1:
            raise p.error("to", f"the phase {start:g} -> {end:g} deg is empty")
        p.done()
        raw.append((p, start % 360.0, length or 360.0, kind))
    check_turn(it, [r[:3] for r in raw])
    return tuple(OrganPhase(kind, start, length) for _, start, length, kind in raw)
