"""The [search] section of a sweep study: an adaptive multi-objective search
(pymoo) over the [sweep] section's design variables, in place of or after the
Monte-Carlo draws.

    [search]
    method = "nsga2"        # nsga2 | smsemoa | agemoea
    population = 100        # designs per generation (the first one: Sobol draws)
    evaluations = 20000     # or: generations = 199 (after the first population)
    seed = 1                # default: the [sweep] seed
    offspring = 100         # designs proposed per generation (default: population)

Everything else (variables and bounds, objectives, constraints, the feasibility
rule, positions, mass model) is the [sweep] section's, so the search and the
Monte-Carlo sweep of one study answer the same question.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..base.limits import CANDIDATES_WHY, MAX_CANDIDATES, MAX_POPULATION, POPULATION_WHY

# how a search measures its feasible front: the hypervolume of the objectives divided by the
# study's reference design's, against this reference point (the runs compute it, the results
# file records both)
HV_REFERENCE = 1.1        # reference point of the hypervolume, in every normalised objective
NORMALISATION = ("each objective divided by the study's reference design's (1 where that is "
                 "not a positive number); reference point 1.1 in every objective")

# method name -> (pymoo module, class): established optimizers, pymoo's default operators
METHODS = {
    "nsga2": ("pymoo.algorithms.moo.nsga2", "NSGA2"),
    "smsemoa": ("pymoo.algorithms.moo.sms", "SMSEMOA"),
    "agemoea": ("pymoo.algorithms.moo.age", "AGEMOEA"),
}


@dataclass(frozen=True)
class SearchSpec:
    method: str
    population: int      # size of the first generation and of the surviving population
    offspring: int       # designs proposed (and evaluated) per later generation
    generations: int     # generations after the first
    seed: int

    @property
    def evaluations(self):
        """Designs evaluated by a complete run (if every generation is full)."""
        return self.population + self.generations * self.offspring

    def sizes(self):
        """Designs per generation, generation 0 first."""
        return [self.population] + [self.offspring] * self.generations


def parse_search(root, sweep) -> SearchSpec:
    """Read [search] of a sweep study (``root`` is the study's top Section,
    ``sweep`` its parsed SweepSpec)."""
    sec = root.table("search")
    method = sec.string("method", "nsga2", choices=tuple(METHODS))
    population = sec.integer("population", 100, minimum=2, maximum=MAX_POPULATION,
                             why=POPULATION_WHY)
    offspring = sec.integer("offspring", population, minimum=1, maximum=MAX_POPULATION,
                            why=POPULATION_WHY)
    if sec.has("generations") and sec.has("evaluations"):
        raise sec.error("evaluations", "give generations or evaluations, not both")
    if sec.has("generations"):
        generations = sec.integer("generations", minimum=1)
    elif sec.has("evaluations"):
        evaluations = sec.integer("evaluations", minimum=1)
        if evaluations < population + offspring:
            raise sec.error("evaluations", f"at least population + offspring = "
                                           f"{population + offspring:,} (the first generation "
                                           f"and one more), got {evaluations:,}")
        # whole generations: rounded up
        generations = math.ceil((evaluations - population) / offspring)
    else:
        raise sec.error("", "give the search's length: generations (after the first "
                            "population) or evaluations (designs evaluated in all)")
    seed = sec.integer("seed", sweep.seed, minimum=0)
    sec.done()
    spec = SearchSpec(method=method, population=population, offspring=offspring,
                      generations=generations, seed=seed)
    if spec.evaluations > MAX_CANDIDATES:
        raise sec.error("generations" if sec.has("generations") else "evaluations",
                        f"{spec.evaluations:,} evaluations in all; at most {MAX_CANDIDATES:,} "
                        f"({CANDIDATES_WHY})")
    return spec
