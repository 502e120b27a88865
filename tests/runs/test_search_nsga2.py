"""ArrayNSGA2 against pymoo's NSGA2, driven side by side by ask and tell: the
same seed must give the same designs, generation for generation, bit for bit.

The test problem is made to reach every branch of the algorithm: infeasible
designs (ties in constraint violation among the 'failed' ones), objectives on a
coarse grid (ties in domination and crowding, infinite crowding at the ends of
fronts), a repair, duplicates (a variable whose bounds are equal, so that
crossover and mutation often leave a design unchanged), odd and uneven
offspring counts and a population smaller than the offspring."""

from __future__ import annotations

import numpy as np
import pytest
from pymoo.algorithms.moo.nsga2 import NSGA2
from pymoo.core.problem import Problem
from pymoo.core.repair import Repair
from pymoo.core.termination import NoTermination
from pymoo.problems.static import StaticProblem

from pipeline.runs.nsga2 import ArrayNSGA2, violation

XL = np.array([0.0, 0.0, 0.5, 2.0, -1.0])
XU = np.array([1.0, 1.0, 0.5, 5.0, 1.0])    # x2: equal bounds


def evaluate(X, infeasible=False):
    """Two objectives rounded to a grid, three constraints, failures (with
    ``infeasible``: no design meets the constraints, violations tied often)."""
    f1 = X[:, 0] + 0.1 * X[:, 4] ** 2
    g = 1.0 + 9.0 * X[:, 1] / 1.0 + (X[:, 3] - 3.5) ** 2
    f2 = g * (1.0 - np.sqrt(np.clip(f1 / g, 0, None)))
    F = np.round(np.stack([f1, f2], axis=1), 1)
    failed = X[:, 4] > 0.7
    G = np.stack([X[:, 0] + X[:, 1] - 1.6,                      # a real constraint
                  np.round(0.3 - X[:, 3] / 10, 2),               # ties in violation
                  np.where(failed, 1e12, 0.0)], axis=1)          # 'evaluable'
    F[failed] = 1e12
    if infeasible:
        G[:, 1] = np.round(X[:, 3], 0)
    return F, G


def repair(X):
    X = np.array(X, float)
    bad = X[:, 0] + X[:, 1] > 1.8
    X[bad, :2] = 0.5 + 0.9 * (X[bad, :2] - 0.5)
    return X


class _Repair(Repair):
    def _do(self, problem, X, **kwargs):
        return repair(X)


class _Box(Problem):
    def __init__(self, xl=XL, xu=XU):
        super().__init__(n_var=len(xl), n_obj=2, n_ieq_constr=3, xl=xl, xu=xu)


def first_generation(n, seed):
    rng = np.random.default_rng(seed + 100)
    x = XL + rng.random((n, len(XL))) * (XU - XL)
    x[::7] = x[1::7][: len(x[::7])] if n > 7 else x[::7]     # duplicates in the first one
    return x


def pymoo_run(pop, off, seed, generations, x0, infeasible=False, xl=XL, xu=XU):
    alg = NSGA2(pop_size=pop, n_offsprings=off, sampling=x0, repair=_Repair())
    box = _Box(xl, xu)
    alg.setup(box, termination=NoTermination(), seed=seed, verbose=False, progress=False)
    out = []
    for _ in range(generations):
        p = alg.ask()
        if p is None or len(p) == 0:
            break
        X = p.get("X")
        F, G = evaluate(X, infeasible)
        alg.evaluator.eval(StaticProblem(box, F=F, G=G), p)
        alg.tell(infills=p)
        out.append((X, alg.pop.get("X")))
    return out


def array_run(pop, off, seed, generations, x0, infeasible=False, xl=XL, xu=XU):
    alg = ArrayNSGA2(pop, off, x0, xl, xu, seed, repair=repair)
    out = []
    for _ in range(generations):
        X = alg.ask()
        if len(X) == 0:
            break
        alg.tell(X, *evaluate(X, infeasible))
        out.append((X, alg.X))
    return out


@pytest.mark.parametrize("pop, off, seed", [(20, 20, 1), (30, 7, 2), (12, 40, 3), (25, 25, 9)])
def test_the_same_designs_as_pymoo_generation_for_generation(pop, off, seed):
    x0 = first_generation(pop, seed)
    want = pymoo_run(pop, off, seed, 40, x0)
    got = array_run(pop, off, seed, 40, x0)
    assert len(got) == len(want) == 40
    for gen, ((xw, pw), (xg, pg)) in enumerate(zip(want, got)):
        assert xw.shape == xg.shape and np.array_equal(xw, xg), f"generation {gen}: asked"
        assert np.array_equal(pw, pg), f"generation {gen}: survivors"


class _Counting:
    """A random generator that counts which draws are made."""

    def __init__(self, rng):
        self.rng, self.calls = rng, {}

    def __getattr__(self, name):
        f = getattr(self.rng, name)

        def counted(*a, **k):
            self.calls[name] = self.calls.get(name, 0) + 1
            return f(*a, **k)
        return counted


def test_no_feasible_design_at_all_as_pymoo():
    """Survival of infeasible designs only (sorted by violation, ties in it)."""
    x0 = first_generation(20, 4)
    want = pymoo_run(20, 20, 4, 15, x0, infeasible=True)
    got = array_run(20, 20, 4, 15, x0, infeasible=True)
    assert len(got) == len(want) == 15
    for (xw, pw), (xg, pg) in zip(want, got):
        assert np.array_equal(xw, xg) and np.array_equal(pw, pg)
    assert (violation(evaluate(got[-1][1], True)[1]) > 0).all()


def test_a_mating_that_finds_nothing_new_ends_as_pymoo():
    """A box of no width: every offspring is a duplicate, the mating gives up
    after pymoo's 100 tries and the algorithm asks for nothing, at the same
    generation in both."""
    lo = np.array([0.5, 0.25, 0.5, 3.0, 0.0])
    x0 = np.repeat(lo[None, :], 6, axis=0)
    want = pymoo_run(6, 6, 5, 5, x0, xl=lo, xu=lo)
    got = array_run(6, 6, 5, 5, x0, xl=lo, xu=lo)
    assert len(got) == len(want) == 1           # the first generation (one design), then none
    assert np.array_equal(got[0][0], want[0][0]) and len(got[0][0]) == 1


def test_the_test_problem_reaches_every_branch(monkeypatch):
    """Ties drawn at random (tournaments), fronts split by randomized crowding
    order, infeasible and failed designs among the survivors and duplicates
    removed all occur in such a run (or the comparison above would prove less)."""
    pop, off = 30, 7
    alg = ArrayNSGA2(pop, off, first_generation(pop, 2), XL, XU, 2, repair=repair)
    alg.random_state = rng = _Counting(alg.random_state)
    import pipeline.runs.nsga2 as mod
    real, removed = mod.unique_rows, []

    def counting(x, *others):
        kept = real(x, *others)
        removed.append(len(x) - len(kept))
        return kept
    monkeypatch.setattr(mod, "unique_rows", counting)
    splits = []
    real_sort = mod.randomized_argsort
    monkeypatch.setattr(mod, "randomized_argsort",
                        lambda *a, **k: splits.append(1) or real_sort(*a, **k))
    infeasible_survivors = 0
    for _ in range(40):
        X = alg.ask()
        alg.tell(X, *evaluate(X))
        infeasible_survivors += int((alg.CV > 0).sum())
    assert rng.calls["choice"] > 20                 # ties in violation, domination, crowding
    assert len(splits) > 20                         # a front cut by crowding order
    assert infeasible_survivors > 0 and sum(removed) > 0
    assert removed[0] > 0                           # duplicates in the first generation


@pytest.mark.parametrize("width", [0, 1, 3, 4, 8, 9, 17])
def test_violation_is_pymoo_s(width):
    """Bit for bit, over magnitudes from 1e-5 to 1e12 (the sum's rounding
    depends on its order: numpy's pairwise sum of a row)."""
    from pymoo.core.individual import calc_cv
    rng = np.random.default_rng(width)
    G = rng.normal(size=(500, width)) * 10.0 ** rng.integers(-5, 13, size=(500, width))
    assert np.array_equal(violation(G), np.array([calc_cv(G=g) for g in G]).ravel())


# ----------------------------------------------------------------- the compiled steps
def test_crowding_distance_is_pymoo_s():
    """kernels.nsga2_ops.crowding_distance against pymoo's 'cd' crowding, bit for
    bit: fronts of 1 to 60 points, 1 to 9 objectives, objectives on coarse grids
    (ties, equal columns: a range of 0), spread over magnitudes, infinities."""
    from pymoo.operators.survival.rank_and_crowding.metrics import get_crowding_function

    from pipeline.kernels.nsga2_ops import crowding_distance
    cd = get_crowding_function("cd")
    rng = np.random.default_rng(4)
    checked = ties = 0
    for trial in range(400):
        # up to 9 objectives: numpy sums a row of 8 or more pairwise
        n, m = int(rng.integers(1, 60)), int(rng.integers(1, 4) if trial % 4 else rng.integers(4, 10))
        F = rng.normal(size=(n, m)) * 10.0 ** rng.integers(-3, 4, size=m)
        if trial % 3 == 0:
            F = np.round(F, 0)                       # ties within a column
        if trial % 7 == 0:
            F[:, 0] = 1.5                            # a column of one value
        if trial % 11 == 0 and n > 3:
            F[1, -1] = np.inf
        want = cd.do(F, n_remove=0)
        got = crowding_distance(np.array(F, dtype=np.double))
        assert got.tobytes() == want.tobytes(), (trial, got, want)
        checked += 1
        ties += len(np.unique(F[:, 0])) < n
    assert checked == 400 and ties > 50


def test_unique_rows_is_pymoo_s():
    """kernels.nsga2_ops.unique_rows against pymoo's DefaultDuplicateElimination:
    exact copies within a batch and against the population and the offspring so
    far, near copies (apart by the spacing of doubles, and by 1e-17 in a small
    variable: the threshold 1e-16), NaN rows."""
    from pymoo.core.duplicate import DefaultDuplicateElimination

    from pipeline.kernels.nsga2_ops import unique_rows
    ref = DefaultDuplicateElimination(func=lambda X: X)
    rng = np.random.default_rng(5)
    dropped = 0
    for trial in range(200):
        pop = rng.random((int(rng.integers(0, 30)), 4)) * 300.0
        X = rng.random((int(rng.integers(0, 30)), 4)) * 300.0
        off = rng.random((int(rng.integers(0, 10)), 4)) * 300.0
        if len(X) > 4:
            X[1] = X[0]                                          # a copy within X
            X[2, 0] = np.nextafter(X[3, 0], np.inf)              # one ulp apart: kept
            X[2, 1:] = X[3, 1:]
            X[4, 3] = np.nan
        if len(X) > 6 and len(pop):
            X[5] = pop[0]                                        # a copy of the population
            X[6] = pop[-1]
            X[6, 3] = 1e-17 if trial % 2 else 2e-16              # small variables
            pop[-1, 3] = 0.0
        if len(X) > 7 and len(off):
            X[7] = off[0]
        want = ref.do(X, pop, off)
        got = unique_rows(X, pop, off)
        assert got.tobytes() == np.asarray(want, float).tobytes(), trial
        dropped += len(X) - len(got)
    assert dropped > 300


def test_sbx_and_pm_are_pymoo_s():
    """kernels.nsga2_ops.sbx and pm against pymoo's SBX and PM operators, drawing
    from generators of the same seed: the same offspring bit for bit and the
    generators left in the same state (as many draws), over parents at the
    bounds, equal parents and a variable of equal bounds."""
    from pymoo.operators.crossover.sbx import SBX
    from pymoo.operators.mutation.pm import PM
    from pymoo.core.variable import get

    from pipeline.kernels.nsga2_ops import pm, sbx
    box = _Box()
    cx, mu = SBX(), PM()
    for seed in range(60):
        rng = np.random.default_rng(seed)
        n = int(rng.integers(1, 40))
        X = XL + rng.random((2, n, len(XL))) * (XU - XL)
        X[:, ::5, 1] = XL[1]                          # at a bound
        X[1, ::4] = X[0, ::4]                         # equal parents
        a, b = np.random.default_rng(seed + 1000), np.random.default_rng(seed + 1000)
        want = cx._do(box, X, random_state=a)
        eta, pv, pe, pb = get(cx.eta, cx.prob_var, cx.prob_exch, cx.prob_bin, size=(n, 1))
        got = sbx(X, XL, XU, eta, pv, pe, pb, b)
        assert got.tobytes() == want.tobytes() and a.random() == b.random(), seed
        off = want.reshape(-1, len(XL))
        want = mu._do(box, off, random_state=a)
        got = pm(off, XL, XU, get(mu.eta, size=len(off)), mu.get_prob_var(box, size=len(off)), b)
        assert got.tobytes() == want.tobytes() and a.random() == b.random(), seed
