"""The mechanism compiler: from a mechanism's plan, the Python source of
kernels specialised to it, written to a cache folder and imported from there.

``kernels_for(plan)`` returns the imported module (see ``generate`` for its
kernels).  The module's name is the hash of its source, and the source
carries a digest of the kernel library it calls, so:

* the same mechanism in a later run imports the same file, and numba's
  on-disk cache (``cache=True``) compiles nothing the second time;
* a change of the mechanism, of an emitter or of a library kernel gives a new
  file (a stale compiled kernel is never reused).

The folder is ``$PIPELINE_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/pipeline``
(``~/.cache/pipeline``).  Files are written to a temporary name and renamed,
so concurrent processes (Dask workers) never import half a file.  Nothing is
passed to exec or eval: the module is imported like any other.
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import os
import sys
import threading
import weakref
from pathlib import Path

from ..base.files import write_text
from ..base.processes import module_command
from ..kernels.config import LANE_WIDTH as LANES   # candidates per block of the lane path
from .generate import defined_functions, generate

_LOCK = threading.Lock()
_MODULES: dict[str, object] = {}
_DIGEST: dict[bool, str] = {}


def cache_dir() -> Path:
    env = os.environ
    return _cache_dir(env.get("PIPELINE_CACHE_DIR"), env.get("XDG_CACHE_HOME"), env.get("HOME"))


@functools.lru_cache(maxsize=16)
def _cache_dir(folder, xdg, home) -> Path:
    """The folder of ``cache_dir`` for these settings: kept, since every
    ``structure_key`` asks (a refined peak's trial angles: 40 us each, of
    Path.home() mostly)."""
    if folder:
        return Path(folder)
    return Path(xdg or Path.home() / ".cache") / "pipeline"


def library_digest(lanes=True) -> str:
    """Digest of every kernel and compiler source the generated modules depend
    on, and of the floating-point flags they are compiled with: the lane walk's
    only where ``lanes`` (a module without an output rocker has no lane walk,
    so PIPELINE_FASTMATH=strict and the default share it)."""
    if lanes not in _DIGEST:
        here = Path(__file__).resolve().parent
        files = (sorted(here.glob("*.py")) + sorted((here / "skeleton").glob("*.py"))
                 + sorted((here.parent / "kernels").glob("*.py"))
                 + sorted((here.parent / "group_types").glob("**/*.py")))
        h = hashlib.sha256()
        from ..kernels.config import FASTMATH, LANE_FASTMATH
        for flags in (FASTMATH, LANE_FASTMATH) if lanes else (FASTMATH,):    # the flags too
            h.update(repr(sorted(flags) if flags else "strict").encode())
        for f in files:
            h.update(str(f.relative_to(here.parent)).encode())
            h.update(f.read_bytes())
        _DIGEST[lanes] = h.hexdigest()[:16]
    return _DIGEST[lanes]


def source_for(plan, rocker=None, watch=True) -> str:
    """The generated source of ``plan``'s kernels (``rocker``: the output
    rocker's (pivot, point) names, for the sweep's positions stage; ``watch``:
    False only for the benchmark of the watch's cost).  With a rocker, the
    sweep's module, which imports every kernel the rocker does not change from
    the module of ``plan`` without one (``source_for(plan, None, watch)``)."""
    shared = None
    if rocker is not None:
        base = source_for(plan, None, watch)
        shared = (module_name(base), defined_functions(base))
    return generate(plan, rocker=rocker, digest=library_digest(rocker is not None),
                    lanes_width=LANES, watch=watch, shared=shared)


def module_name(source: str) -> str:
    return "pipeline_mech_" + hashlib.sha256(source.encode()).hexdigest()[:20]


def structure_key(plan, rocker=None, watch=True) -> tuple:
    """What the generated source depends on: the plan's structure (not its
    parameter values) and the rocker; a cheap key for the modules in memory."""
    return (*_structure(plan), tuple(rocker) if rocker is not None else None, bool(watch),
            str(cache_dir()))


# id(plan) -> (a weak reference to the plan, its structure): a Plan is frozen, and a
# scene's refined peaks and flywheel ask for its structure at every evaluation (27 us)
_STRUCTURES: dict[int, tuple] = {}


def _structure(plan) -> tuple:
    """The plan's own part of ``structure_key``, kept per plan object."""
    hit = _STRUCTURES.get(id(plan))
    if hit is not None and hit[0]() is plan:
        return hit[1]
    arrays = (plan.codes, plan.gidx, plan.goff, plan.fixed_idx, plan.fixed_off, plan.link_a,
              plan.link_b, plan.body_com, plan.body_turn, plan.body_mass_off, plan.joint_point,
              plan.joint_bodies, plan.slide_bodies, plan.slide_dir, plan.slide_angle,
              plan.slide_follow, plan.slide_declared,
              plan.load_body, plan.load_point, plan.input_group, plan.input_kind,
              plan.input_law, plan.input_points, plan.input_body)
    tables = tuple(None if t is None else (t[0].tobytes(), t[1].tobytes())
                   for t in plan.input_tables)
    made = (tuple(a.tobytes() for a in arrays), tables, plan.point_names, plan.par_names,
            plan.group_names, plan.n_visible, plan.n_kinematic, plan.crank_body, plan.gravity)
    key = id(plan)
    _STRUCTURES[key] = (weakref.ref(plan, lambda _, key=key: _STRUCTURES.pop(key, None)), made)
    return made


_BY_STRUCTURE: dict[tuple, object] = {}


def kernels_for(plan, rocker=None, watch=True):
    """The generated kernels of ``plan``, imported (written first if new)."""
    key = structure_key(plan, rocker, watch)
    mod = _BY_STRUCTURE.get(key)
    if mod is not None:
        return mod
    if rocker is not None:
        kernels_for(plan, None, watch)      # the module the sweep's imports from: written
    src = source_for(plan, rocker, watch)
    mod = _imported(src, module_name(src))
    _BY_STRUCTURE[key] = mod
    if rocker is not None:
        _compile_beside(mod)
    return mod


def _compile_beside(mod, kernel="walk", *what) -> None:
    """Where ``mod``'s ``kernel`` (a sweep module's lane walk; with ``what`` =
    ("scene",), a module's forces_curve) is not in numba's cache yet and this
    process may use two cores or more: a process of its own compiles it, and
    what goes with it, into the cache meanwhile (``pipeline.compiler.beside``).
    ``PIPELINE_COMPILE_BESIDE=0`` turns it off."""
    if (os.environ.get("PIPELINE_COMPILE_BESIDE", "1") == "0"
            or os.environ.get("NUMBA_DISABLE_JIT", "0") not in ("", "0")
            or not hasattr(mod, kernel)
            or (kernel == "walk" and not getattr(mod, "HAS_LANES", False))):
        return
    from .parallel import default_jobs
    if default_jobs() < 2:
        return
    try:        # the index numba's cache keeps of the kernel's compiled versions
        if Path(getattr(mod, kernel)._cache._cache_file._index_path).exists():
            return
    except AttributeError:      # another numba: look no further, compile beside
        pass
    import subprocess
    path = Path(mod.SOURCE_PATH)
    for key, proc in list(_BESIDE.items()):     # (those that ended: reaped, forgotten)
        if proc is None or proc.poll() is not None:
            del _BESIDE[key]
    argv, env = module_command("pipeline.compiler.beside", mod.__name__, str(path.parent), *what)
    try:
        _BESIDE[(mod.__name__, kernel)] = subprocess.Popen(
            argv, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL)
    except OSError:         # no second process: the run compiles them itself
        pass


_BESIDE: dict[tuple, object] = {}     # (module, kernel): its process beside (Popen)


def await_beside(mod, kernel, timeout=120.0) -> None:
    """Where a process beside this one compiles ``mod``'s ``kernel`` (started by
    this process: ``_compile_beside``), wait for it (at most ``timeout``
    seconds): the kernel then loads from numba's cache, instead of compiling a
    second time here."""
    proc = _BESIDE.pop((getattr(mod, "__name__", None), kernel), None)
    if proc is not None:
        import subprocess
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:   # (then this process compiles it)
            pass


def scene_kernels_for(plan, forces=False):
    """``kernels_for(plan)`` for a scene: where it asks for forces and the
    module's ``forces_curve`` is new, that compiles in a process beside the run
    (``beside.compile_scene_forces``) while the run compiles the positions; the
    run's forces wait for it (``await_beside``)."""
    mod = kernels_for(plan)
    if forces:
        _compile_beside(mod, "forces_curve", "scene")
    return mod


def gpu_kernels_for(plan, rocker=None):
    """The CUDA kernel module of ``plan``'s sweep (``pipeline.compiler.cuda_source``):
    it imports the CPU module (``kernels_for``) and calls its functions."""
    from .cuda_source import gpu_source
    cpu = kernels_for(plan, rocker)
    src = gpu_source(cpu.__name__)
    return _imported(src, "pipeline_gpu_" + module_name(src)[len("pipeline_mech_"):])


def _imported(src, mod_name: str):
    """The module of source ``src``, written to the cache folder as
    ``mod_name``.py (unless there already) and imported.  ``src`` a function
    that writes the source: called only where the file is not there (its name
    says everything the source depends on: ``plan_path``)."""
    with _LOCK:
        mod = _MODULES.get(mod_name)
        if mod is not None:
            return mod
        folder = cache_dir()
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"{mod_name}.py"
        if callable(src):
            if not path.exists():
                write_text(path, src())
        elif not path.exists() or path.read_text() != src:
            write_text(path, src)       # a new temporary file, renamed when complete
        if str(folder) not in sys.path:
            sys.path.insert(0, str(folder))
        importlib.invalidate_caches()
        mod = importlib.import_module(mod_name)
        mod.SOURCE_PATH = str(path)
        _MODULES[mod_name] = mod
        return mod
