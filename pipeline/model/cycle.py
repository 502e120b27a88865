"""The machine's cyclogram ([cycle] of a study): the required phases of the
machine's organs against the cycle angle psi of the main shaft (degrees, one
turn), DOMAIN.md section 9.

The OV-7 warp-knitting machine's organs, as the thesis's cyclogram table gives
them: the needle rises 0-100, dwells 100-160, rises 160-200, falls 200-360;
the sinker moves 0-20, 20-70, dwells 70-190, moves 190-220, 220-310, 310-360;
the presser moves 0-50, dwells 50-180, moves 180-290, 290-360; the eyelets
(the organ the eyelet-needle mechanism's output rocker drives) dwell 240 -> 30,
swing forward 30 -> 130 and back 130 -> 240.

Every organ's phases are contiguous round the turn and make one turn exactly
(each angle of the cycle lies in one phase).  The organ the mechanism's output
drives (``Cycle.output``) is compared with the design: its phases are one
dwell, one forward and one back swing, in that order round the turn, the
shape of the design's own phases (``pipeline.solve.cyclogram``)."""

from __future__ import annotations

from dataclasses import dataclass

# what an organ does in a phase; the output organ's phases are OUTPUT_KINDS
KINDS = ("dwell", "move", "rise", "fall", "forward", "back")
OUTPUT_KINDS = ("dwell", "forward", "back")
ALIGN = ("best", "fixed")


@dataclass(frozen=True)
class OrganPhase:
    kind: str           # one of KINDS
    start: float        # deg, cycle angle in [0, 360)
    length: float       # deg, > 0

    @property
    def end(self):
        return (self.start + self.length) % 360.0


@dataclass(frozen=True)
class Organ:
    name: str
    phases: tuple       # OrganPhase, contiguous round the turn, 360 deg in all


@dataclass(frozen=True)
class Cycle:
    organs: tuple = ()          # Organ, as declared (the cyclogram's rings, inside out)
    output: str = ""            # the organ the mechanism's output drives ("" if none)
    align: str = "best"         # the cycle turned so that the dwells start together
    phase: float = 0.0          # deg, align = "fixed": the cycle angle at phi1 = phi0

    def organ(self, name):
        return next((o for o in self.organs if o.name == name), None)


def output_shaped(kinds) -> bool:
    """Whether phases of ``kinds`` (in order round the turn) are one dwell, one
    forward and one back swing in that order: the shape of a design's phases."""
    kinds = list(kinds)
    if sorted(kinds) != sorted(OUTPUT_KINDS):
        return False
    k = kinds.index("dwell")
    return kinds[k:] + kinds[:k] == list(OUTPUT_KINDS)
