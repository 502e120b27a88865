#!/usr/bin/env bash
# The GPU's checks in one call of the device tool (issue 54), from the repository root:
#
#     bash benchmarks/gpu_session.sh            # on a lent GPU machine: at most 8 minutes
#     bash benchmarks/gpu_session.sh --smoke    # under numba's CUDA simulator, tiny sizes
#
# It runs the real-GPU tests (pytest -m gpu), benchmarks/bench_gpu.py at 10^6, 10^7 and
# 10^8 candidates of the default study (a size the last rate says would not finish in
# time is left out, saying so) and benchmarks/bench_host.py (the host's side alone at
# 10^7: the ceiling of the end to end rate there), each step under a time limit, and
# writes one table,
# gpu_session.md, with the machine, the driver, the numba and numba-cuda versions and every
# step's figures, and each step's whole log beside it: into $OUT (the device tool's folder
# that comes back), else --out DIR, else results/gpu_session/.  The suite runs --smoke
# (tests/test_bench_scripts.py), so the script cannot rot.
#
# A package the machine's image lacks travels as a wheel in .whl/ (docs/guide/gpu.md): the
# script installs what is there into /tmp/site first.
set -u -o pipefail

smoke=0
out="${OUT:-}"
while [ $# -gt 0 ]; do
  case "$1" in
    --smoke) smoke=1 ;;
    --out) out="${2:?gpu_session.sh: --out needs a folder}"; shift ;;
    *) echo "gpu_session.sh: error: unknown option $1 (--smoke, --out DIR)" >&2; exit 2 ;;
  esac
  shift
done
cd "$(dirname "$0")/.." || exit 2
out="${out:-results/gpu_session}"
mkdir -p "$out" || exit 2
PY="${PYTHON:-python3}"
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}" PYTHONUNBUFFERED=1
if compgen -G ".whl/*.whl" > /dev/null; then
  "$PY" -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target /tmp/site .whl/*.whl > "$out/wheels.log" 2>&1 \
    && export PYTHONPATH="$PYTHONPATH:/tmp/site"
fi

if [ "$smoke" = 1 ]; then
  export NUMBA_ENABLE_CUDASIM=1
  bench=(--smoke)
  host=(--smoke)
  limits=(300 300 300)
else
  unset NUMBA_ENABLE_CUDASIM
  # 10^8 end to end is left out where the 10^7 rate says it would take over 150 s
  bench=(--sizes 1000000 10000000 100000000 --repeat 3 --max-seconds 150)
  host=(--sizes 10000000)
  limits=(150 270 60)
fi

step() {   # step NAME LIMIT_S COMMAND...: its log in $out/NAME.log, its exit status kept
  local name=$1 limit=$2
  shift 2
  local t0=$SECONDS
  timeout "$limit" "$@" > "$out/$name.log" 2>&1
  local rc=$?
  echo "$rc $((SECONDS - t0))" > "$out/$name.rc"
  echo "gpu_session.sh: $name: exit $rc after $((SECONDS - t0)) s (limit $limit s)"
}

{
  date -u +"date: %Y-%m-%d %H:%M UTC"
  if command -v nvidia-smi > /dev/null; then
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1 \
      | sed 's/^/nvidia-smi: /'
  else
    echo "nvidia-smi: none here"
  fi
  "$PY" -c "
import importlib.metadata as m, sys
print('python:', sys.version.split()[0])
for name in ('numba', 'numba-cuda', 'numpy'):
    try:
        print(name + ':', m.version(name))
    except m.PackageNotFoundError:
        print(name + ': not installed')"
  "$PY" -m pipeline.cli doctor 2>&1 | sed 's/^/doctor: /'
} > "$out/machine.log" 2>&1

step tests "${limits[0]}" "$PY" -m pytest -m gpu -n 0 -q -p no:cacheprovider -rs tests/runs/test_gpu.py
step bench "${limits[1]}" "$PY" benchmarks/bench_gpu.py "${bench[@]}"
step host "${limits[2]}" "$PY" benchmarks/bench_host.py "${host[@]}" --output "$out"

"$PY" - "$out" "$smoke" <<'EOF'
"""gpu_session.md: one table of what the logs say."""
import sys
from pathlib import Path

out, smoke = Path(sys.argv[1]), sys.argv[2] == "1"


def log(name):
    p = out / f"{name}.log"
    return p.read_text(errors="replace").splitlines() if p.exists() else []


def status(name):
    p = out / f"{name}.rc"
    rc, s = (p.read_text().split() if p.exists() else ("?", "?"))
    return {"0": "passed", "124": "stopped at its time limit"}.get(rc, f"exit {rc}") + f", {s} s"


rows = [("machine", line.split(": ", 1)[0], line.split(": ", 1)[-1]) for line in log("machine")
        if ": " in line]
tests = [line for line in log("tests") if " passed" in line or " skipped" in line
         or " failed" in line or " error" in line or line.startswith("SKIPPED")]
rows += [("pytest -m gpu", status("tests"), "; ".join(tests[-3:]) or "no summary line")]
keep = ("device:", "compile,", "CUDA kernel", "force stage:", "kernel only",
        "stages end to end:", "end to end,", "profiled end to end,")
rows += [("bench_gpu.py", status("bench"), "")]
rows += [("bench_gpu.py", line.split(":", 1)[0], line.split(":", 1)[1].strip())
         for line in log("bench") if line.startswith(keep)]
rows += [("bench_host.py", status("host"), "")]
rows += [("bench_host.py", line.split(":", 1)[0], line.split(":", 1)[1].strip())
         for line in log("host") if line.startswith(("drawing a chunk", "host alone,"))]
title = "under numba's CUDA simulator (--smoke: sizes and times mean nothing)" if smoke else \
    "on the lent GPU"
text = [f"# GPU session {title}", "", "| step | what | result |", "|---|---|---|"]
text += [f"| {a} | {b} | {c.replace('|', '/')} |" for a, b, c in rows]
text += ["", "Each step's whole log is beside this file (machine.log, tests.log, bench.log, "
         "host.log; host.md: bench_host.py's table)."]
(out / "gpu_session.md").write_text("\n".join(text) + "\n")
print("\n".join(text))
EOF
# the exit status: 0 where every step passed (the table is written either way)
for name in tests bench host; do
  read -r rc _ < "$out/$name.rc" && [ "$rc" = 0 ] || exit 1
done
