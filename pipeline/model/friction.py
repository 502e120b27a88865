"""Coulomb friction in the joints of a mechanism ([mechanism.friction]).

At a revolute joint of pin diameter d the friction is a moment f_r (d/2) |R|
opposing the relative rotation of the two bodies (the friction circle); at a
prismatic pair it is a force f_s |N| along the guide opposing the relative
sliding, acting on the line of the guide through the slider's centre of mass.
A block of length l that bears on its guide at its two ends l apart carries
N/2 -+ 1000 C/l there (``solve.reactions.slide_action``): its friction is
f_s (|N/2 - 1000 C/l| + |N/2 + 1000 C/l|) = f_s max(|N|, 2000 |C| / l), more
than f_s |N| where the couple C wedges the block between the guide's faces.

At a relative speed of exactly zero (two bodies that turn together at this
position, a dwell, a crank at rest) the friction is taken as zero: the joint
sticks there and carries no friction loss.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Friction:
    """The friction coefficients and the bearings' sizes, per joint and slide
    in the compiled plan's order (``Plan.joint_names``, ``Plan.slide_names``)."""
    revolute: float                 # Coulomb coefficient at revolute joints
    slide: float                    # Coulomb coefficient at prismatic pairs
    pins: tuple = ()                # (joint name, pin diameter mm, pin length mm) per joint
    blocks: tuple = ()              # (slide name, block length mm, 0: no length) per slide
    p_max: float | None = None      # MPa: allowed bearing pressure
    pv_max: float | None = None     # MPa*m/s: allowed p*v

    def diameters(self):
        return tuple(d for _, d, _ in self.pins)

    def lengths(self):
        return tuple(length for _, _, length in self.pins)

    def block_lengths(self):
        return tuple(length for _, length in self.blocks)
