"""NSGA-II on plain arrays: pymoo's NSGA2, generation for generation and bit
for bit, without its per-design objects.

pymoo keeps a population as an array of ``Individual`` objects and reads
every value through them; at the search's population of 100 its loop takes
about 8 ms a generation where this one takes under 1 ms (benchmarks/
bench_search.py runs both in one process: 9,800 against 36,000 designs/s,
the kernels' 1.2 ms a generation included).  This class runs the same
algorithm on arrays: pymoo's operators (SBX, polynomial mutation), its
non-dominated sorting, crowding distance, randomized argsort and duplicate
elimination, and the same draws from the same random generator in the same
order, so a seed gives the designs pymoo's ``NSGA2`` gives
(``tests/runs/test_search_nsga2.py`` drives both side by side).  The
operators, the crowding distance and the duplicate check run compiled
(``pipeline.kernels.nsga2_ops``: between pymoo's draws, with numpy's own
powers and sums, each tested against pymoo's function); what else is written
again here is the glue pymoo spreads over its population objects: the binary
tournament, the mating loop, the split by feasibility and the
rank-and-crowding survival.

The interface is pymoo's ask and tell on arrays: ``ask()`` returns the designs
to evaluate (the first generation first), ``tell(X, F, G)`` takes the designs
evaluated (those asked, or the first of them) with their objectives and
inequality constraints (g <= 0).
"""

from __future__ import annotations

import math

import numpy as np

from pymoo.algorithms.moo.nsga2 import NSGA2
from pymoo.core.variable import get
from pymoo.operators.crossover.sbx import SimulatedBinaryCrossover
from pymoo.operators.mutation.pm import PolynomialMutation
from pymoo.util.misc import random_permutations
from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting
from pymoo.util.randomized_argsort import randomized_argsort

from ..kernels.nsga2_ops import crowding_distance, pm, sbx, unique_rows


class _Bounds:
    """What pymoo's operators read of a problem: the bounds and the number of
    variables."""

    def __init__(self, xl, xu):
        self.xl = np.asarray(xl, float)
        self.xu = np.asarray(xu, float)
        self.n_var = len(self.xl)


def violation(G) -> np.ndarray:
    """pymoo's constraint violation of rows of inequality constraints: the sum
    of their positive parts (``core.individual.calc_cv``, default settings)."""
    G = np.asarray(G, float)
    # a row's sum is numpy's pairwise sum, as np.sum of the row alone (tested)
    return np.ascontiguousarray(np.maximum(0.0, G - 0.0)).sum(axis=1) + 0.0


class ArrayNSGA2:
    """pymoo's ``NSGA2(pop_size, n_offsprings, sampling=x0, repair=repair)``
    with its default operators, on arrays (see the module's text).

    ``repair(X) -> X`` moves proposals inside what can be built (as pymoo's
    ``Repair._do``); ``seed`` seeds the random generator as ``Algorithm.setup``
    does."""

    def __init__(self, pop_size, n_offsprings, x0, xl, xu, seed, repair=None):
        reference = NSGA2(pop_size=pop_size, n_offsprings=n_offsprings)
        if reference.tournament_type != "comp_by_dom_and_crowding":   # pragma: no cover
            raise RuntimeError(f"pymoo's NSGA2 tournament is {reference.tournament_type!r}; "
                               "ArrayNSGA2 follows 'comp_by_dom_and_crowding'")
        if reference.mating.crossover.n_offsprings != reference.mating.crossover.n_parents:
            raise RuntimeError("ArrayNSGA2 follows a crossover with as many children as "
                               "parents (pymoo's SBX: 2 and 2)")   # pragma: no cover
        if not (isinstance(reference.mating.crossover, SimulatedBinaryCrossover)
                and isinstance(reference.mating.mutation, PolynomialMutation)
                and not reference.mating.mutation.at_least_once):    # pragma: no cover
            raise RuntimeError("ArrayNSGA2 follows pymoo's NSGA2 with SBX and polynomial "
                               "mutation (not at least once)")
        self.crossover = reference.mating.crossover
        self.mutation = reference.mating.mutation
        self.n_max = reference.mating.n_max_iterations
        self.pop_size, self.n_offsprings = pop_size, n_offsprings
        self.problem = _Bounds(xl, xu)
        self.repair = repair if repair is not None else (lambda X: X)
        self.random_state = np.random.default_rng(seed)
        self.nds = NonDominatedSorting()
        self.x0 = np.asarray(x0, float)
        # the population: designs, objectives, constraint violations, crowding distances
        self.X = self.F = self.CV = self.crowd = None

    # ---------------------------------------------------------------- ask
    def ask(self) -> np.ndarray:
        """The next designs to evaluate (empty: the mating found nothing new)."""
        if self.X is None:      # Initialization: the sampling repaired, duplicates removed
            return unique_rows(self.repair(np.array(self.x0)))
        return self._mating()

    def _mating(self):
        off = np.zeros((0, self.problem.n_var))
        n_infills = 0
        while len(off) < self.n_offsprings:
            n_remaining = self.n_offsprings - len(off)
            _off = self._mate(n_remaining)
            _off = self.repair(np.array(_off))
            _off = unique_rows(_off, self.X, off)
            if len(off) + len(_off) > self.n_offsprings:
                _off = _off[:self.n_offsprings - len(off)]
            off = np.concatenate([off, _off])
            n_infills += 1
            if n_infills >= self.n_max:
                break
        return off

    def _mate(self, n_offsprings):
        rs = self.random_state
        cx = self.crossover
        n_matings = math.ceil(n_offsprings / cx.n_offsprings)
        parents = self._tournament(n_matings, cx.n_parents)
        # Crossover.do: X[parent, mating, variable]
        X = np.swapaxes(self.X[parents], 0, 1)
        Xp = np.empty((cx.n_offsprings, n_matings, X.shape[2]))
        cross = rs.random(n_matings) < get(cx.prob, size=n_matings)
        if np.any(cross):
            # SimulatedBinaryCrossover._do, compiled between its draws (kernels.nsga2_ops)
            eta, prob_var, prob_exch, prob_bin = get(cx.eta, cx.prob_var, cx.prob_exch,
                                                     cx.prob_bin, size=(n_matings, 1))
            Q = sbx(X, self.problem.xl, self.problem.xu, eta, prob_var, prob_exch, prob_bin,
                    rs)
            Xp[:, cross] = Q[:, cross]
        Xp[:, ~cross] = X[:, ~cross]     # no crossover: the parents themselves
        off = Xp.reshape(-1, X.shape[-1])
        # Mutation.do
        mu = self.mutation
        # PolynomialMutation._do, compiled between its draws (kernels.nsga2_ops)
        Xm = pm(off, self.problem.xl, self.problem.xu, get(mu.eta, size=len(off)),
                mu.get_prob_var(self.problem, size=len(off)), rs)
        mut = rs.random(size=len(off)) <= get(mu.prob, size=len(off))
        off = off.copy()
        off[mut] = Xm[mut]
        return off

    def _tournament(self, n_select, n_parents, pressure=2):
        """TournamentSelection with NSGA-II's binary_tournament: constraint
        violation first, then domination, then crowding; a tie drawn at
        random, the draws in the tournaments' order."""
        rs = self.random_state
        n_random = n_select * n_parents * pressure
        n_perms = math.ceil(n_random / len(self.X))
        P = random_permutations(n_perms, len(self.X), random_state=rs)[:n_random]
        P = np.reshape(P, (n_select * n_parents, pressure))
        a, b = P[:, 0], P[:, 1]
        cva, cvb = self.CV[a], self.CV[b]
        Fa, Fb = self.F[a], self.F[b]
        a_better = (Fa < Fb).any(axis=1)
        b_better = (Fb < Fa).any(axis=1)
        # the comparison of each tournament, before any draw (-1: drawn at random)
        S = np.full(len(a), -1, dtype=np.int64)
        infeasible = (cva > 0.0) | (cvb > 0.0)
        by_cv = np.where(cva < cvb, a, np.where(cva > cvb, b, -1))
        dom = np.where(a_better & ~b_better, a, np.where(b_better & ~a_better, b, -1))
        ca, cb = self.crowd[a], self.crowd[b]
        by_crowd = np.where(ca > cb, a, np.where(ca < cb, b, -1))
        S[:] = np.where(infeasible, by_cv, np.where(dom >= 0, dom, by_crowd))
        for i in np.flatnonzero(S < 0):
            S[i] = rs.choice([a[i], b[i]])
        return S.reshape(n_select, n_parents)

    # ---------------------------------------------------------------- tell
    def tell(self, X, F, G):
        """The evaluated designs X with their objectives F and constraints G
        (g <= 0)."""
        X, F, CV = np.asarray(X, float), np.asarray(F, float), violation(G)
        if self.X is None:      # the first generation: all of it ranked, none dropped
            self._survive(X, F, CV, len(X))
        else:
            self._survive(np.concatenate([self.X, X]), np.concatenate([self.F, F]),
                          np.concatenate([self.CV, CV]), self.pop_size)

    def _survive(self, X, F, CV, n_survive):
        """Survival.do (split by feasibility) with RankAndCrowding."""
        n_survive = min(n_survive, len(X))
        feasible = np.where(CV <= 0.0)[0]
        infeasible = np.where(~(CV <= 0.0))[0]
        infeasible = infeasible[np.argsort(CV[infeasible])]
        crowd = np.full(len(X), np.nan)
        keep = np.zeros(0, np.int64)
        if len(feasible):
            keep = feasible[self._rank_and_crowding(F[feasible], min(len(feasible), n_survive),
                                                    crowd, feasible)]
        # the places left: the least violating infeasible designs
        keep = np.concatenate([keep, infeasible[:max(n_survive - len(keep), 0)]])
        self.X, self.F, self.CV, self.crowd = X[keep], F[keep], CV[keep], crowd[keep]

    def _rank_and_crowding(self, F, n_survive, crowd, where):
        survivors = []
        fronts = self.nds.do(F.astype(float, copy=False), n_stop_if_ranked=n_survive)
        for front in fronts:
            I = np.arange(len(front))  # noqa: E741
            crowding = crowding_distance(F[front, :])
            if len(survivors) + len(I) > n_survive:
                n_remove = len(survivors) + len(front) - n_survive
                I = randomized_argsort(crowding, order="descending", method="numpy",  # noqa: E741
                                       random_state=self.random_state)
                I = I[:-n_remove]  # noqa: E741
            crowd[where[front]] = crowding
            survivors.extend(front[I])
        return np.asarray(survivors, np.int64)
