"""The shape of the package: no import cycles between modules of pipeline/
(imports inside functions count too), kernels that import nothing but numpy,
numba, math and each other, a package per layer importing only from the layers
below, no import inside the package of a path kept for one release, and no
function of the compiler over 80 lines."""

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parent.parent / "pipeline"


def _modules():
    mods = {}
    for f in PKG.rglob("*.py"):
        parts = f.relative_to(PKG.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        mods[name] = f
    return mods


def _from_module(mods, name, node):
    """The module a ``from X import ...`` of module ``name`` imports from."""
    if not node.level:
        return node.module or ""
    base = name if mods[name].name == "__init__.py" else name.rsplit(".", 1)[0]
    for _ in range(node.level - 1):
        base = base.rsplit(".", 1)[0]
    return base + ("." + node.module if node.module else "")


def _imports(mods, name):
    f = mods[name]
    out = set()
    for node in ast.walk(ast.parse(f.read_text())):
        if isinstance(node, ast.ImportFrom):
            base = _from_module(mods, name, node)
            for a in node.names:
                full = f"{base}.{a.name}"
                out.add(full if full in mods else base)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out


def test_no_module_imports_a_module_that_imports_it_back():
    mods = _modules()
    edges = {m: {t for t in _imports(mods, m) if t in mods and t != m} for m in mods}
    # every module reachable from m must not reach m again
    cycles = []
    for m in mods:
        seen, todo = set(), list(edges[m])
        while todo:
            t = todo.pop()
            if t in seen:
                continue
            seen.add(t)
            todo.extend(edges[t])
        if m in seen:
            cycles.append(m)
    assert not cycles, f"modules on an import cycle: {sorted(cycles)}"


def test_the_cycle_check_finds_a_cycle(tmp_path, monkeypatch):
    """The check above can fail: a planted pair of modules importing each other."""
    pkg = tmp_path / "pipeline"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("def f():\n    from .b import g\n")
    (pkg / "b.py").write_text("from .a import f\n")
    monkeypatch.setattr(__import__(__name__), "PKG", pkg)
    try:
        test_no_module_imports_a_module_that_imports_it_back()
    except AssertionError as e:
        assert "pipeline.a" in str(e)
    else:
        raise AssertionError("the planted cycle was not found")


def test_kernels_import_only_numpy_numba_math():
    mods = _modules()
    allowed = ("numpy", "numba", "math")
    for m in mods:
        if not (m.startswith("pipeline.kernels")
                or (m.startswith("pipeline.group_types.") and m.endswith(".kernels"))):
            continue
        for t in _imports(mods, m):
            top = t.split(".")[0]
            assert top in allowed or t.startswith("pipeline.kernels") or top in (
                "hashlib", "os", "pathlib", "__future__"), f"{m} imports {t}"


def test_importing_the_package_keeps_the_callers_matplotlib_backend():
    """A notebook's backend is its own: only the command line chooses Agg."""
    import subprocess
    import sys
    mods = sorted(m for m in _modules() if not m.startswith("pipeline.compiler"))
    code = ("import importlib, matplotlib\n"
            f"for m in {mods!r}:\n    importlib.import_module(m)\n"
            "print(matplotlib.get_backend())")
    env = dict(__import__("os").environ, MPLBACKEND="svg")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True).stdout.split()
    assert out[-1].lower() == "svg"
    for m, f in _modules().items():
        if m != "pipeline.cli":
            assert "matplotlib.use(" not in f.read_text(), m


def test_the_command_line_draws_with_agg_and_a_sweep_never_imports_matplotlib(tmp_path):
    """``pipeline`` chooses Agg over the user's MPLBACKEND for the pictures it
    writes, without importing matplotlib itself: a sweep, which draws nothing,
    never pays its import (0.09 s of every process)."""
    import subprocess
    import sys
    studies = Path(__file__).resolve().parents[1] / "studies"
    code = ("import sys\nfrom pipeline.cli import main\n"
            f"main(['run', {str(studies / 'ov7_synthesis.toml')!r}, '--candidates', '40', '-q', "
            f"'-o', {str(tmp_path / 'sweep.h5')!r}])\n"
            "print('matplotlib' in sys.modules)\n"
            f"main(['run', {str(studies / 'ov7_class3.toml')!r}, '-q', "
            f"'-o', {str(tmp_path / 'scene.h5')!r}])\n"
            "import matplotlib\nprint(matplotlib.get_backend())")
    env = dict(__import__("os").environ, MPLBACKEND="svg")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True, timeout=600).stdout.split()
    assert out[-2] == "False" and out[-1].lower() == "agg", out
    assert any(tmp_path.rglob("*.png")), "the scene drew its pictures"


# ---------------------------------------------------------------- layers
# The layers of pipeline/, lowest first: a module's layer is its subpackage
# (docs/architecture.md draws them), and the face is the modules at the top.  A
# module imports only from its own layer and the layers below.
# study sits below compiler and solve: reading and checking a study's TOML needs no solver
# (what needs a solved position, the CAD bodies' centres of mass, is checked by the run).
LAYERS = ("base", "kernels", "model", "study", "compiler", "solve", "results", "runs",
          "analysis", "views")
FACE = ("api", "cli", "runner", "compile", "bench", "old_paths")
# a group type's folder (pipeline/group_types/NAME/) holds its own layers, one module
# each: its __init__ (the codes) and the registry that finds the folders are base
TYPE_LAYERS = {"model": "model", "kernels": "kernels", "emitter": "compiler",
               "lanes": "compiler"}


def _layer_of(module):
    """The rank of ``module``'s layer (the face's is the highest), None if it has none."""
    parts = module.split(".")
    if len(parts) < 2:
        return None
    if parts[1] == "group_types":
        if len(parts) <= 3:
            return LAYERS.index("base")
        return LAYERS.index(TYPE_LAYERS[parts[3]]) if parts[3] in TYPE_LAYERS else None
    if parts[1] in LAYERS:
        return LAYERS.index(parts[1])
    if len(parts) == 2 and parts[1] in FACE:
        return len(LAYERS)
    return None


def _upward(mods):
    out = set()
    for m in mods:
        if m == "pipeline":
            continue
        for t in _imports(mods, m):
            if t in mods and t != "pipeline" and _layer_of(t) > _layer_of(m):
                out.add((m, t))
    return out


def test_every_module_has_a_layer():
    missing = [m for m in _modules() if m != "pipeline" and _layer_of(m) is None]
    assert not missing, f"modules in no layer package and not in FACE: {missing}"


def test_layers_import_only_downward():
    up = sorted(_upward(_modules()))
    assert not up, f"upward imports (a lower layer importing a higher one): {up}"


def _planted(tmp_path, monkeypatch, module, *imports):
    """A copy of the package whose ``module`` (a path under pipeline/) gains a
    function holding ``imports`` (lines), made the package the checks read."""
    import shutil
    pkg = tmp_path / "pipeline"
    shutil.copytree(PKG, pkg, ignore=shutil.ignore_patterns("__pycache__"))
    f = pkg / module
    f.write_text(f.read_text() + "\n\ndef _planted():\n"
                 + "".join(f"    {line}\n" for line in imports))
    monkeypatch.setattr(__import__(__name__), "PKG", pkg)


def test_the_layer_check_finds_an_upward_import(tmp_path, monkeypatch):
    """The check can fail: a planted import of the command line from one design's scene."""
    _planted(tmp_path, monkeypatch, "solve/scene.py", "from ..cli import main")
    assert ("pipeline.solve.scene", "pipeline.cli") in _upward(_modules())


def test_the_layer_check_finds_a_lazy_import_of_the_solver_from_a_study(tmp_path, monkeypatch):
    """A study's reader that reached for the solver inside a function (as the CAD
    check once did, to place the bodies at phi0) is an upward import."""
    _planted(tmp_path, monkeypatch, "study/cad_report.py",
             "from ..solve.scene import solve_curves")
    assert ("pipeline.study.cad_report", "pipeline.solve.scene") in _upward(_modules())


# ---------------------------------------------------------------- old paths
def _old_path_imports(mods):
    """(module, import) for every import inside pipeline/ of a path kept for one
    release: a moved module's old name (pipeline.old_paths.MOVED), or the
    re-exports of a package that took an old module's name (``from ..study import
    load_study`` instead of ``from ..study.reader import load_study``)."""
    from pipeline.old_paths import REEXPORTED, new_name
    kept = {f"pipeline.{p}" for p in REEXPORTED}
    out = set()
    for m in mods:
        for t in _imports(mods, m):
            if new_name(t) is not None or (t in kept and m != t and m != "pipeline"):
                out.add((m, t))
    return out


def test_no_module_imports_an_old_path():
    """The old paths are for code outside the package; inside it every import
    names a module where it is now."""
    old = sorted(_old_path_imports(_modules()))
    assert not old, f"imports of a path kept for one release (use the new one): {old}"


def test_the_old_path_check_finds_one(tmp_path, monkeypatch):
    """The check can fail: planted imports of an old path and of a re-export."""
    _planted(tmp_path, monkeypatch, "views/tables.py", "from ..storage import put",
             "from ..study import load_study")
    found = _old_path_imports(_modules())
    assert ("pipeline.views.tables", "pipeline.storage") in found
    assert ("pipeline.views.tables", "pipeline.study") in found


def test_an_old_path_is_the_module_itself():
    """``import pipeline.sweep`` gives the module pipeline.runs.sweep itself (a
    monkeypatch through the old name acts on the real module), with its own name
    and spec; a moved package's modules too.  (In a fresh interpreter: every
    module is imported.)"""
    import subprocess
    import sys
    code = ("import importlib\n"
            "from pipeline.old_paths import MOVED\n"
            "for old, new in MOVED.items():\n"
            "    was = importlib.import_module(f'pipeline.{old}')\n"
            "    now = importlib.import_module(f'pipeline.{new}')\n"
            "    assert was is now, old\n"
            "    assert now.__name__ == now.__spec__.name == f'pipeline.{new}', old\n"
            "import pipeline.groups.ppr, pipeline.model.groups.ppr\n"
            "assert pipeline.groups.ppr is pipeline.model.groups.ppr\n"
            "from pipeline import sweep\n"
            "import pipeline.runs.sweep\n"
            "assert sweep is pipeline.runs.sweep\n"
            "print(len(MOVED))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr


def test_tests_mirror_the_packages():
    """tests/ has a folder per layer package (tests of the face at the top) and
    only tests/support/ besides; no test imports another test module, only
    support."""
    tests = Path(__file__).resolve().parent
    folders = {d.name for d in tests.iterdir() if d.is_dir() and not d.name.startswith(("_", "."))}
    assert folders - {"support"} <= set(LAYERS), sorted(folders - {"support"} - set(LAYERS))
    for f in tests.rglob("test_*.py"):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module:
                assert not node.module.split(".")[-1].startswith("test_"), (f, node.module)
            elif isinstance(node, ast.Import):
                assert not any(a.name.split(".")[-1].startswith("test_") for a in node.names), f


def test_importing_an_old_path_warns_naming_the_new_one(tmp_path):
    """Each old path, and each name of the flat package's pipeline.model, .study
    and .analysis, warns (DeprecationWarning) with the path to import instead,
    attributed to the importing line, and gives the very object; importing every
    module of the package at its new path warns of no old path.  (In a fresh
    interpreter: a module already imported does not warn again.)"""
    import subprocess
    import sys
    code = '''
import importlib, sys, warnings
from pipeline.old_paths import MOVED
def caught(f):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        value = f()
    return value, [x for x in w if "old import path" in str(x.message)]
mods = %r
for m in mods:
    _, w = caught(lambda: importlib.import_module(m))
    assert not w, (m, [str(x.message) for x in w])
for old, new in MOVED.items():
    _, w = caught(lambda: __import__(f"pipeline.{old}"))      # as an import statement does
    assert sys.modules[f"pipeline.{old}"] is importlib.import_module(f"pipeline.{new}"), old
    assert [x.category for x in w] == [DeprecationWarning], (old, w)
    assert f"import pipeline.{new} " in str(w[0].message), (old, str(w[0].message))
    assert w[0].filename == __file__, (old, w[0].filename)
for pkg in ("model", "study", "analysis"):
    p = importlib.import_module(f"pipeline.{pkg}")
    for name, home in p._OLD_NAMES.items():
        value, w = caught(lambda: getattr(p, name))
        assert value is getattr(importlib.import_module(home), name), (pkg, name)
        assert name in vars(importlib.import_module(home)), (pkg, name, home)
        assert [x.category for x in w] == [DeprecationWarning], (pkg, name, w)
        assert f"import {name} from {home} " in str(w[0].message), str(w[0].message)
        assert w[0].filename == __file__, (pkg, name, w[0].filename)
print("ok")
''' % sorted(m for m in _modules() if m != "pipeline.old_paths"
               and not m.startswith("pipeline.compiler.skeleton"))
    user = tmp_path / "user.py"        # a user's script: the warnings name its lines
    user.write_text(code)
    out = subprocess.run([sys.executable, str(user)], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.split()[-1] == "ok", out.stderr[-3000:]
    # as the user sees it: an old path is an error under -W error::DeprecationWarning
    old = subprocess.run([sys.executable, "-W", "error::DeprecationWarning", "-c",
                          "import pipeline.sweep"], capture_output=True, text=True)
    assert old.returncode != 0 and "import pipeline.runs.sweep " in old.stderr, old.stderr


# ---------------------------------------------------------------- re-exports
# the modules whose names are imported from elsewhere on purpose: the package and
# its API (docs/guide/api.md); the skeleton's header, whose imports declare the
# generated module's names for the other skeleton files (compiler/skeleton/header.py)
PUBLIC = ("pipeline", "pipeline.api", "pipeline.compiler.skeleton.header")


def _defined(tree):
    """The names a module binds at its top level itself (def, class, assignment,
    a loop's or a with's target), not by an import."""
    out = set()
    todo = list(tree.body)
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(node.name)
            continue
        targets = []
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, (ast.AnnAssign, ast.AugAssign, ast.For)):
            targets = [node.target]
        elif isinstance(node, ast.With):
            targets = [i.optional_vars for i in node.items if i.optional_vars]
        for t in targets:
            out.update(n.id for n in ast.walk(t) if isinstance(n, ast.Name))
        for field in ("body", "orelse", "finalbody", "handlers"):
            todo.extend(getattr(node, field, ()))
    return out


def _reexport_uses(mods):
    """(module, line, source, name) for every ``from X import name`` inside
    pipeline/ (in functions too) where X, a module of the package, does not
    define ``name`` but imports it: the name is to be imported where it is defined."""
    trees = {m: ast.parse(f.read_text()) for m, f in mods.items()}
    defined = {m: _defined(t) for m, t in trees.items()}
    out = set()
    for m, tree in trees.items():
        for node in ast.walk(tree):
            if not isinstance(node, ast.ImportFrom):
                continue
            base = _from_module(mods, m, node)
            if base not in mods or base in PUBLIC:
                continue
            for a in node.names:
                if a.name != "*" and f"{base}.{a.name}" not in mods \
                        and a.name not in defined[base]:
                    out.add((m, node.lineno, base, a.name))
    return out


def test_no_module_imports_a_name_from_a_module_that_does_not_define_it():
    """Inside the package a name is imported from the module that defines it,
    never through another module's import of it (one place for each thing: a
    module's imports are its own, free to change)."""
    uses = sorted(_reexport_uses(_modules()))
    assert not uses, f"names imported through a module that only imports them: {uses}"


def test_the_reexport_check_finds_one(tmp_path, monkeypatch):
    """The check can fail: a planted import of ResultsError (base.errors') through
    results.storage, and of a function's name through a module that imports it."""
    _planted(tmp_path, monkeypatch, "views/tables.py",
             "from ..results.storage import ResultsError, open_results")
    found = {(m, base, name) for m, _, base, name in _reexport_uses(_modules())}
    assert ("pipeline.views.tables", "pipeline.results.storage", "ResultsError") in found
    assert ("pipeline.views.tables", "pipeline.results.storage", "open_results") not in found


COMPILER_FUNCTION_LINES = 80      # a function of the compiler, def line to last line, at most


def _long_functions(folder, limit=COMPILER_FUNCTION_LINES):
    """(module, function, lines) of every function and method under ``folder``
    (sub-folders too, the skeleton's generated kernels' templates among them)
    longer than ``limit`` lines."""
    out = []
    for f in sorted(folder.rglob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > limit:
                    out.append((str(f.relative_to(folder)), node.name, n))
    return out


def test_no_function_of_the_compiler_is_over_80_lines():
    """What writes the generated module is small functions named for what each
    writes: none over 80 lines in pipeline/compiler/ (its skeleton too), nor in
    a group type's compiler layer (its emitter and lane lines)."""
    long = list(_long_functions(PKG / "compiler"))
    long += [(m, f, n) for m, f, n in _long_functions(PKG / "group_types")
             if Path(m).stem in [k for k, v in TYPE_LAYERS.items() if v == "compiler"]]
    assert not long, f"functions over {COMPILER_FUNCTION_LINES} lines: {long}"


def test_the_function_length_check_finds_one(tmp_path):
    """The check can fail: a planted 81-line function (and a method) is found,
    one of 80 lines is not."""
    body = "".join(f"    x{i} = {i}\n" for i in range(79))
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "m.py").write_text(
        f"def long():\n{body}    return 0\n\n\ndef fits():\n{body}\n"
        f"class K:\n    def method(self):\n{body.replace('    ', '        ')}"
        "        return 0\n")
    found = {(name, n) for _, name, n in _long_functions(tmp_path)}
    assert found == {("long", 81), ("method", 81)}
