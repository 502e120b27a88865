"""The sweep's lanes and force lanes against the careful path and the scalar force
stage: the checks that tests/compiler and the group types' own test files share
(each file runs the sweep of its own mechanism, compiled once for the file)."""

import collections
import math
import re

import numpy as np
from numba import njit

from pipeline.compiler.parallel import run_rows
from pipeline.kernels import config as kc
from pipeline.kernels import sweep as ks
from support.tolerances import (FAIL_ANGLE_TRIAD_RAD, LANE_AGREEMENT_REL, LANE_MARGIN_REL,
                                SPLICED_REFERENCE_TOL)


def widened_draws(studies, stem, widen, candidates):
    """A shipped sweep study (``studies``/``stem``.toml) with ranges of its text
    widened (``widen``: (old, new) pairs, each old text there exactly once), its
    problem, and the first ``candidates`` draws of its chunk 0 as parameter rows."""
    import dataclasses

    from pipeline.runs.sweep import build_problem
    from pipeline.study.reader import parse_study
    from pipeline.study.sweep_spec import parameter_rows
    from pipeline.study.sampling import draw_candidates
    text = (studies / f"{stem}.toml").read_text()
    for old, new in widen:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    study = parse_study(text, f"{stem}_wide.toml")
    pb = build_problem(study, study.sweep)
    spec = dataclasses.replace(study.sweep, candidates=candidates, chunk_size=candidates)
    return pb, parameter_rows(pb.plan, spec, draw_candidates(spec, 0))


def careful_rows(problem, pars, tols=None):
    """Statuses and metrics of ``pars`` on the careful path alone (``evaluate_careful``),
    with the problem's tolerances or ``tols``."""
    k = problem.kernels
    n = pars.shape[0]
    status = np.zeros(n, np.int8)
    metrics = np.full((n, ks.N_METRICS), np.nan)
    col = np.empty(len(problem.phis))
    trail = np.empty((len(problem.phis) + 1, 4))
    q1, q2 = (np.empty(len(problem.phis) + problem.dwell_w + 1, np.int64) for _ in range(2))
    for i in range(n):
        status[i] = k.evaluate_careful(pars[i], problem.phis, problem.phi_close,
                                       problem.tols if tols is None else tols,
                                       problem.settings(), problem.loads, col, trail, q1, q2,
                                       metrics[i])
    return status, metrics


def lane_flags(problem, pars):
    """Per row of ``pars``: 1 where its lane flagged itself (the careful path redoes
    it), 0 where the lane vouched, -1 where it did not start in a lane; the
    generated setup_lane and block_walk called as the sweep's evaluate calls them
    (a lane's numbers do not depend on its neighbours).  Also (lanes the walk
    vouched for, lanes walked) over the blocks of ``pars`` whose every candidate
    starts in a lane."""
    from pipeline.kernels.continuation import work
    k = problem.kernels
    L, npos = k.LANES, len(problem.phis)
    pos, d1, d2, m, state, _ = work(k.N_POINTS, k.N_GROUPS, k.N_TRIADS)
    phis = np.asarray(problem.phis)
    close = problem.phi_close if math.isfinite(problem.phi_close) else phis[0]
    ext = np.concatenate([phis, close + (phis[:3] - phis[0])])    # the walk's angles
    flags = np.full(len(pars), -1)
    vouched = walked = 0
    S = np.empty((k.N_LANE_ROWS, L))
    theta = np.empty((npos + 3, L * k.THETA_COLS))
    rows = []
    for i in range(len(pars) + 1):
        if i < len(pars) and k.setup_lane(pars, i, len(rows), problem.phis, close,
                                          problem.tols, S, theta, pos, d1, d2, m,
                                          state, k.callees()) == kc.OK:
            rows.append(i)
        if len(rows) == L or (i == len(pars) and rows):
            for lane in range(len(rows), L):     # (a partial block: copies of lane 0)
                S[:, lane] = S[:, 0]
                theta[:, lane::L] = theta[:, 0::L]
            k.block_walk(S, theta, np.cos(ext), np.sin(ext), problem.phis, problem.tols,
                         problem.settings(), k.callees())
            flags[rows] = S[k.R_flag, :len(rows)] != 0.0
            if rows[-1] - rows[0] == L - 1:
                walked += L
                vouched += int((S[k.R_flag] == 0.0).sum())
            rows = []
    return flags, (vouched, walked)


def lanes_vouched(problem, pars):
    """(lanes the walk vouched for, lanes walked) over the blocks of ``pars`` whose
    every candidate starts in a lane."""
    return lane_flags(problem, pars)[1]


def spliced_rows(problem, pars, status, metrics):
    """The rows of ``pars`` whose lane flagged itself and was spliced: OK, with the
    lanes' Newton count (a flagged lane walked whole has the careful path's)."""
    k = problem.kernels
    flags, _ = lane_flags(problem, pars)
    lanes_count = float(k.NEWTON_STEPS * k.N_TRIADS)
    return (flags == 1) & (status == kc.OK) & (metrics[:, ks.M_NEWTON_MEAN] == lanes_count)


def assert_lanes_agree(problem, candidates, class3=True):
    """The lane path (evaluate_rows) against the careful path alone, candidate by
    candidate: the same statuses and failing groups, the failure angles within
    the location figures (a lane that flagged itself is walked from two positions
    before its flag: ``careful_tail``), the metrics to rounding; and the lanes
    vouch for most candidates (a lane path that handed every lane over would
    agree trivially).  A lane that flagged itself and met no failure is
    spliced (its careful window solved to near rounding, the lane's numbers
    elsewhere): its metrics are held against the careful walk at Newton's
    closure 1e-14 (``SPLICED_REFERENCE_TOL``) and must be no further from it than
    the careful path's own at the product's closure, up to the lanes' rounding."""
    assert problem.kernels.HAS_LANES
    vouched, walked = lanes_vouched(problem, candidates[:400])
    assert walked >= 200 and vouched >= 0.6 * walked, (vouched, walked)
    s_fast, m_fast = problem.evaluate_rows(candidates)
    s_ref, m_ref = careful_rows(problem, candidates)
    np.testing.assert_array_equal(s_fast, s_ref)
    ok = s_ref == kc.OK
    assert ok.sum() > 100
    spliced = spliced_rows(problem, candidates, s_fast, m_fast)
    # the README's figures: 1e-12 relative, the singularity margin 7.2e-12 (a small
    # difference of large products); what is counted or located is identical
    cols = ((ks.M_STROKE, LANE_AGREEMENT_REL), (ks.M_DWELL, LANE_AGREEMENT_REL),
            (ks.M_DWELL_START, 0.0))
    if problem.spec.wants_forces:
        cols += ((ks.M_PEAK_R, LANE_AGREEMENT_REL), (ks.M_PEAK_MBAL, LANE_AGREEMENT_REL),
                 (ks.M_PEAK_PHI, 0.0), (ks.M_FORCES_DONE, 0.0))
    cols += ((ks.M_MARGIN, LANE_MARGIN_REL),) if class3 else ()
    regular = ok & ~spliced
    for col, rel in cols:
        a, b = m_fast[regular, col], m_ref[regular, col]
        np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
        f = np.isfinite(b)
        assert f.sum() > 100, col
        np.testing.assert_allclose(a[f], b[f], rtol=rel, atol=0, err_msg=f"metric column {col}")
    if spliced.any():
        assert_spliced_exact(problem, candidates[spliced], m_fast[spliced], m_ref[spliced],
                             cols)
    # a failure the lane's careful walk located from two positions before the lane's
    # flag, against the walk from the start: the same group, the same boundary
    # located twice (each within FAIL_ANGLE_TRIAD_RAD of the exact one)
    np.testing.assert_array_equal(m_fast[~ok, ks.M_FAIL_GROUP], m_ref[~ok, ks.M_FAIL_GROUP])
    np.testing.assert_allclose(m_fast[~ok, ks.M_FAIL_PHI], m_ref[~ok, ks.M_FAIL_PHI], rtol=0,
                               atol=2 * FAIL_ANGLE_TRIAD_RAD)
    return s_ref


def assert_spliced_exact(problem, pars, m_spliced, m_careful, cols):
    """Spliced lanes' metrics against the careful walk solved to Newton's closure
    SPLICED_REFERENCE_TOL (exact to rounding): over the rows, the largest
    relative distance no greater than the careful path's own at the product's
    closure plus the lanes' rounding figure; what is located or counted
    identical."""
    tight = problem.tols.copy()
    tight[kc.T_NEWTON_TOL] = SPLICED_REFERENCE_TOL
    s_exact, m_exact = careful_rows(problem, pars, tight)
    assert (s_exact == kc.OK).all()
    for col, rel in cols:
        a, b, e = m_spliced[:, col], m_careful[:, col], m_exact[:, col]
        np.testing.assert_array_equal(np.isnan(a), np.isnan(e))
        f = np.isfinite(e)
        if rel == 0.0:
            np.testing.assert_array_equal(a[f], e[f], err_msg=f"metric column {col}")
            continue
        scale = np.abs(e[f])
        ours, theirs = np.abs(a[f] - e[f]) / scale, np.abs(b[f] - e[f]) / scale
        assert ours.max(initial=0.0) <= theirs.max(initial=0.0) + rel, (col, ours.max(),
                                                                       theirs.max())


def scalar_forces(settings):
    """``settings`` asking for the scalar force stage for every candidate (the
    force lanes' baseline: the same module, the same candidates)."""
    s = settings.copy()
    s[ks.SET_SCALAR_FORCES] = 1.0
    return s


def evaluate_with(kernels, problem, pars, settings=None):
    """Statuses and metrics of ``pars`` by ``kernels``' evaluate with ``settings``
    (the problem's own by default), on threads as the sweep runs them."""
    n = pars.shape[0]
    status = np.zeros(n, np.int8)
    metrics = np.full((n, ks.N_METRICS), np.nan)
    run_rows(kernels.evaluate, np.ascontiguousarray(pars), problem.phis, problem.phi_close,
             problem.tols, problem.settings() if settings is None else settings,
             problem.loads, status, metrics)
    return status, metrics


def assert_force_lanes_round(pb, pars, min_done):
    """The force lanes of a mechanism whose lines are not all its careful
    kernels' (``SAME_BITS`` False) against the scalar force stage on ``pars``: the
    same statuses, verdicts, peak joints and angles, the positions stage's
    metrics to the bit; the peaks (and the transmission angle) within the lanes'
    agreement with the careful path; and not the same bits."""
    k, settings = pb.kernels, pb.settings()
    assert k.HAS_LANE_FORCES and not k.SAME_BITS and k.lane_forces_apply(settings)
    s1, m1 = pb.evaluate_rows(pars)
    s0, m0 = evaluate_with(k, pb, pars, scalar_forces(settings))
    np.testing.assert_array_equal(s1, s0)
    done = m0[:, ks.M_FORCES_DONE] == 1.0
    assert done.sum() > min_done
    for col in (ks.M_FORCES_DONE, ks.M_PEAK_JOINT, ks.M_PEAK_PHI, ks.M_STROKE, ks.M_DWELL):
        np.testing.assert_array_equal(m1[:, col], m0[:, col])
    cols = [ks.M_PEAK_R, ks.M_PEAK_MBAL, ks.M_PEAK_ACC, ks.M_PEAK_EPS]
    if settings[ks.SET_WANT_TRANSMISSION]:
        cols.append(ks.M_MIN_TRANS)
    for col in cols:
        np.testing.assert_allclose(m1[done, col], m0[done, col], rtol=LANE_AGREEMENT_REL, atol=0)
        assert np.isfinite(m1[done, col]).all()
    assert m1.tobytes() != m0.tobytes()


def packed_force_lane_ops(problem):
    """The packed (SIMD) floating-point instructions in the machine code of
    ``problem``'s force lanes, counted by kind."""
    k = problem.kernels
    f = njit(**dict(kc.JIT, cache=False))(k.force_lanes.py_func)
    npos = 4
    FS = np.ones(k.N_FROWS * k.LANES)
    FT = np.ones((npos, k.FT_COLS * k.LANES))
    RB = np.zeros((npos, k.N_RCOLS * k.LANES))
    f(FS, FT, RB, k.LANES, npos, 1e-12, 1e-6, 1.0, 0.0, problem.loads, 3)
    asm = next(iter(f.inspect_asm().values()))
    return collections.Counter(re.findall(r"\b(v?(?:mul|add|sub|div|sqrt)pd)\b", asm))
