"""The shape of the package: no import cycles between modules of pipeline/
(imports inside functions count too), and kernels that import nothing but
numpy, numba, math and each other."""

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


def _imports(mods, name):
    f = mods[name]
    pkg = name if f.name == "__init__.py" else name.rsplit(".", 1)[0]
    out = set()
    for node in ast.walk(ast.parse(f.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg
                for _ in range(node.level - 1):
                    base = base.rsplit(".", 1)[0]
                base = base + ("." + node.module if node.module else "")
            else:
                base = node.module or ""
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
        if not m.startswith("pipeline.kernels"):
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


# ---------------------------------------------------------------- layers
# Every module of pipeline/ in its layer, lowest first; a module imports only from
# its own layer and the layers below.  (docs/architecture.md draws them; the flat
# modules move into a subpackage per layer as issue 26 goes on.)
LAYERS = {
    "base": ["base"],
    "kernels": ["kernels"],
    "model": ["model"],
    "compute": ["compiler"],
    "one design": ["solve"],
    "study": ["study"],
    "results": ["results"],
    "runs": ["runs"],
    "analysis": ["analysis"],
    "views": ["views"],
    "face": ["api", "cli", "runner", "compile", "bench", "old_paths"],
}
# imports that still go upward: each is work left (issue 26), and the list only
# shrinks (a test below fails when one of them is gone, so it is struck off)
KNOWN_UPWARD = set()


def _layer_of(module):
    rest = module.split(".")[1] if "." in module else ""
    for rank, (_, members) in enumerate(LAYERS.items()):
        if rest in members:
            return rank
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
    assert not missing, f"modules in no layer of LAYERS: {missing}"


def test_layers_import_only_downward():
    up = _upward(_modules())
    new = sorted(up - KNOWN_UPWARD)
    assert not new, f"upward imports (a lower layer importing a higher one): {new}"
    gone = sorted(KNOWN_UPWARD - up)
    assert not gone, f"fixed: strike these off KNOWN_UPWARD: {gone}"


def test_the_layer_check_finds_an_upward_import(tmp_path, monkeypatch):
    """The check can fail: a planted import of the command line from a kernel."""
    import shutil
    pkg = tmp_path / "pipeline"
    shutil.copytree(PKG, pkg, ignore=shutil.ignore_patterns("__pycache__"))
    f = pkg / "solve" / "scene.py"
    f.write_text(f.read_text() + "\n\ndef _planted():\n    from ..cli import main\n")
    monkeypatch.setattr(__import__(__name__), "PKG", pkg)
    up = _upward(_modules())
    assert ("pipeline.solve.scene", "pipeline.cli") in up - KNOWN_UPWARD
