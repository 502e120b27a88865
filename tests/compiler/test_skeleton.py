"""The fixed parts of the generated modules (pipeline/compiler/skeleton): real
Python files whose every name is declared above their marker line, pasted
verbatim into the generated source."""

import ast
import builtins
from pathlib import Path

import pytest

from pipeline.compiler import module_name, source_for
from pipeline.compiler.skeleton import END, MARKER, part
from pipeline.study.reader import load_study

SKELETON = Path(__file__).resolve().parents[2] / "pipeline" / "compiler" / "skeleton"
STUDIES = Path(__file__).resolve().parents[2] / "studies"
PARTS = sorted(f.stem for f in SKELETON.glob("*.py") if f.stem not in ("__init__", "_mechanism"))


def _tree(name):
    return ast.parse((SKELETON / f"{name}.py").read_text(), f"{name}.py")


def _imported(tree, module=None):
    """Names the file imports (from ``module`` only, if given: ".header" etc.)."""
    out = set()
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and module is not None:
            if "." * node.level + (node.module or "") == module:
                out.update(a.asname or a.name for a in node.names)
        elif isinstance(node, (ast.Import, ast.ImportFrom)) and module is None:
            out.update((a.asname or a.name).split(".")[0] for a in node.names)
    return out


def _bound(tree):
    """Every name the file binds anywhere (imports, defs, arguments, targets)."""
    out = _imported(tree)
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            out.add(node.name)
        elif isinstance(node, ast.arg):
            out.add(node.arg)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
            out.add(node.id)
        elif isinstance(node, ast.ExceptHandler) and node.name:
            out.add(node.name)
    return out


def _top_level(tree):
    """Names the file defines at module level (defs and assignments)."""
    out = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            out.add(node.name)
        elif isinstance(node, ast.Assign):
            for t in node.targets:
                out.update(n.id for n in ast.walk(t) if isinstance(n, ast.Name))
    return out


def test_every_skeleton_part_is_there():
    assert PARTS == ["advance_closed", "advance_newton", "batch", "careful", "crank_dynamics",
                     "header", "lane_forces", "no_lane_forces", "no_lanes", "parallel",
                     "sweep_stages"]


@pytest.mark.parametrize("name", PARTS)
def test_a_skeleton_file_is_python_with_every_name_declared(name):
    text = (SKELETON / f"{name}.py").read_text()
    assert text.count(MARKER) == 1 and text.isascii()
    compile(text, f"{name}.py", "exec")
    tree = _tree(name)
    used = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}
    undeclared = used - _bound(tree) - set(dir(builtins))
    assert not undeclared, f"{name}.py uses names its import block does not declare: {undeclared}"
    # what the import block declares is there: the header's imports, the mechanism's
    # names (the stub), the careful part's kernels
    header = _imported(_tree("header"))
    assert _imported(tree, ".header") <= header
    assert _imported(tree, "._mechanism") <= _top_level(_tree("_mechanism"))
    assert _imported(tree, ".careful") <= _top_level(_tree("careful"))
    walk = ast.parse((SKELETON.parents[1] / "kernels" / "walk.py").read_text())
    assert _imported(tree, "...kernels.walk") <= _top_level(walk)
    # above the marker only the declarations: below it, no import of the package's own
    body = ast.parse(part(name))
    assert not any(isinstance(n, ast.ImportFrom) and n.level for n in ast.walk(body))


def test_the_header_exports_what_it_imports():
    """Its __all__ (below the end marker, for linters) lists its imports, no more."""
    text = (SKELETON / "header.py").read_text()
    assert text.count(END) == 1 and END not in part("header")
    tree = _tree("header")
    exported = next(n.value for n in tree.body if isinstance(n, ast.Assign)
                    and n.targets[0].id == "__all__")
    assert set(ast.literal_eval(exported)) == _imported(tree)


def test_pyflakes_finds_nothing_in_the_skeleton():
    import pyflakes.api as api
    from pyflakes.reporter import Reporter

    class Collect:
        def __init__(self):
            self.lines = []

        def write(self, s):
            self.lines.append(s)

    out = Collect()
    n = api.checkRecursive([str(SKELETON)], Reporter(out, out))
    assert n == 0, "".join(out.lines)


@pytest.fixture(scope="module")
def sources():
    """Generated sources that use every part: a scene of a closed-form mechanism
    (no rocker), a sweep with class III groups and lanes, a sweep with a class
    III group with a slider, the take-up's mechanism (an RPR: no lane form) with
    a rocker; each sweep's module and the module of its mechanism (no rocker:
    everything the rocker does not change), which it imports from."""
    out = {}
    for name in ("ov7_base", "ov7_synthesis", "ov7_class3_slider_sweep"):
        study = load_study(STUDIES / f"{name}.toml")
        plan = study.mechanism.compile()
        if study.kind == "sweep":
            out[name] = source_for(plan, tuple(study.output.rocker))
            out[name + " mechanism"] = source_for(plan)
        else:
            out[name] = source_for(plan)
    plan = load_study(STUDIES / "takeup_dynamics.toml").mechanism.compile()
    out["takeup with a rocker"] = source_for(plan, tuple(plan.point_names[:2]))
    return out


def test_the_generated_source_holds_every_part_verbatim(sources):
    everything = "\n".join(sources.values())
    for name in PARTS:
        text = part(name)
        if name == "header":
            assert all(s.startswith(text.split("{n_groups}")[0]) for s in sources.values())
            text = text[text.index("\nimport math"):]
        elif name == "no_lanes":
            assert text.format(why="No output rocker declared") in sources["ov7_base"]
            text = text.format(why="A group without a lane form")
            assert text in sources["takeup with a rocker"]
        elif name == "no_lane_forces":
            assert text.format(why="no output rocker declared") in sources["ov7_base"]
            text = text.format(why="no lane path: a group without a lane form of its positions")
            assert text in sources["takeup with a rocker"]
        assert text in everything, name
    assert part("advance_closed") in sources["ov7_base"]
    assert part("advance_newton") in sources["ov7_synthesis mechanism"]
    for sweep in ("ov7_synthesis", "ov7_class3_slider_sweep"):
        # the sweep's module defines what the rocker changes, imports the rest
        assert part("advance_newton") not in sources[sweep] and "def position(" not in sources[sweep]
        assert part("sweep_stages") in sources[sweep] and part("parallel") in sources[sweep]
        assert f"from {module_name(sources[sweep + ' mechanism'])} import (" in sources[sweep]
    assert "def walk(" in sources["ov7_synthesis"]       # the lane path, not no_lanes
    assert "def force_lanes(" in sources["ov7_synthesis"]     # and the force lanes
    assert part("lane_forces") in sources["ov7_synthesis"]
    assert "every candidate takes the careful path" not in sources["ov7_synthesis"]
