"""Where the main job's kernels spend their time, by kernel, with ``perf``.

    python benchmarks/bench_profile.py [--chunks 30] [--smoke] [-o DIR]

numba's compiled kernels have no symbols that ``perf`` can see, so a profile of a
sweep shows addresses only.  This script runs the main job's chunks on one thread
(``studies/ov7_synthesis.toml``, its kernels cached) under ``perf record`` and
first writes ``/tmp/perf-PID.map``: every loaded kernel's functions, named from
its object code (kept as numba loads it from its cache) with their addresses in
numba's engine, which ``perf report`` reads.  The table gives each function's share
of the samples: the kernels by name (``walk``: the lane walk, ``force_lanes``,
``settle``, ...), libm's ``sincos``, the interpreter.  The speed guide's profile
of 2026-12-06 was taken so.

--smoke (the suite: that it runs): two small chunks, no ``perf``; the map written
to a temporary file and checked to name the lane walk.  Writes DIR/profile.md
(default results/bench/).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import ROOT, STUDIES, hardware  # noqa: E402

_OBJECTS: dict[int, bytes] = {}     # id(code library) -> its object code


def keep_object_code() -> bool:
    """From now on keep each code library's object code as numba loads or builds
    it (numba frees it once the library is in its engine).  False where this
    numba has no such step (another version: no map then)."""
    from numba.core import codegen
    cls = codegen.CPUCodeLibrary
    original = getattr(cls, "_set_compiled_object", None)
    if original is None:
        return False

    def keep(self, value):          # (loaded from numba's cache)
        _OBJECTS[id(self)] = value
        return original(self, value)
    cls._set_compiled_object = keep
    compiled = cls._object_compiled_hook.__func__

    def keep_compiled(klass, ll_module, buf):  # (compiled here: numba's engine says so)
        compiled(klass, ll_module, buf)
        lib = getattr(ll_module, "_CPUCodeLibrary__library", None)
        if lib is not None:
            _OBJECTS[id(lib.__repr__.__self__)] = buf
    cls._object_compiled_hook = classmethod(keep_compiled)
    return True


def readable(symbol: str) -> str:
    """numba's mangled name as module.function (a generated module: ``mechanism``)."""
    m = re.match(r"_ZN(.*)", symbol)
    if not m:
        return symbol
    rest, parts = m.group(1), []
    while rest and rest[0].isdigit():
        n = re.match(r"\d+", rest).group(0)
        rest = rest[len(n):]
        parts.append(rest[:int(n)])
        rest = rest[int(n):]
    name = ".".join(re.sub(r"^pipeline_(mech|plan)_[0-9a-f]+$", r"\1", p) for p in parts)
    return name or symbol


def write_perf_map(path: Path) -> list[tuple[int, int, str]]:
    """Every function of every loaded kernel's object code: (address, size, name),
    written as perf's map of this process's compiled code."""
    import gc

    from numba.core.dispatcher import Dispatcher
    rows, seen = set(), set()
    for d in [o for o in gc.get_objects() if isinstance(o, Dispatcher)]:
        for cres in list(d.overloads.values()):
            lib = getattr(cres, "library", None)
            obj = _OBJECTS.get(id(lib))
            if lib is None or obj is None or id(lib) in seen:
                continue
            seen.add(id(lib))
            with tempfile.NamedTemporaryFile(suffix=".o") as f:
                f.write(obj)
                f.flush()
                out = subprocess.run(["nm", "-S", "--defined-only", f.name],
                                     capture_output=True, text=True).stdout
            for line in out.splitlines():
                parts = line.split()
                if len(parts) == 4 and parts[2] in "tTwW":
                    address = lib.get_pointer_to_function(parts[3])
                    if address:
                        rows.add((address, int(parts[1], 16), parts[3]))
    rows = sorted(rows)
    path.write_text("".join(f"{a:x} {s:x} {readable(n)}\n" for a, s, n in rows))
    return rows


def child(chunks: int, map_path: Path | None) -> None:
    """The profiled process: the main job's kernels loaded, the map written, then
    ``chunks`` chunks evaluated on this thread."""
    keep_object_code()
    from pipeline.runs.problem import plain_problem
    from pipeline.study.reader import load_study
    study = load_study(STUDIES / "ov7_synthesis.toml")
    spec = study.sweep
    # (as `pipeline run --candidates`: enough chunks for the profile)
    spec = spec.with_candidates(max(spec.candidates, (chunks + 1) * spec.chunk_size))
    problem = plain_problem(study, spec)
    problem.evaluate_chunk(0, parallel=False)       # (the kernels loaded)
    rows = write_perf_map(map_path or Path(f"/tmp/perf-{os.getpid()}.map"))
    print(f"map: {len(rows)} functions")
    for c in range(1, chunks + 1):
        problem.evaluate_chunk(c, parallel=False)


def profile(chunks: int, out: Path) -> list[tuple[float, str]]:
    """(percent, function) of ``perf record`` over a child process's chunks."""
    data = out / "perf.data"
    run = subprocess.run(["perf", "record", "-q", "-F", "999", "-o", str(data), "--",
                          sys.executable, __file__, "--child", str(chunks)],
                         capture_output=True, text=True, cwd=ROOT,
                         env=dict(os.environ, OPENBLAS_THREAD_TIMEOUT="4"))   # (as the CLI)
    if run.returncode != 0:
        raise SystemExit(f"perf record failed: {run.stderr.strip()[-500:]}")
    rep = subprocess.run(["perf", "report", "-i", str(data), "--no-children", "--stdio",
                          "--sort", "sym"], capture_output=True, text=True).stdout
    data.unlink()
    rows = []
    for line in rep.splitlines():
        m = re.match(r"\s*([\d.]+)%\s+\[[.k]\]\s+(.*)", line)
        if m:
            rows.append((float(m.group(1)), m.group(2).strip()))
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--chunks", type=int, default=30)
    ap.add_argument("--smoke", action="store_true")
    ap.add_argument("--child", type=int, default=None, help=argparse.SUPPRESS)
    ap.add_argument("-o", "--out", type=Path, default=ROOT / "results" / "bench")
    a = ap.parse_args(argv)
    if a.child is not None:
        child(a.child, None)
        return 0
    a.out.mkdir(parents=True, exist_ok=True)
    head = ["# Where the main job's kernels spend their time\n", f"Machine: {hardware()}.\n"]
    if a.smoke:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "perf.map"
            child(2, path)
            names = [line.split(" ", 2)[2] for line in path.read_text().splitlines()]
        if not any(n.endswith(".walk") for n in names):
            raise SystemExit(f"the map names no lane walk: {names[:10]}")
        body = [f"Smoke: the map names {len(names)} functions, the lane walk among them; "
                "perf not run.\n"]
    elif shutil.which("perf") is None:
        raise SystemExit("perf is not installed here (Debian: linux-perf)")
    else:
        rows = profile(a.chunks, a.out)
        body = [f"{a.chunks} chunks of the main job on one thread, `perf record` at 999 Hz; "
                "each function's share of the samples:\n", "| % | function |", "|---|---|"]
        body += [f"| {p:.2f} | {name} |" for p, name in rows[:30]]
    text = "\n".join(head + body) + "\n"
    (a.out / "profile.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
