"""Tests of pipeline.pareto against the O(n^2) brute-force reference in tests/support/naive_pareto.py."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pipeline.kernels.pareto import (
            _rank_valid,
            crowding_distance,
            dominates,
            knee_point,
            nondominated_rank,
        )

from support.naive_pareto import brute_force_rank, crowding_ref, dominates_ref

NAN = math.nan
INF = math.inf

HYP = settings(max_examples=150, deadline=None,
               suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def check_rank(F, feasible=None, expected=None):
    got = nondominated_rank(F, feasible)
    ref = brute_force_rank(F, feasible)
    assert got.dtype == np.int32
    np.testing.assert_array_equal(got, ref)
    if expected is not None:
        np.testing.assert_array_equal(got, np.asarray(expected))
    return got


def check_front_structure(F, rank):
    """Independent sanity: no dominance inside a front; rank r > 1 is dominated by rank r-1."""
    F = np.asarray(F, dtype=float)
    for i in np.flatnonzero(rank > 0):
        doms = [j for j in np.flatnonzero(rank > 0) if dominates_ref(F[j], F[i])]
        assert all(rank[j] < rank[i] for j in doms)
        if rank[i] > 1:
            assert any(rank[j] == rank[i] - 1 for j in doms)
        else:
            assert not doms


# ---------------------------------------------------------------------------
# dominance
# ---------------------------------------------------------------------------
def test_dominates():
    assert dominates([1, 2], [1, 3])
    assert dominates([0, 0, 0], [1, 1, 1])
    assert not dominates([1, 2], [1, 2])          # identical
    assert not dominates([1, 3], [2, 2])          # incomparable
    assert not dominates([2, 2], [1, 3])
    assert not dominates([1, 3], [1, 2])
    assert not dominates([NAN, 0], [1, 1])
    assert not dominates([0, 0], [NAN, 1])
    assert dominates([-INF, 0], [0, 0])
    assert not dominates([0.0, 1.0], [-0.0, 1.0])
    with pytest.raises(ValueError):
        dominates([1, 2], [1, 2, 3])


# ---------------------------------------------------------------------------
# hand-made sets
# ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "F, feasible, expected",
    [
        # ties in f1 and an exact duplicate
        ([[1, 2], [1, 3], [2, 1], [1, 2], [2, 2], [0, 5]], None, [1, 2, 1, 1, 2, 1]),
        ([[1, 1], [2, 1], [3, 1]], None, [1, 2, 3]),                 # ties in f2
        ([[1, 3], [1, 2], [1, 1]], None, [3, 2, 1]),                 # ties in f1
        ([[2, 2]] * 5, None, [1] * 5),                               # all identical
        ([[1, 1], [1, 1], [1, 2], [1, 2], [0, 3]], None, [1, 1, 2, 2, 1]),
        ([[3, 4]], None, [1]),                                       # single point
        ([[NAN, 4]], None, [0]),                                     # single NaN
        ([[3, 4]], [False], [0]),                                    # single infeasible
        ([[NAN, 0], [1, 1], [0, NAN], [2, 2], [NAN, NAN]], None, [0, 1, 0, 2, 0]),
        ([[0, 0], [1, 1], [2, 2], [1, 1]], [False, True, True, True], [0, 1, 2, 1]),
        ([[0, 0], [1, 1]], [False, False], [0, 0]),                  # all infeasible
        ([[0, 0], [NAN, 1]], [False, True], [0, 0]),
        ([[-INF, 5], [0, INF], [INF, -INF], [0, 0]], None, [1, 2, 1, 1]),
        ([[0.0, 1.0], [-0.0, 1.0], [0.0, 2.0]], None, [1, 1, 2]),   # signed zeros are equal
        ([[5, 5], [4, 4], [3, 3], [2, 2], [1, 1]], None, [5, 4, 3, 2, 1]),  # chain
        ([[1, 2, 3], [3, 2, 1], [2, 2, 2], [1, 2, 3], [2, 3, 4], [4, 4, 4]], None,
         [1, 1, 1, 1, 2, 3]),
        ([[1, 1, 1], [1, 1, 2], [1, 2, 1], [2, 1, 1], [1, 1, 1]], None, [1, 2, 2, 2, 1]),
        ([[1, 2, NAN], [0, 0, 0], [1, 1, 1]], [True, False, True], [0, 0, 1]),
        ([[3], [1], [2], [1]], None, [3, 1, 2, 1]),                  # m = 1
        ([[1, 2, 3, 4], [2, 1, 3, 4], [2, 2, 3, 4], [2, 2, 3, 4]], None, [1, 1, 2, 2]),
    ],
)
def test_hand_made(F, feasible, expected):
    F = np.array(F, dtype=float)
    fe = None if feasible is None else np.array(feasible)
    rank = check_rank(F, fe, expected)
    check_front_structure(F, rank)
    # the general O(m n^2) path agrees on the valid rows
    valid = rank > 0
    if valid.any():
        np.testing.assert_array_equal(_rank_valid(F[valid], general=True), rank[valid])


def test_empty_and_input_checks():
    r = nondominated_rank(np.empty((0, 2)))
    assert r.shape == (0,) and r.dtype == np.int32
    r = nondominated_rank(np.empty((0, 3)), np.empty(0, bool))
    assert r.shape == (0,)
    # integer input and 0/1 feasibility flags
    np.testing.assert_array_equal(
        nondominated_rank(np.array([[1, 2], [2, 3], [0, 9]]), np.array([1, 1, 0])), [1, 2, 0])
    with pytest.raises(ValueError):
        nondominated_rank(np.arange(5.0))
    with pytest.raises(ValueError):
        nondominated_rank(np.zeros((3, 2)), np.ones(4, bool))
    assert crowding_distance(np.empty((0, 2)), np.empty(0, np.int32)).shape == (0,)
    assert knee_point(np.empty((0, 2)), np.empty(0, np.int32)) == -1
    with pytest.raises(ValueError):
        crowding_distance(np.zeros((3, 2)), np.ones(2, np.int32))


def test_permuted_chain_and_input_not_modified():
    rng = np.random.default_rng(1)
    n = 200
    F = np.column_stack([np.arange(n), np.arange(n) * 2.0, -np.arange(n) * 0.0])
    perm = rng.permutation(n)
    G = F[perm].copy()
    G0 = G.copy()
    r = nondominated_rank(G)
    np.testing.assert_array_equal(G, G0)
    np.testing.assert_array_equal(r, perm + 1)
    r2 = nondominated_rank(G[:, :2])
    np.testing.assert_array_equal(r2, perm + 1)


# ---------------------------------------------------------------------------
# hypothesis: many ties (small integer ranges)
# ---------------------------------------------------------------------------
@st.composite
def objective_sets(draw, m, max_n=40, hi=4):
    n = draw(st.integers(0, max_n))
    vals = draw(st.lists(st.integers(0, hi), min_size=n * m, max_size=n * m))
    F = np.array(vals, dtype=float).reshape(n, m)
    if n and draw(st.booleans()):                 # sprinkle NaNs
        nan_mask = np.array(draw(st.lists(st.booleans(), min_size=n * m, max_size=n * m)))
        nan_mask &= np.array(draw(st.lists(st.sampled_from([False] * 4 + [True]),
                                           min_size=n * m, max_size=n * m)))
        F[nan_mask.reshape(n, m)] = np.nan
    feasible = None
    if draw(st.booleans()):
        feasible = np.array(draw(st.lists(st.sampled_from([True, True, True, False]),
                                          min_size=n, max_size=n)), dtype=bool)
    return F, feasible


@pytest.mark.parametrize("m", [2, 3])
@HYP
@given(data=st.data())
def test_hypothesis_matches_brute_force(m, data):
    F, feasible = data.draw(objective_sets(m))
    rank = check_rank(F, feasible)
    valid = rank > 0
    if valid.any():
        np.testing.assert_array_equal(_rank_valid(F[valid], general=True), rank[valid])
    # stability: permuting the input permutes the ranks
    perm = np.array(data.draw(st.permutations(range(F.shape[0]))), dtype=np.intp)
    fe = None if feasible is None else feasible[perm]
    np.testing.assert_array_equal(nondominated_rank(F[perm], fe), rank[perm])


@HYP
@given(data=st.data())
def test_hypothesis_other_m(data):
    m = data.draw(st.sampled_from([1, 4, 5]))
    F, feasible = data.draw(objective_sets(m, max_n=30, hi=3))
    check_rank(F, feasible)


@HYP
@given(data=st.data())
def test_hypothesis_real_values_front_structure(data):
    m = data.draw(st.sampled_from([2, 3]))
    n = data.draw(st.integers(1, 25))
    vals = data.draw(st.lists(st.sampled_from([-INF, -1.5, -0.0, 0.0, 0.25, 1e300, INF, 3.0]),
                              min_size=n * m, max_size=n * m))
    F = np.array(vals).reshape(n, m)
    rank = check_rank(F)
    check_front_structure(F, rank)


# ---------------------------------------------------------------------------
# medium random sets
# ---------------------------------------------------------------------------
@pytest.mark.parametrize("m", [2, 3])
@pytest.mark.parametrize("kind", ["continuous", "ties"])
def test_medium_random(m, kind):
    rng = np.random.default_rng(100 + m)
    n = 3000
    if kind == "continuous":
        F = rng.random((n, m))
        F[:, 1] -= 0.5 * F[:, 0]                 # mild correlation -> more fronts
    else:
        F = rng.integers(0, 25, size=(n, m)).astype(float)
    feasible = rng.random(n) > 0.1
    F[rng.random(n) < 0.02, rng.integers(0, m)] = np.nan
    got = nondominated_rank(F, feasible)
    ref = brute_force_rank(F, feasible, jit=True)
    np.testing.assert_array_equal(got, ref)
    assert got.max() > 1
    valid = got > 0
    np.testing.assert_array_equal(_rank_valid(F[valid], general=True), got[valid])
    perm = rng.permutation(n)
    np.testing.assert_array_equal(nondominated_rank(F[perm], feasible[perm]), got[perm])


# ---------------------------------------------------------------------------
# crowding distance
# ---------------------------------------------------------------------------
def test_crowding_hand_made():
    F = np.array([[0, 4], [1, 2], [3, 1], [4, 0],      # front 1
                  [5, 5], [6, 4.5],                     # front 2 (2 points)
                  [9, 9],                               # front 3 (1 point)
                  [-1, -1]], dtype=float)               # infeasible
    feasible = np.array([True] * 7 + [False])
    rank = nondominated_rank(F, feasible)
    np.testing.assert_array_equal(rank, [1, 1, 1, 1, 2, 2, 3, 0])
    cd = crowding_distance(F, rank)
    np.testing.assert_allclose(cd, [INF, 0.75 + 0.75, 0.75 + 0.5, INF, INF, INF, INF, 0.0])
    np.testing.assert_array_equal(cd, crowding_ref(F, rank))
    # zero-range objective contributes nothing; identical points: 0
    G = np.array([[0, 1], [1, 1], [2, 1], [3, 1]], dtype=float)
    np.testing.assert_allclose(crowding_distance(G, np.ones(4, np.int32)),
                               [INF, 2 / 3, 2 / 3, INF])
    H = np.ones((4, 3))
    np.testing.assert_array_equal(crowding_distance(H, np.ones(4, np.int32)), np.zeros(4))
    np.testing.assert_array_equal(crowding_distance(H[:2], np.ones(2, np.int32)), [INF, INF])


@pytest.mark.parametrize("m", [2, 3])
@HYP
@given(data=st.data())
def test_crowding_matches_reference(m, data):
    F, feasible = data.draw(objective_sets(m, max_n=30, hi=6))
    rank = nondominated_rank(F, feasible)
    cd = crowding_distance(F, rank)
    ref = crowding_ref(F, rank)
    np.testing.assert_allclose(cd, ref, rtol=1e-12, atol=0)
    assert not np.isnan(cd).any()
    assert np.all(cd[rank == 0] == 0)
    assert np.all(cd[rank > 0] >= 0)


def test_crowding_random_and_arbitrary_rank_labels():
    rng = np.random.default_rng(5)
    F = rng.random((300, 3))
    rank = nondominated_rank(F)
    np.testing.assert_allclose(crowding_distance(F, rank), crowding_ref(F, rank), rtol=1e-12)
    # any grouping labels work (e.g. a caller's own clustering)
    labels = rng.integers(0, 6, 300).astype(np.int32)
    np.testing.assert_allclose(crowding_distance(F, labels), crowding_ref(F, labels), rtol=1e-12)


def test_crowding_infinite_objectives_give_no_nan():
    F = np.array([[-INF, 3], [0, 2], [1, 1], [2, INF], [INF, -INF]], dtype=float)
    rank = nondominated_rank(F)
    cd = crowding_distance(F, rank)
    assert not np.isnan(cd).any()


# ---------------------------------------------------------------------------
# knee point
# ---------------------------------------------------------------------------
def test_knee_2d_obvious():
    F = np.array([
        [0.0, 10.0],    # extreme
        [2.0, 2.0],     # dominated by the knee
        [1.0, 1.0],     # the knee
        [10.0, 0.0],    # extreme
        [5.0, 0.5],     # on the front, flat part
        [0.5, 0.5],     # would be the knee but infeasible
        [NAN, 0.0],
        [0.2, 6.0],     # on the front, steep part
    ])
    feasible = np.array([True, True, True, True, True, False, True, True])
    rank = nondominated_rank(F, feasible)
    assert knee_point(F, rank) == 2
    perm = np.array([7, 6, 5, 4, 3, 2, 1, 0])
    assert knee_point(F[perm], nondominated_rank(F[perm], feasible[perm])) == 5
    # scale invariance (normalisation per objective)
    G = F * np.array([1000.0, 0.001])
    assert knee_point(G, nondominated_rank(G, feasible)) == 2


def test_knee_3d_obvious():
    F = np.array([
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.6, 0.6, 0.1],
        [0.3, 0.3, 0.3],    # the knee
        [0.5, 0.5, 0.5],    # dominated
    ])
    rank = nondominated_rank(F)
    np.testing.assert_array_equal(rank, [1, 1, 1, 1, 1, 2])
    assert knee_point(F, rank) == 4
    # extreme points in general position: plane through them is sum(x) = 1.5
    H = np.array([[0.0, 0.5, 1.0], [1.0, 0.0, 0.5], [0.5, 1.0, 0.0],
                  [0.45, 0.45, 0.45], [0.3, 0.3, 0.8]])
    assert knee_point(H, nondominated_rank(H)) == 3


def test_knee_ties_and_degenerate():
    # symmetric front: rows 1 and 2 are exactly equidistant -> lowest index
    F = np.array([[0.0, 4.0], [1.0, 2.0], [2.0, 1.0], [4.0, 0.0]])
    assert knee_point(F, nondominated_rank(F)) == 1
    G = F[[3, 2, 1, 0]]
    assert knee_point(G, nondominated_rank(G)) == 1
    # empty front 1
    assert knee_point(F, np.zeros(4, np.int32)) == -1
    assert knee_point(F, nondominated_rank(F, np.zeros(4, bool))) == -1
    # single point and all-identical fronts
    assert knee_point(np.array([[1.0, 1.0], [2.0, 2.0]]), np.array([2, 1])) == 1
    assert knee_point(np.ones((3, 2)), np.ones(3, np.int32)) == 0
    # knee is always a member of front 1
    rng = np.random.default_rng(3)
    for m in (2, 3, 4):
        X = rng.random((500, m))
        r = nondominated_rank(X)
        k = knee_point(X, r)
        assert r[k] == 1


# ---------------------------------------------------------------------------
# scale: 10^6 x 2
# ---------------------------------------------------------------------------
def test_million_by_two():
    rng = np.random.default_rng(2024)
    n = 1_000_000
    F = rng.random((n, 2))
    rank = nondominated_rank(F)
    assert rank.shape == (n,) and rank.dtype == np.int32
    assert rank.min() == 1
    # independent check of front 1 (continuous values: no ties): a point is
    # non-dominated iff its f2 is below every f2 of points with smaller f1
    order = np.argsort(F[:, 0], kind="stable")
    f2 = F[order, 1]
    prev_min = np.minimum.accumulate(np.concatenate([[np.inf], f2[:-1]]))
    front1 = np.zeros(n, bool)
    front1[order] = f2 < prev_min
    np.testing.assert_array_equal(rank == 1, front1)
    cd = crowding_distance(F, rank)
    assert not np.isnan(cd).any()
    assert rank[knee_point(F, rank)] == 1
