"""The sweep's positions stage in lock-step lanes.

LANES candidates of a block advance together, position by position; the lane
loop is the innermost loop, with straight-line code (no call, no library
function: division and square root only), so LLVM turns it into packed
vector instructions.  Every per-candidate constant and every piece of state
that lives from one crank position to the next is a row of one array
``S[row, lane]`` (a single base pointer: no aliasing to rule out).

Inputs besides the crank: ``setup_lane`` fills the input's columns of the
lane's table with its law at every step of the walk (e(q), or q for a slider,
then q' and q'': the careful path's own law and library calls), and the walk
reads them; the force lanes take them over as a class III solution.

The fast path is exact to rounding where it runs, and says where it cannot
vouch for a lane (S[R_flag, lane] set): an assembly failure or a margin below
``settings[SET_MARGIN_SAFE]``, a Newton that did not reach the tolerance in
its fixed count, a correction or a step larger than the careful walk allows,
a change of sign of det J, a revolution that does not close, a rocker step
too large for the series.  Such a lane is redone on the careful path from two
positions before its first flag (``careful_tail``), which finds its failure as
the walk from the start finds it; where it meets none, the careful window is
spliced into the lane's numbers (solved to near rounding: the lane's own hold
outside it), and only a lane that cannot be spliced is walked whole.

Class III groups (and their sliding variant, P5 on a guide's line instead of
a lead): the unknown angles a, b live as unit vectors e(a), e(b);
a Newton update is a rotation by a small angle, with cos/sin from their
series (exact to rounding for |angle| <= 0.05 rad, larger corrections are
refused); the predictor rotates by the last increment (the secant predictor
of the careful walk).  The output rocker's angle is accumulated from its
increments, atan of a small argument by its series.
"""

from __future__ import annotations

import ast
import math
import re

from ..kernels.continuation import FOLD_SHARE
from ..kernels.watch import ERR_FACTOR
from .emit import constant_names
from .names import text, wrap_line
from .skeleton import part

NEWTON_STEPS = 2          # Newton steps per position after the predictor
ATAN_ARG = 0.1            # largest tan of a rocker step taken by the atan series


TRIAD_ROWS = ("ca", "sa", "cb", "sb", "dca", "dsa", "dcb", "dsb", "sign", "a0c", "a0s", "b0c",
              "b0s")


def _lane_rows(consts, triads, watched):
    """The rows of the lane array S[row, lane]: every per-candidate constant,
    each class III group's state, the output rocker's, and each watched group's
    margin^2 at k-3, k-2, k-1."""
    rows = list(consts)
    for e in triads:
        rows += [f"t{e.triad_row}_{x}" for x in TRIAD_ROWS]
    rows += ["rock_x", "rock_y", "theta", "margin", "margin_b", "flag", "first_flag",
             "last_flag"]
    for i, e in enumerate(watched):
        rows += [f"w{i}_{x}" for x in ("k3", "k2", "k1")]
    return rows


def _lane_constants(plan, names, rocker, width, fast, rows, n_triads, n_inputs):
    """The module's constants of the lane path: the output rocker's points, the
    lane count, the lane table's columns and the rows of S."""
    ipiv, ipt = plan.point(rocker[0]), plan.point(rocker[1])
    src = [f"ROCKER_PIVOT = {names.I(ipiv)}   # {text(rocker[0])}",
           f"ROCKER_POINT = {names.I(ipt)}   # {text(rocker[1])}",
           f"LANES = {width}",
           f"HALF = {width // 2}   # the walk's lanes in pairs: l and HALF + l",
           f"HAS_LANES = {fast}   # every kinematic group has a lane form",
           f"NEWTON_STEPS = {NEWTON_STEPS}   # Newton steps per position in the lanes",
           f"LANE_STEP_MAX = {math.atan(ATAN_ARG)!r}   # the largest rocker step the lanes' "
           "atan series takes exactly",
           f"THETA_COLS = {2 + 4 * n_triads + 4 * n_inputs}   # rocker angle, e(a), e(b) of "
           "each class III group, e(q) (or q), q', q'' of each input, the position's margin",
           f"THETA_IN = {1 + 4 * n_triads}   # the first column of the inputs' laws",
           f"TRAIL_COLS = {4 * n_triads + 4 * n_inputs}   # the columns handed over (the trail)",
           f"MARGIN_COL = {1 + 4 * n_triads + 4 * n_inputs}   # the lane's margin at each position "
           "(a spliced lane's: evaluate)",
           f"N_LANE_ROWS = {len(rows)}",
           "# rows of the lane array S[row, lane]"]
    return (src + [f"R_{r} = {i}" for i, r in enumerate(rows)]
            + ["# where each row starts in the walk's flat S (R_row * LANES)"]
            + [f"W_{r} = {i * width}" for i, r in enumerate(rows)] + [""])


def lane_kernel(plan, names, ems, rocker, width, watch=True):
    """Source of the lane path of ``plan`` (``setup_lane``, ``walk``,
    ``block_walk``, ``lanes_apply``) with the output rocker ``rocker`` =
    (pivot, point) names, LANES = ``width``."""
    kin = ems[:plan.n_kinematic]
    fast = all(e.fast for e in kin)
    triads = [e for e in kin if e.continued]    # (the groups solved by continuation)
    inputs = [e for e in kin if e.takes_law]
    for j, e in enumerate(inputs):      # their columns of the table, after the triads'
        e.theta_col = 1 + 4 * len(triads) + 4 * j
    consts = constant_names(plan, names, ems)
    watched = [e for e in kin if e.watched and watch]
    rows = _lane_rows(consts, triads, watched)
    src = _lane_constants(plan, names, rocker, width, fast, rows, len(triads), len(inputs))
    if not fast:
        src += ["\n" + no_lane_path("A group without a lane form")]
        return "\n".join(src) + "\n"
    rocker_xy = (names.xy(plan.point(rocker[0])), names.xy(plan.point(rocker[1])))
    src += [""] + _walk(plan, names, kin, triads, watched, rocker_xy, width) + ["", ""]
    src += _setup_lane(consts, inputs, triads, watched)
    src += _block_walk() + _lanes_apply()
    return "\n".join(src) + "\n\n"


def _setup_lane(consts, inputs, triads, watched):
    """Source of ``setup_lane``: one candidate into one lane (its constants, its
    inputs' laws, the careful solve at phis[0], the first increment of each
    class III group from its analogs)."""
    unpack = "(" + ", ".join(consts) + ("," if len(consts) == 1 else "") + ") = K"
    body = ["K = constants(pars[i])"] + _split(unpack) + [f"S[R_{c}, l] = {c}" for c in consts]
    for e in inputs:
        body += e.law_steps()
    body += ["adv = function_at(called[AT_ADVANCE], ADVANCE_FN)   # (its address: callees)",
             "st = adv(K, walk_start(K, phis[0], state), phis[0], np.int64(1), tols, state, pos,",
             "         d1, d2, margins, np.bool_(False))",
             "ok = st == OK"]
    for e in triads:
        body += e.setup_lines()
    body += _setup_rocker_lines(triads)
    for i, e in enumerate(watched):
        body.append(f"# {e.title()}: the watch's history starts with margin^2 at phis[0]")
        body += [f"S[R_w{i}_{x}, l] = margins[{e.g}] * margins[{e.g}]"
                 for x in ("k3", "k2", "k1")]
    return [
        "# its own function, compiled from the start in the process beside the run",
        "# (pipeline.compiler.beside), which then loads it from numba's cache;",
        "# with a Python wrapper: the lane tests and the benchmark call it",
        "@njit(**JIT)",
        "def setup_lane(pars, i, l, phis, close, tols, S, theta, pos, d1, d2, margins, state,",
        "               called):",
        '    """Candidate ``i`` into lane ``l``: its constants, its inputs\' laws at every',
        "    step of the walk (``close``: phi_close, or phis[0] where the revolution",
        "    need not close), and the careful solve at phis[0] (order 1: the first",
        "    increment of the class III angles comes from their analogs).  Returns",
        "    OK, the status of a failure there, or -1.  ``called``: ``callees()``, advance's",
        '    address among them."""'] + ["    " + x for x in body] + [
        "    # OK (0): in the lane; a failure at phis[0] is the careful path's own first",
        "    # step, reported as it is; -1: assembled, but the lane cannot start (careful)",
        "    return (0 if ok else -1) if st == OK else st", "", ""]


def _setup_rocker_lines(triads):
    """setup_lane's lines of the output rocker's start, the lane's margin (the
    smallest of its class III groups') and its flags."""
    out = ["S[R_rock_x, l] = pos[ROCKER_POINT, 0] - pos[ROCKER_PIVOT, 0]",
           "S[R_rock_y, l] = pos[ROCKER_POINT, 1] - pos[ROCKER_PIVOT, 1]",
           "S[R_theta, l] = 0.0",
           "theta[0, l] = 0.0"]
    if triads:
        out.append("S[R_margin, l] = min(" + ", ".join(f"state[{e.triad_row}, S_MARGIN]"
                                                      for e in triads)
                   + ("" if len(triads) > 1 else ", math.inf") + ")")
    else:
        out.append("S[R_margin, l] = math.inf")
    out.append("theta[0, MARGIN_COL * LANES + l] = S[R_margin, l]")
    return out + [
        "if not ok or not math.isfinite(S[R_rock_x, l]):",
        "    ok = False",
        "    S[R_rock_x, l] = 1.0",
        "    S[R_rock_y, l] = 0.0",
        "S[R_flag, l] = 0.0",
        "S[R_first_flag, l] = -1.0   # the first position the lane flagged (-1: none)",
        "S[R_last_flag, l] = -1.0    # and the last"]


def _flat(line):
    """A line of the walk, which sees S flat, rows LANES apart (a constant stride:
    rows provably apart, so no run-time overlap checks), while the lane count
    stays a run-time value (a constant trip count is unrolled, and stays scalar).
    A row's start is a constant of its own (W_row, not R_row * LANES): the same
    machine code, and numba types and lowers two operations fewer per access."""
    return re.sub(r"S\[R_(\w+), l\]", r"S[W_\1 + l]", line)


def _walk(plan, names, kin, triads, watched, rocker_xy, width):
    """Source of ``walk``: every lane of a block advanced one crank position at a
    time, each group's lane lines, the output rocker's angle and the flags; at
    the closing position, the class III groups' return to their start."""
    walk = ["@njit(**JIT_LANES)   # FMA contraction: the one kernel with it",
            "def walk(S, n_lanes, theta, cph_tab, sph_tab, k_end, k_close, tol, jump, step_change,",
            "         margin_safe, close, watch_floor):",
            '    """The lock-step walk over crank positions 1 .. k_end - 1: every lane of the',
            "    block advances one position at a time (straight-line code, division and",
            "    square root only); a function of its own so that nothing outside the",
            "    loops shares their variables (LLVM then vectorizes the lane loop).  At",
            "    k_close (phi_close) the class III groups must be back on their start; every",
            "    watched group's margin^2 passes the watch's certificate",
            '    (pipeline.kernels.watch) on every window of three positions."""',
            "    for k in range(1, k_end):",
            "        cph = cph_tab[k]",
            "        sph = sph_tab[k]",
            "        armed = k >= 3      # the watch: four positions known",
            "        # a trip count known only at run time: LLVM vectorizes this loop (a",
            "        # constant count is unrolled instead, and stays scalar)",
            "        for l in range(n_lanes):"]
    # margin: this position's (its class III groups' smallest), into the running one after
    inner = ["bad = False", "low = False", "big = False", "margin = math.inf"]
    for fi, off in zip(plan.fixed_idx, plan.fixed_off):
        pn = names.xy(fi)
        inner += [f"{pn}x = S[R_{names.par(off)}, l]",
                  f"{pn}y = S[R_{names.par(int(off) + 1)}, l]"]
    for e in kin:
        inner += e.lanes()
        if e in watched:
            inner += _watch_lines(watched.index(e), e)
    inner += _rocker_step_lines(*rocker_xy)
    paired = _paired([_flat(line) for line in inner]) if width % 2 == 0 else None
    if paired:      # (n_lanes is LANES: block_walk passes S's width)
        walk[-1] = "        for l in range(n_lanes - HALF):   # lanes l and HALF + l"
        walk += ["            " + line for line in paired]
    else:
        walk += ["            " + _flat(line) for line in inner]
    if triads:
        walk += ["        if k == k_close:"] + ["            " + _flat(x)
                                                  for x in _closing_lines(triads)]
    return walk


def _paired(lines):
    """The walk's lane lines for lanes l and HALF + l, statement by statement in
    turn (the second lane's local names with the suffix ``_h``), or None where a
    line is not a plain assignment.  A lane's position is one long chain of
    dependent operations (two Newton steps, the cos/sin series, the divisions):
    with one vector of lanes in the loop's body the core waits on its latencies,
    and the next vector's chain comes too late to fill the wait (the body is
    longer than the core's reorder window); two chains side by side fill it.
    The same operations on each lane, so the same bits.  Measured: the main
    job's walk 20 % faster on this AMD EPYC (AVX2); four chains spilled so many
    registers that the walk took three times as long."""
    local = set()
    for line in lines:
        code = line.split("#")[0].strip()
        if not code:
            continue
        try:
            tree = ast.parse(code)
        except SyntaxError:
            return None
        if len(tree.body) != 1 or not isinstance(tree.body[0], (ast.Assign, ast.AugAssign)):
            return None
        local |= {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)
                  and isinstance(n.ctx, ast.Store)}
    names = re.compile(r"(?<![.\w])(" + "|".join(sorted(local, key=len, reverse=True))
                       + r")\b")     # (not an attribute: math.inf)
    out = []
    for line in lines:
        code = line.split("#")[0].rstrip()
        out.append(line)
        if code.strip():
            twin = re.sub(r"\+ l\]", "+ HALF + l]", names.sub(r"\1_h", code))
            out.append(re.sub(r"\[k, l\]", "[k, HALF + l]", twin))
    return out


def _rocker_step_lines(piv, pt):
    """The walk's lines of the output rocker (its angle from the increments, atan
    series of a small tan) and of the lane's margin and flags at this position."""
    return [
        "# the output rocker: its angle from the increments (atan series of a small tan)",
        f"ux = {pt}x - {piv}x", f"uy = {pt}y - {piv}y",
        "vx = S[R_rock_x, l]", "vy = S[R_rock_y, l]",
        "tn = (vx * uy - vy * ux) / (vx * ux + vy * uy)",
        "z = tn * tn",
        "dth = tn * (1.0 - z * (1.0 / 3.0 - z * (1.0 / 5.0 - z * (1.0 / 7.0 - z * (1.0 / 9.0"
        " - z * (1.0 / 11.0 - z * (1.0 / 13.0 - z * (1.0 / 15.0))))))))",
        f"big = big | (not (abs(tn) <= {ATAN_ARG}))",
        "th = S[R_theta, l] + dth",
        "big = big | (abs(th) > 3.0)",
        "S[R_rock_x, l] = ux", "S[R_rock_y, l] = uy", "S[R_theta, l] = th",
        "theta[k, l] = th",
        "theta[k, MARGIN_COL * LANES + l] = margin",
        "flagged = bad | low | big",
        # the flags as arithmetic on 0/1 and whole numbers (exact: the values of the
        # max and the selects, bit for bit), not as a select of the row's own value,
        # which LLVM stores as a masked store: microcoded on AMD's AVX2 cores
        "flag_now = 1.0 if flagged else 0.0",
        "flag_was = S[R_flag, l]",
        "S[R_flag, l] = flag_was + flag_now - flag_was * flag_now   # their max",
        "first_was = S[R_first_flag, l]",
        "last_was = S[R_last_flag, l]",
        "k_at = float(k)",
        "S[R_first_flag, l] = first_was + (k_at - first_was) * (flag_now if first_was < 0.0 "
        "else 0.0)",
        "S[R_last_flag, l] = last_was + (k_at - last_was) * flag_now",
    ]


def _closing_lines(triads):
    """The walk's lines at the closing position: each class III group back on its
    start, else the lane flagged."""
    shut = ["# the revolution closes on its start (row k_close is phi_close)",
            "for l in range(n_lanes):"]
    for e in triads:
        t = f"t{e.triad_row}"
        shut += [f"    ea = S[R_{t}_a0c, l] * S[R_{t}_sa, l] - S[R_{t}_a0s, l] * S[R_{t}_ca, l]",
                 f"    eb = S[R_{t}_b0c, l] * S[R_{t}_sb, l] - S[R_{t}_b0s, l] * S[R_{t}_cb, l]",
                 f"    dot = S[R_{t}_a0c, l] * S[R_{t}_ca, l] + S[R_{t}_a0s, l] * S[R_{t}_sa, l]",
                 "    if not (abs(ea) <= close and abs(eb) <= close and dot > 0.0):",
                 "        S[R_flag, l] = 1.0",
                 "        if S[R_first_flag, l] < 0.0:",
                 "            S[R_first_flag, l] = k",
                 "        S[R_last_flag, l] = max(S[R_last_flag, l], k)"]
    return shut


def _block_walk():
    """Source of ``block_walk``: the walk of a full block (its closing checks inside)."""
    return [
        "# its own function: compiled beside the run, as setup_lane",
        "@njit(**JIT)",
        "def block_walk(S, theta, cph_tab, sph_tab, phis, tols, settings, called):",
        '    """The lock-step walk of a full block (every lane set up), then the closing',
        "    checks; S[R_flag, l] != 0 marks a lane the careful path must redo.  The walk",
        '    through its address (``called``: ``callees()``)."""',
        "    walk_at = function_at(called[AT_WALK], WALK_FN)",
        "    npos = phis.shape[0]",
        "    margin_safe = settings[SET_MARGIN_SAFE]",
        "    tol = tols[T_NEWTON_TOL]",
        "    jump = tols[T_JUMP]",
        "    step_change = tols[T_STEP_CHANGE]",
        "    close = tols[T_CLOSE]",
        "    # the lock-step walk: positions 1 .. n - 1, the closing position and two past it",
        "    # (the watch's windows wrap round the close)",
        "    walk_at(S.reshape(N_LANE_ROWS * LANES), S.shape[1], theta, cph_tab, sph_tab, "
        "npos + 3, npos,",
        "            tol, jump, step_change, margin_safe, close, tols[T_WATCH])",
        "    # the lane's least margin from its column, position by position as the walk",
        "    # met them, in a loop of its own over two rows of S in turn: the running value",
        "    # written back where the walk read it was a masked store (microcoded on AMD's",
        "    # AVX2 cores)",
        "    n_lanes = S.shape[1]",
        "    for k in range(1, npos + 3, 2):",
        "        for l in range(n_lanes):",
        "            S[R_margin_b, l] = min(S[R_margin, l], theta[k, MARGIN_COL * LANES + l])",
        "        if k + 1 == npos + 3:",
        "            for l in range(n_lanes):",
        "                S[R_margin, l] = S[R_margin_b, l]",
        "        else:",
        "            for l in range(n_lanes):",
        "                S[R_margin, l] = min(S[R_margin_b, l],",
        "                                     theta[k + 1, MARGIN_COL * LANES + l])",
        "", ""]


def _lanes_apply():
    """Source of ``lanes_apply``: whether the crank grid suits the lane path."""
    return [
        "@njit(**JIT_INNER)",
        "def lanes_apply(phis, tols):",
        '    """Whether the lane path applies to this crank grid (at least 3 positions, steps',
        '    no longer than the careful walk\'s largest)."""',
        "    return phis.shape[0] >= 3 and abs(phis[1] - phis[0]) <= tols[T_SUBSTEP]", ""]


def _watch_lines(i, e):
    """Lane lines of the watch (pipeline.kernels.watch) for a group whose margin is
    ``m``: the window of margin^2 at k - 2, k - 1, k (equal steps: the quadratic
    q(t) = D[k-1] + b t + c t^2, its cubic term from the third difference),
    division-free; a window that may come within the watch threshold of zero
    flags the lane (the careful path looks closely)."""
    r = {x: f"S[R_w{i}_{x}, l]" for x in ("k3", "k2", "k1")}
    fold = []
    if e.continued:
        fold = ["# (class III: margin^2 exists only where the group assembles, and the",
                "# solutions may resume past a short range where it does not; where the",
                "# line through the centre and a neighbour falls to zero within",
                "# 1 / FOLD_SHARE steps the careful walk slows down into a possible fold:",
                "# continuation.fold_limit)",
                f"hit = hit | ({1.0 + FOLD_SHARE!r} * g1 - max(g2, v) <= lim)"]
    return [
        f"# {e.title()}: the watch's window of margin^2 at k - 2, k - 1, k",
        f"g3 = {r['k3']}", f"g2 = {r['k2']}", f"g1 = {r['k1']}", "v = m * m",
        f"lim = watch_floor + {ERR_FACTOR / 6.0!r} * abs(v - 3.0 * g1 + 3.0 * g2 - g3)",
        "bq = 0.5 * (v - g2)", "cq = 0.5 * (v - 2.0 * g1 + g2)",
        "hit = (min(g2, min(g1, v)) <= lim) | ((cq > 0.0) & (abs(bq) < 2.0 * cq)"
        " & (4.0 * cq * g1 - bq * bq <= 4.0 * cq * lim))",
    ] + fold + [
        "big = big | (armed & hit)",
        f"{r['k3']} = g2", f"{r['k2']} = g1", f"{r['k1']} = v",
    ]


def _split(line, width=90):
    return wrap_line(line, width).split("\n")


# the lane path's constants where there is no output rocker (not a sweep)
NO_ROCKER = ("ROCKER_PIVOT = 0", "ROCKER_POINT = 0", "LANES = 1", "HAS_LANES = False",
             "N_LANE_ROWS = 4", "THETA_COLS = 2", "THETA_IN = 1", "TRAIL_COLS = 0",
             "MARGIN_COL = 1", "R_margin = 0", "R_flag = 1",
             "R_first_flag = 2", "R_last_flag = 3",
             "NEWTON_STEPS = 0", "LANE_STEP_MAX = 0.0")


def no_lane_path(why):
    """``setup_lane``, ``block_walk`` and ``lanes_apply`` of a module without a lane
    path (pipeline/compiler/skeleton/no_lanes.py): every candidate takes the careful
    path, for the reason ``why``."""
    return part("no_lanes").format(why=why)


def no_rocker_kernel():
    """The lane path of a module without an output rocker: its constants, and
    no lane path."""
    return "\n".join(NO_ROCKER) + "\n\n\n" + no_lane_path("No output rocker declared")
