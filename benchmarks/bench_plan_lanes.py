"""Could the sweep's lane walk run on the plan path? The generated walk against the same
walk split into one kernel per group, as a plan path would call them.

    python benchmarks/bench_plan_lanes.py [--blocks 40] [--rounds 5] [--smoke] [-o DIR]

Issue 53 asks that a new mechanism's sweep start at once, on kernels compiled once per
installation that read the mechanism's plan as data, while its generated module compiles.
The careful path alone is 17-24 times slower than the lanes (``bench_sweep.py``), too slow
to pay; a plan path would need the lane walk.  This measures what such a walk would cost,
before anyone builds it: the main job's generated ``walk`` (its sweep module, compiled) is
cut at its groups' comments into one kernel per group (the careful path's forms do the same
for ``position``: ``pipeline.compiler.plan_path``), each with its own lane loop, called in
turn from a loop over the groups, as a plan path would dispatch them:

* a group's rows of the lane table at a run-time base: the kernel gets a view of the table
  from its first row (its rows at constant offsets within it, as a form's constants sit in
  the plan), so that LLVM sees rows a constant stride apart, as in the generated walk;
* the values one group hands the next (point coordinates, the flags, the margin) in rows
  of a scratch table that the loop copies in before each kernel and out after it, by
  indices read at run time (as a plan's point indices are);
* nothing else changed: the same lines, the same flags (FMA contraction).

Both walks run on the same blocks of the main job's candidates (set up by the module's
``setup_lane``), alternated; the table says whether the lane table and the walk's outputs
are the same to the bit, and the time per block of each (the generated walk takes its lanes
in pairs, the split one at a time: the run fails where they differ, so the suite's smoke run
holds the pairs to the one-lane walk's bits).  --smoke (the suite): two blocks, one round.
Writes DIR/plan_lanes.md.  A measurement, not product code: nothing in
``pipeline`` calls the split walk.
"""

from __future__ import annotations

import argparse
import ast
import hashlib
import re
import sys
import textwrap
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import ROOT, STUDIES, hardware, write_table  # noqa: E402

_IND = " " * 12         # the lane loop's body in the generated walk
_OUTER = {"S", "theta", "k", "cph", "sph", "armed", "tol", "jump", "step_change",
          "margin_safe", "close", "watch_floor", "l", "math", "LANES", "MARGIN_COL",
          "min", "max", "abs", "float"}
_FLAGS = {"bad", "low", "big"}      # booleans handed on (as 0.0 / 1.0 in the scratch)


def _pieces(src):
    """(the lane loop's body cut at each group's comment, the lines after the loop) of
    the generated ``walk`` in module source ``src``."""
    walk = re.search(r"^def walk\(S.*?(?=^\S)", src, re.S | re.M).group(0).splitlines()
    start = next(i for i, x in enumerate(walk) if x.strip().startswith("for l in range(n_lanes"))
    end = next(i for i, x in enumerate(walk) if x.strip().startswith("if k == k_close:"))
    chunks, cur = [], []
    for line in walk[start + 1:end]:
        if re.search(r"HALF \+ l\]|\b\w+_h\b", line):
            continue        # (the second lane of a pair: the split walks one at a time)
        if line.startswith((_IND + "# group ", _IND + "# the output rocker")) and cur:
            chunks.append(cur)
            cur = []
        cur.append(line[len(_IND):])
    return chunks + [cur], textwrap.dedent("\n".join(walk[end:]))


def _reads_writes(lines):
    """(names read before the piece writes them, names it writes)."""
    read, wrote = set(), set()
    for st in ast.parse("\n".join(lines)).body:
        loads = {n.id for n in ast.walk(st) if isinstance(n, ast.Name)
                 and isinstance(n.ctx, ast.Load)}
        if isinstance(st, ast.AugAssign):
            loads.add(st.target.id)
        read |= {x for x in loads if x not in wrote}
        wrote |= {n.id for n in ast.walk(st) if isinstance(n, ast.Name)
                  and isinstance(n.ctx, ast.Store)}
    return read, wrote


def split_source(mod_name, src, copied=True):
    """The split walk's module: ``chunk_i`` per group, ``split_walk``; its tables
    (N_CHUNKS, BASES, IN_ROWS, OUT_ROWS, N_HANDED) as constants.  Not ``copied``: each
    kernel reads and writes the handed values at their own rows of the scratch, fixed
    when the module is written (no run-time indices: the cost of the split alone)."""
    # the walk reads row r at its start W_r (= R_r * LANES); written back as R_r * LANES
    src = re.sub(r"\bS\[W_(\w+) \+ ", r"S[R_\1 * LANES + ", src)
    chunks, tail = _pieces(src)
    rows = {m.group(1): int(m.group(2)) for m in re.finditer(r"^(R_\w+) = (\d+)", src, re.M)}
    rw = [_reads_writes(c) for c in chunks]
    handed = sorted({x for read, _ in rw for x in read
                     if x not in _OUTER and not x.startswith("R_")})
    slot = {x: j for j, x in enumerate(handed)}
    out = [f"from {mod_name} import *", "from pipeline.kernels.config import JIT_LANES",
           "import math", "import numpy as np", "from numba import njit", ""]
    bases, ins, outs = [], [], []
    for i, (lines, (read, wrote)) in enumerate(zip(chunks, rw)):
        text = "\n".join(lines)
        used = sorted({rows[r] for r in re.findall(r"\b(R_\w+)\b", text)})
        base = used[0] if used else 0
        text = re.sub(r"\bS\[(R_\w+) \* LANES \+ l\]",
                      lambda m, b=base: f"S[{rows[m.group(1)] - b} * LANES + l]", text)
        if "R_" in text:
            raise ValueError(f"group piece {i}: a row of the lane table read otherwise than "
                             "as S[R * LANES + l]")
        mine_in = [x for x in handed if x in read]
        mine_out = [x for x in handed if x in wrote]
        body = ["@njit(**JIT_LANES)",
                f"def chunk_{i}(S, H, n_lanes, theta, k, cph, sph, armed, tol, jump, "
                "step_change, margin_safe, close, watch_floor):",
                "    for l in range(n_lanes):"]
        for j, x in enumerate(mine_in):
            v = f"H[{j if copied else slot[x]} * LANES + l]"
            body.append(f"        {x} = {v} != 0.0" if x in _FLAGS else f"        {x} = {v}")
        body += ["        " + t for t in text.splitlines()]
        for j, x in enumerate(mine_out):
            v = f"(1.0 if {x} else 0.0)" if x in _FLAGS else x
            row = len(mine_in) + j if copied else slot[x]
            body.append(f"        H[{row} * LANES + l] = {v}")
        out += body + ["", ""]
        bases.append(base)
        ins.append([slot[x] for x in mine_in])
        outs.append([slot[x] for x in mine_out])
    if not copied:      # (the loop copies nothing)
        ins, outs = [[] for _ in ins], [[] for _ in outs]
    width = max(1, max(len(a) for a in ins))
    args = ("S[bases[g] * LANES:], H, n_lanes, theta, k, cph, sph, armed, tol, jump, "
            "step_change, margin_safe, close, watch_floor")
    disp = []
    for i in range(len(chunks)):
        disp += [f"            {'if' if i == 0 else 'elif'} g == {i}:",
                 f"                chunk_{i}({args})"]
    out += ["@njit(**JIT_LANES)",
            "def split_walk(S, n_lanes, theta, cph_tab, sph_tab, k_end, k_close, tol, jump,",
            "               step_change, margin_safe, close, watch_floor, X, H, bases, n_in,",
            "               in_rows, n_out, out_rows):",
            "    for k in range(1, k_end):",
            "        cph = cph_tab[k]",
            "        sph = sph_tab[k]",
            "        armed = k >= 3",
            "        for g in range(bases.shape[0]):",
            "            for q in range(n_in[g]):        # the group's inputs, from their rows",
            "                r = in_rows[g, q]",
            "                for l in range(LANES):",
            "                    H[q * LANES + l] = X[r * LANES + l]"] + disp + [
            "            for q in range(n_out[g]):       # and its outputs, to theirs",
            "                r = out_rows[g, q]",
            "                for l in range(LANES):",
            "                    X[r * LANES + l] = H[(n_in[g] + q) * LANES + l]"]
    out += ["        " + t for t in tail.splitlines()]
    pad = [a + [0] * (width - len(a)) for a in ins]
    pado = [a + [0] * (max(1, max(map(len, outs))) - len(a)) for a in outs]
    out += ["", f"N_CHUNKS = {len(chunks)}", f"N_HANDED = {len(handed)}", f"BASES = {bases}",
            f"IN_ROWS = {pad}", f"N_IN = {[len(a) for a in ins]}", f"OUT_ROWS = {pado}",
            f"N_OUT = {[len(a) for a in outs]}", ""]
    return "\n".join(out)


def _blocks(pb, n_blocks):
    """``n_blocks`` full blocks of the main job's candidates set up in lanes, and
    the walk's arguments after theta."""
    from pipeline.kernels import config as kc
    from pipeline.kernels.sweep import SET_MARGIN_SAFE
    mod = pb.kernels
    _, _, pars = pb.draw_chunk(0)
    pars = np.ascontiguousarray(pars)
    phis, tols, close, npos = pb.phis, pb.tols, pb.phi_close, len(pb.phis)
    ang = np.array([phis[k] if k < npos else close + (phis[k - npos] - phis[0])
                    for k in range(npos + 3)])
    pos, d1, d2, margins, state, _ = mod.work(mod.N_POINTS, mod.N_GROUPS, mod.N_TRIADS)
    called = mod.callees()      # (the addresses of the kernels setup_lane calls)
    blocks, i = [], 0
    while len(blocks) < n_blocks:
        S = np.empty((mod.N_LANE_ROWS, mod.LANES))
        theta = np.zeros((npos + 3, mod.LANES * mod.THETA_COLS))
        lane = 0
        while lane < mod.LANES:
            if mod.setup_lane(pars, i, np.int64(lane), phis, close, tols, S, theta, pos, d1,
                              d2, margins, state, called) == 0:
                lane += 1
            i += 1
        blocks.append((S, theta))
    s = pb.settings()
    rest = (np.cos(ang), np.sin(ang), npos + 3, npos, tols[kc.T_NEWTON_TOL], tols[kc.T_JUMP],
            tols[kc.T_STEP_CHANGE], s[SET_MARGIN_SAFE], tols[kc.T_CLOSE], tols[kc.T_WATCH])
    return blocks, rest


def measure(n_blocks, rounds, echo=print):
    """{'same': bool, 'generated': s/block, 'split': s/block, 'groups': n}."""
    from pipeline.compiler import _imported
    from pipeline.runs.sweep import build_problem
    from pipeline.study.reader import load_study
    study = load_study(STUDIES / "ov7_synthesis.toml")
    pb = build_problem(study, study.sweep.with_candidates(max(2_000, 40 * n_blocks)))
    mod = pb.kernels
    blocks, rest = _blocks(pb, n_blocks)
    lanes = mod.LANES
    walks = {"generated": lambda S, th: mod.walk(S.reshape(-1), lanes, th, *rest)}
    for name, copied in (("split, rows fixed", False), ("split, rows at run time", True)):
        src = split_source(mod.__name__, Path(mod.SOURCE_PATH).read_text(), copied)
        split = _imported(src, "bench_split_walk_" + hashlib.sha256(src.encode()).hexdigest()[:16])
        walks[name] = _split_call(split, lanes, rest)
    groups = split.N_CHUNKS

    def run(walk):
        outs = [(S.copy(), th.copy()) for S, th in blocks]
        t = time.perf_counter()
        for S, th in outs:
            walk(S, th)
        return time.perf_counter() - t, outs

    t0 = time.perf_counter()
    outs = {name: run(w)[1] for name, w in walks.items()}  # (compiled, or loaded)
    echo(f"the walks compiled or loaded in {time.perf_counter() - t0:.1f} s")
    same = {name: all(np.array_equal(x, y, equal_nan=True)
                      for p, q in zip(outs["generated"], o) for x, y in zip(p, q))
            for name, o in outs.items()}
    times = {name: [] for name in walks}
    for _ in range(rounds):
        for name, w in walks.items():
            times[name].append(run(w)[0] / n_blocks)
    return {"same": same, "seconds": {k: min(v) for k, v in times.items()}, "groups": groups,
            "lanes": lanes, "blocks": n_blocks, "rounds": rounds}


def _split_call(split, lanes, rest):
    """A split module's walk, called as the generated one (its scratch and tables)."""
    X = np.zeros(split.N_HANDED * lanes)
    H = np.zeros(max(split.N_HANDED, max(split.N_IN) + max(split.N_OUT)) * lanes)
    tables = (np.array(split.BASES, np.int64), np.array(split.N_IN, np.int64),
              np.array(split.IN_ROWS, np.int64).reshape(split.N_CHUNKS, -1),
              np.array(split.N_OUT, np.int64),
              np.array(split.OUT_ROWS, np.int64).reshape(split.N_CHUNKS, -1))

    def walk(S, th):
        split.split_walk(S.reshape(-1), lanes, th, *rest, X, H, *tables)
    return walk


def table(r):
    t = r["seconds"]
    rows = [f"| {name} | {s * 1e3:.3f} | {s / t['generated']:.2f} | "
            f"{'yes' if r['same'][name] else 'no'} |" for name, s in t.items()]
    return "\n".join([
        "# The lane walk split per group, as a plan path would run it", "",
        f"hardware: {hardware()}", "",
        f"The main job's generated `walk` against the same lines in {r['groups']} group "
        f"kernels (`benchmarks/bench_plan_lanes.py`), {r['blocks']} blocks of {r['lanes']} "
        f"lanes, best of {r['rounds']} alternated rounds; the values one group hands the "
        "next at rows fixed when the module is written, or copied in and out by rows read "
        "at run time (as a plan's).", "",
        "| walk | ms per block | against the generated | lane table and outputs the same "
        "to the bit |", "|---|---|---|---|", *rows, ""])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--blocks", type=int, default=40)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--smoke", action="store_true", help="two blocks, one round")
    ap.add_argument("-o", "--out", default=str(ROOT / "results" / "bench"))
    a = ap.parse_args(argv)
    r = measure(2 if a.smoke else a.blocks, 1 if a.smoke else a.rounds)
    text = table(r)
    write_table(a.out, "plan_lanes.md", text)
    if not all(r["same"].values()):
        # (the generated walk takes its lanes in pairs, the split one lane at a time:
        # the same operations on each lane, so the suite's smoke run holds them equal)
        raise SystemExit(f"the walks differ: {r['same']}")
    return r


if __name__ == "__main__":
    main()
