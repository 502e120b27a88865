"""Force equations of a mechanism, eliminated at generation time.

The kinetostatic system (``pipeline.kernels.forces``) has one unknown pair per
revolute joint (Rx, Ry), per prismatic pair (N, C) and the balancing moment;
each moving body gives three rows: the x and y force balance and the moment
balance about its centre of mass.  The force-balance rows have coefficients
+-1 in the joint columns (they are the body-joint incidence matrix, which is
totally unimodular), so they are eliminated here, symbolically, with exact
pivots +-1 chosen for the least fill-in.  What is left is a small dense system
(mostly the moment rows) that the generated code solves with partial pivoting
at run time (on locals, ``gauss_unrolled``, up to 6 x 6; in a work array by
``kernels.forces.gauss_solve`` beyond); back substitution then gives every
unknown.  Mechanism B: 15 unknowns, a 5 x 5 system at run time instead of
15 x 15.  A plan whose system is not square keeps the general solver (it
reports NaN, as before).
"""

from __future__ import annotations

from ..kernels.inputs import ROTARY
from .names import literal
from .names import text

MM = 1e-3


class _Sym:
    """Straight-line code of the elimination: entries are exact numbers
    (floats) or names of generated locals."""

    def __init__(self):
        self.lines = []
        self.k = 0

    def var(self, expr):
        name = f"e{self.k}"
        self.k += 1
        self.lines.append(f"{name} = {expr}")
        return name

    @staticmethod
    def is_num(x):
        return isinstance(x, float)

    def mul(self, a, b):
        if self.is_num(a) and self.is_num(b):
            return a * b
        if self.is_num(b):
            a, b = b, a
        if self.is_num(a):
            if a == 0.0:
                return 0.0
            if a == 1.0:
                return b
            if a == -1.0:
                return self.var(f"-{b}")
            return self.var(f"{literal(a)} * {b}")
        return self.var(f"{a} * {b}")

    def sub(self, a, b):
        """a - b"""
        if self.is_num(a) and self.is_num(b):
            return a - b
        if self.is_num(b) and b == 0.0:
            return a
        if self.is_num(a) and a == 0.0:
            return self.var(f"-{b}") if not self.is_num(b) else -b
        return self.var(f"{_s(a)} - {_s(b)}")


# the run-time system up to this size is solved in straight-line code on locals
# (gauss_unrolled); beyond it by the library's loop (kernels.forces.gauss_solve)
UNROLLED_MAX = 6


def gauss_unrolled(a, b) -> list:
    """Lines that solve the m x m system ``a`` x = ``b`` (expressions) into the
    locals gb0..gb{m-1}, and set ``ok`` False where it is singular: the same
    operations in the same order as ``kernels.forces.gauss_solve`` (partial
    pivoting, the same skipped zero multipliers), so the same bits, but on
    locals the compiler keeps in registers instead of a work array it must
    load and store (mechanism B's 4 x 4: 15 % of a tolerance build's time in
    the loop, seen with perf).  Where the system is singular the lines go on
    with infinities; ``ok`` then replaces every unknown by NaN, as the loop's
    early return does."""
    m = len(b)
    out = ["# (kernels.forces.gauss_solve's operations, unrolled: compiler.force_equations."
           "gauss_unrolled)"]
    for i in range(m):
        out += [f"ga{i}_{j} = {a[i][j]}" for j in range(m)] + [f"gb{i} = {b[i]}"]
    for c in range(m):
        out += [f"gp = {c}", f"gbest = abs(ga{c}_{c})"]
        for r in range(c + 1, m):
            out += [f"gv = abs(ga{r}_{c})", "if gv > gbest:", "    gbest = gv",
                    f"    gp = {r}"]
        out += ["if not (gbest > 0.0):", "    ok = False"]
        for r in range(c + 1, m):
            out.append(f"if gp == {r}:")
            out += [f"    ga{c}_{k}, ga{r}_{k} = ga{r}_{k}, ga{c}_{k}" for k in range(c, m)]
            out.append(f"    gb{c}, gb{r} = gb{r}, gb{c}")
        if c + 1 < m:
            out.append(f"ginv = 1.0 / ga{c}_{c}")
        for r in range(c + 1, m):
            out += [f"gf = ga{r}_{c} * ginv", "if gf != 0.0:"]
            out += [f"    ga{r}_{k} -= gf * ga{c}_{k}" for k in range(c + 1, m)]
            out.append(f"    gb{r} -= gf * gb{c}")
    for c in range(m - 1, -1, -1):
        out.append(f"gs = gb{c}")
        out += [f"gs -= ga{c}_{k} * gb{k}" for k in range(c + 1, m)]
        out.append(f"gb{c} = gs / ga{c}_{c}")
    return out


def _s(x):
    return literal(x) if isinstance(x, float) else x


def force_kernel(plan, names) -> str:
    """Source of ``forces_at`` for ``plan`` (same signature and outputs as the
    general kinetostatics kernel).

    Inputs besides the crank (``pipeline.kernels.inputs``) add one unknown
    each: the drive on the input's body (a moment for a rotary input, a force
    along the guide for a slider input).  Their rows of ``slide_out``, after
    the slides', are (drive [N*m or N], its share of M_bal [N*m]); the
    returned M_bal is the moment the main shaft delivers, the crank's own
    plus every input's drive times dq/dphi1 (the inputs are driven from the
    main shaft: by virtual power, sum of drive * q' = M_bal on phi1)."""
    ni = plan.n_inputs
    n = 3 * len(plan.body_names)
    sig = ("def forces_at(par, pos, d1, d2, omega1, eps1, loads_k, work_a, work_b, loads_out, "
           "r_out, slide_out):")
    general = ["@njit(**JIT)", sig,
               '    """Kinetostatics at one position (the general solver: this plan\'s system',
               '    is not square or has no body)."""',
               "    return kinetostatics(pos, d1, d2, omega1, eps1, GRAVITY, par, BODY_COM, "
               "BODY_TURN,",
               "                         BODY_MASS_OFF, JOINT_POINT, JOINT_BODIES, SLIDE_BODIES, "
               "SLIDE_DIR,",
               "                         SLIDE_ANGLE, CRANK_BODY, LOAD_BODY, LOAD_POINT, loads_k, "
               "work_a,", "                         work_b, loads_out, r_out, slide_out)", ""]
    square = is_square(plan)
    if not square and ni > 0:
        # the general solver knows no inputs: nothing to solve (NaN, as it gives)
        return "\n".join(
            ["@njit(**JIT)", sig,
             '    """Kinetostatics at one position: NaN everywhere (this plan\'s force',
             '    system is not square: a body is missing or over-constrained)."""',
             "    for j in range(r_out.shape[0]):",
             "        r_out[j, 0] = r_out[j, 1] = math.nan",
             "    for k in range(slide_out.shape[0]):",
             "        slide_out[k, 0] = slide_out[k, 1] = math.nan",
             "    return math.nan", ""]) + "\n"
    if not square:
        return "\n".join(general) + "\n"

    body, m = eliminated(plan, names)
    # its own function, not inline='always' in the force stage's loop: numba types a
    # function's every statement once per round of its type inference, and the force
    # stage's loop-carried maxima take several (measured: the default study's
    # force_stage 8.4 s of compile inlined, 2.5 s + 1.0 s apart)
    src = ["@njit(**JIT)", sig,
           '    """Kinetostatics at one position: reactions r_out (n_joints, 2) [N], slides',
           "    (N [N], C [N*m]), loads at the centres of mass; returns M_bal [N*m] (NaN",
           "    everywhere when the system is singular or the kinematics is NaN).  The",
           "    force equations of every body, with the force-balance rows eliminated",
           f'    at generation time ({n} unknowns, {m} solved at run time)."""']
    src += ["    " + line for line in body]
    return "\n".join(src) + "\n\n"


def is_square(plan) -> bool:
    """Whether the plan's kinetostatic system is square (as many unknowns as
    the bodies' 3 equations each), so that ``eliminated`` solves it."""
    nb, nj, ns = len(plan.body_names), len(plan.joint_names), len(plan.slide_names)
    ni = plan.n_inputs
    has_crank = plan.crank_body >= 0
    return nb > 0 and 2 * nj + 2 * ns + int(has_crank) + ni == 3 * nb and (has_crank or ni > 0)


def slide_angle(plan, names, k) -> str:
    """The expression of slide ``k``'s angle (rad; from its guide link where it
    turns with one): the declared angle, turned with the guide parameters it
    follows (a design variable turns the slide with its guide)."""
    follow = [int(i) for i in plan.slide_follow[k] if i >= 0]
    if not follow:
        return literal(float(plan.slide_angle[k]))
    return " + ".join([literal(float(plan.slide_angle[k] - plan.slide_declared[k]))]
                      + [f"par[PAR_{names.par(i)}]" for i in follow])


def eliminated(plan, names, lanes=False):
    """(lines, m) of a square plan's kinetostatics at one position (the body of
    ``forces_at``): the applied loads (``applied_loads`` into loads_out), the
    force-balance rows eliminated here, the m x m system left solved at run
    time, the reactions into r_out (slides and inputs into slide_out) and the
    returned M_bal.

    ``lanes``: the lines for the force lanes (``pipeline.compiler.lane_forces``),
    where no library call may stand: a slide's normal from the cos/sin of its
    angle, hoisted per candidate (``SLIDE_COS_k``, ``SLIDE_SIN_k``), and, for a
    slide that turns with a link, the link's unit vector turned by them, in
    place of atan2 and sin/cos at every position (the same direction, to
    rounding); a link of no length sets ``bad``."""
    s = _ForceSystem(plan, names, lanes)
    s.load_entries()
    s.joint_entries()
    for k in range(len(plan.slide_names)):
        s.slide_entries(k)
    if s.has_crank:
        s.add(3 * plan.crank_body + 2, s.col_m, 1.0)
    shares = [s.input_entries(k) for k in range(plan.n_inputs)]     # q' of every input
    pivots = s.eliminate()
    body, x, m = s.solve_remaining()
    body += s.back_substitution(pivots, x)
    body += s.outputs(shares)
    return body, m


class _ForceSystem:
    """The kinetostatic system of a square plan at one position, built in
    generated locals (``_Sym``): its entries A[(row, col)] and right-hand side
    b, three rows per body (x, y force balance, moment about the centre of
    mass); columns 2j, 2j + 1 joint j's reaction, then each slide's (N, C),
    the crank's balancing moment, each input's drive."""

    def __init__(self, plan, names, lanes):
        self.plan, self.names, self.lanes = plan, names, lanes
        self.nj, self.ns = len(plan.joint_names), len(plan.slide_names)
        self.n = 3 * len(plan.body_names)
        self.col_m = 2 * self.nj + 2 * self.ns
        self.has_crank = plan.crank_body >= 0
        self.col_in = self.col_m + int(self.has_crank)            # first input's drive
        self.sym = _Sym()
        self.L = self.sym.lines
        self.P = [names.I(i) for i in range(len(plan.point_names))]
        self.A: dict = {}                       # (row, col) -> entry
        self.b: dict = {}

    def add(self, r, c, v):
        """A[r, c] += v (a zero entry dropped)."""
        sym, A = self.sym, self.A
        old = A.get((r, c), 0.0)
        if isinstance(old, float) and isinstance(v, float):
            val = old + v
        elif isinstance(old, float) and old == 0.0:
            val = v
        else:
            val = sym.var(f"{_s(old)} + {_s(v)}")
        if isinstance(val, float) and val == 0.0:
            A.pop((r, c), None)
        else:
            A[(r, c)] = val

    def lever(self, p, s):
        """The lever (x, y) from point ``s`` to point ``p``, in m."""
        P, sym = self.P, self.sym
        return (sym.var(f"(pos[{P[p]}, 0] - pos[{P[s]}, 0]) * {MM}"),
                sym.var(f"(pos[{P[p]}, 1] - pos[{P[s]}, 1]) * {MM}"))

    def load_entries(self):
        """The right-hand side: the applied and inertia loads at each centre of mass."""
        L = self.L
        L.append("# applied and inertia loads reduced to each centre of mass: (Fx, Fy, M)")
        L.append("applied_loads(pos, d1, d2, omega1, eps1, GRAVITY, par, BODY_COM, BODY_TURN, "
                 "BODY_MASS_OFF,")
        L.append("              LOAD_BODY, LOAD_POINT, loads_k, loads_out)")
        for i in range(len(self.plan.body_names)):
            for k in range(3):
                self.b[3 * i + k] = self.sym.var(f"-loads_out[{i}, {k}]")

    def joint_entries(self):
        """Each revolute joint's reaction on both its bodies, and its moment."""
        plan, sym = self.plan, self.sym
        self.L.append("# revolute joints: R_j (force of the first body on the second) on "
                      "both bodies,")
        self.L.append("# with its moment about each body's centre of mass (levers in m)")
        for j in range(self.nj):
            p = int(plan.joint_point[j])
            for side in range(2):
                body = int(plan.joint_bodies[j, side])
                if body < 0:
                    continue
                sgn = 1.0 if side == 1 else -1.0
                lx, ly = self.lever(p, int(plan.body_com[body]))
                self.add(3 * body, 2 * j, sgn)
                self.add(3 * body + 1, 2 * j + 1, sgn)
                self.add(3 * body + 2, 2 * j, sym.mul(-sgn, ly))
                self.add(3 * body + 2, 2 * j + 1, sym.mul(sgn, lx))

    def slide_normal(self, k):
        """Slide ``k``'s unit normal (nx, ny): from atan2 and sin/cos of its angle,
        or in the lanes from the hoisted cos/sin (a turning guide's link vector
        turned by them; a link of no length sets ``bad``)."""
        plan, sym, P = self.plan, self.sym, self.P
        if self.lanes:
            c_, s_ = f"SLIDE_COS_{k}", f"SLIDE_SIN_{k}"
            if plan.slide_dir[k, 0] < 0:
                return sym.var(f"-{s_}"), sym.var(c_)
            a_, b_ = (int(v) for v in plan.slide_dir[k])
            dx = sym.var(f"pos[{P[b_]}, 0] - pos[{P[a_]}, 0]")
            dy = sym.var(f"pos[{P[b_]}, 1] - pos[{P[a_]}, 1]")
            r2 = sym.var(f"{dx} * {dx} + {dy} * {dy}")
            self.L.append(f"bad = bad | (not ({r2} > 0.0))")
            f = sym.var(f"1.0 / math.sqrt({r2})")
            return (sym.var(f"-({f} * ({s_} * {dx} + {c_} * {dy}))"),
                    sym.var(f"{f} * ({c_} * {dx} - {s_} * {dy})"))
        angle = slide_angle(plan, self.names, k)
        if plan.slide_dir[k, 0] >= 0:
            a_, b_ = (int(v) for v in plan.slide_dir[k])
            th = sym.var(f"math.atan2(pos[{P[b_]}, 1] - pos[{P[a_]}, 1], pos[{P[b_]}, 0] - "
                         f"pos[{P[a_]}, 0]) + {angle}")
        else:
            th = sym.var(angle)
        return sym.var(f"-math.sin({th})"), sym.var(f"math.cos({th})")

    def slide_entries(self, k):
        """Slide ``k``'s normal force N and moment C on both its bodies."""
        plan, sym = self.plan, self.sym
        sq = int(plan.body_com[int(plan.slide_bodies[k, 1])])
        nx, ny = self.slide_normal(k)
        col = 2 * self.nj + 2 * k
        for side in range(2):
            body = int(plan.slide_bodies[k, side])
            if body < 0:
                continue
            sgn = 1.0 if side == 1 else -1.0
            lx, ly = self.lever(sq, int(plan.body_com[body]))
            fx = sym.mul(sgn, nx)
            fy = sym.mul(sgn, ny)
            self.add(3 * body, col, fx)
            self.add(3 * body + 1, col, fy)
            self.add(3 * body + 2, col, sym.var(f"{lx} * {fy} - {ly} * {fx}"))
            self.add(3 * body + 2, col + 1, sgn)

    def input_entries(self, k):
        """Input ``k``'s drive (a moment on a rotary input's link, a force along a
        slider input's guide); returns its q' (the drive's share of M_bal)."""
        plan, sym = self.plan, self.sym
        body = int(plan.input_body[k])
        col = self.col_in + k
        a_, b_ = (self.P[int(v)] for v in plan.input_points[k])
        label = text(plan.input_names[k])
        if int(plan.input_kind[k]) == ROTARY:
            self.L.append(f"# input {label}: a drive moment on its link; q' = (r x r') / |r|^2")
            self.add(3 * body + 2, col, 1.0)
            return sym.var(
                f"((pos[{b_}, 0] - pos[{a_}, 0]) * (d1[{b_}, 1] - d1[{a_}, 1]) - "
                f"(pos[{b_}, 1] - pos[{a_}, 1]) * (d1[{b_}, 0] - d1[{a_}, 0])) / "
                f"((pos[{b_}, 0] - pos[{a_}, 0]) ** 2 + (pos[{b_}, 1] - pos[{a_}, 1]) ** 2)")
        self.L.append(f"# input {label}: a drive force along its guide at the block; "
                      "q' = u . (block' - guide point') in m")
        g = self.names.K(int(plan.input_group[k]), "guide_angle")
        if self.lanes:       # (the input's hoisted cos/sin of the same angle: the same bits)
            ux = sym.var(f"LANE_CONST({g}_cos)")
            uy = sym.var(f"LANE_CONST({g}_sin)")
        else:
            ux = sym.var(f"math.cos(par[PAR_{g}])")
            uy = sym.var(f"math.sin(par[PAR_{g}])")
        s_ = int(plan.body_com[body])
        lx = sym.var(f"(pos[{b_}, 0] - pos[{self.P[s_]}, 0]) * {MM}")
        ly = sym.var(f"(pos[{b_}, 1] - pos[{self.P[s_]}, 1]) * {MM}")
        self.add(3 * body, col, ux)
        self.add(3 * body + 1, col, uy)
        self.add(3 * body + 2, col, sym.var(f"{lx} * {uy} - {ly} * {ux}"))
        return sym.var(f"({ux} * (d1[{b_}, 0] - d1[{a_}, 0]) + "
                       f"{uy} * (d1[{b_}, 1] - d1[{a_}, 1])) * {MM}")

    def eliminate(self):
        """Symbolic elimination with exact +-1 pivots, least fill first; returns
        the pivots (row, col) in elimination order."""
        self.L.append("# elimination with the exact pivots +-1 of the force-balance rows")
        self.rows_left, self.cols_left = set(range(self.n)), set(range(self.n))
        pivots = []
        while (best := self._least_fill_pivot()) is not None:
            _, r, c = best
            self.rows_left.discard(r)
            self.cols_left.discard(c)
            pivots.append((r, c))
            self._eliminate_column(r, c)
        return pivots

    def _least_fill_pivot(self):
        """(fill, row, col) of the +-1 entry whose elimination fills in least."""
        A, rows_left, cols_left = self.A, self.rows_left, self.cols_left
        best = None
        for (r, c), v in A.items():
            if r in rows_left and c in cols_left and isinstance(v, float) and abs(v) == 1.0:
                rc = sum(1 for (r2, c2) in A if r2 == r and c2 in cols_left)
                cc = sum(1 for (r2, c2) in A if c2 == c and r2 in rows_left)
                cost = (rc - 1) * (cc - 1)
                if best is None or cost < best[0]:
                    best = (cost, r, c)
        return best

    def _eliminate_column(self, r, c):
        """Column ``c`` eliminated from the rows left by pivot row ``r``."""
        A, b, sym = self.A, self.b, self.sym
        piv = A[(r, c)]
        row = {c2: v for (r2, c2), v in A.items() if r2 == r and c2 in self.cols_left}
        for r2 in sorted(self.rows_left):
            f = A.get((r2, c))
            if f is None:
                continue
            f = f if piv == 1.0 else sym.mul(-1.0, f)      # multiplier a[r2, c] / piv
            A.pop((r2, c))
            for c2, v in row.items():
                self.add(r2, c2, sym.mul(sym.mul(-1.0, f), v))
            b[r2] = sym.sub(b[r2], sym.mul(f, b[r]))

    def solve_remaining(self):
        """(lines, x, m): the lines so far, then the m x m system left solved at
        run time, partial pivoting; x: the solved unknowns' locals by column."""
        A, b = self.A, self.b
        rem_r, rem_c = sorted(self.rows_left), sorted(self.cols_left)
        m = len(rem_r)
        body = list(self.L)
        body.append(f"# the remaining {m} x {m} system, partial pivoting at run time")
        body.append("ok = True")
        if m <= UNROLLED_MAX:
            a = [[_s(A.get((r, c), 0.0)) for c in rem_c] for r in rem_r]
            body += gauss_unrolled(a, [_s(b[r]) for r in rem_r]) if m else []
            solved = [f"gb{jj}" for jj in range(m)]
        else:
            for i, r in enumerate(rem_r):
                for jj, c in enumerate(rem_c):
                    body.append(f"work_a[{i}, {jj}] = {_s(A.get((r, c), 0.0))}")
                body.append(f"work_b[{i}] = {_s(b[r])}")
            body.append(f"ok = gauss_solve(work_a, work_b, {m})")
            solved = [f"work_b[{jj}]" for jj in range(m)]
        x = {}
        for c, value in zip(rem_c, solved):
            x[c] = f"x{c}"
            body.append(f"x{c} = {value}")
        return body, x, m

    def back_substitution(self, pivots, x):
        """The eliminated unknowns, back through the pivot rows (NaN where the
        run-time system is singular)."""
        out = ["# back substitution through the eliminated rows"]
        for r, c in reversed(pivots):
            piv = self.A[(r, c)]
            terms = [f"{_s(v)} * x{c2}" for (r2, c2), v in sorted(self.A.items())
                     if r2 == r and c2 != c and c2 in x]
            rhs = _s(self.b[r]) + "".join(f" - {t}" for t in terms)
            out.append(f"x{c} = {'' if piv == 1.0 else '-'}({rhs})")
            x[c] = f"x{c}"
        out.append("if not ok:")
        out.append("    " + " = ".join(f"x{c}" for c in range(self.n)) + " = math.nan")
        return out

    def outputs(self, shares):
        """The reactions into r_out, the slides' and inputs' into slide_out, and
        the returned M_bal (the crank's own plus each input's share)."""
        nj, ns, ni = self.nj, self.ns, self.plan.n_inputs
        out = []
        for j in range(nj):
            out += [f"r_out[{j}, 0] = x{2 * j}", f"r_out[{j}, 1] = x{2 * j + 1}"]
        for k in range(ns):
            out += [f"slide_out[{k}, 0] = x{2 * nj + 2 * k}",
                    f"slide_out[{k}, 1] = x{2 * nj + 2 * k + 1}"]
        if not ni:
            return out + [f"return x{self.col_m}"]
        out.append("# every input's drive, and its share of the main shaft's moment")
        share = [f"slide_out[{ns + k}, 1]" for k in range(ni)]
        if self.lanes:               # (the lanes keep no slide_out: locals)
            share = [f"drive_share{k}" for k in range(ni)]
        for k in range(ni):
            if not self.lanes:
                out.append(f"slide_out[{ns + k}, 0] = x{self.col_in + k}")
            out.append(f"{share[k]} = x{self.col_in + k} * {shares[k]}")
        total = " + ".join(([f"x{self.col_m}"] if self.has_crank else []) + share)
        return out + [f"return {total}"]
