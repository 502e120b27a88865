"""A structural group type is one folder of pipeline/group_types: nothing else in
pipeline/ names a type (its study name, its plan code, its classes, its library
kernels), and a new type is added by writing one folder, in a copy of the
package, and nothing else: its study parses, its scene solves to the naive
reference, and its sweep runs in lanes as the careful path does."""

import importlib
import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

PKG = Path(__file__).resolve().parent.parent / "pipeline"
TESTS = Path(__file__).resolve().parent
# the compatibility table of the old import paths (one release) names the modules
# that moved into the folders: the one module besides the registry allowed to
OLD_PATHS = "old_paths.py"


def _type_words():
    """{folder: the words that name its type}: the names of its plan codes and
    their constants, its study types and classes, its library kernels, its
    emitters."""
    from pipeline import group_types
    words = {}
    for f in group_types.folders():
        init = importlib.import_module(f"pipeline.group_types.{f}")
        model = importlib.import_module(f"pipeline.group_types.{f}.model")
        kernels = importlib.import_module(f"pipeline.group_types.{f}.kernels")
        emitter = importlib.import_module(f"pipeline.group_types.{f}.emitter")
        classes = model.STUDY_TYPES + getattr(model, "BUILT", ())
        words[f] = (set(init.CODES.values()) | {k for k in vars(init) if k.startswith("G_")}
                    | {c.TYPE for c in classes} | {c.__name__ for c in classes}
                    | set(kernels.__all__) | {e.__name__ for e in emitter.EMITTERS})
    return words


def _named_outside(pkg, words):
    """(module path, line, word) for every word of a type named in a module of
    ``pkg`` outside that type's folder (the registry and the old paths apart)."""
    out = []
    shared = {w for f, ws in words.items() for w in ws
              if sum(w in o for o in words.values()) > 1}     # (a helper two types share)
    for py in sorted(pkg.rglob("*.py")):
        rel = py.relative_to(pkg)
        if rel.as_posix() in (OLD_PATHS, "group_types/__init__.py"):
            continue
        text = py.read_text()
        for f, ws in words.items():
            if rel.parts[:2] == ("group_types", f):
                continue
            for w in ws - shared:
                for m in re.finditer(rf"(?<!\w){re.escape(w)}(?!\w)", text):
                    out.append((rel.as_posix(), text.count("\n", 0, m.start()) + 1, w))
    return out


def test_no_module_names_a_group_type_outside_its_folder():
    words = _type_words()
    assert {"RRR", "G_RRR", "rrr", "class3", "ClassIIISlider", "PPR"} <= set().union(
        *words.values())
    assert not _named_outside(PKG, words)


def test_the_name_check_finds_a_type_named_elsewhere(tmp_path):
    """It can fail: a comment naming the RRR dyad in the sweep's runner, or its code."""
    pkg = tmp_path / "pipeline"
    shutil.copytree(PKG, pkg, ignore=shutil.ignore_patterns("__pycache__"))
    f = pkg / "runs" / "sweep.py"
    f.write_text(f.read_text() + "\n# an RRR dyad's margin\nX = G_PRP\n")
    found = {(m, w) for m, _, w in _named_outside(pkg, _type_words())}
    assert {("runs/sweep.py", "RRR"), ("runs/sweep.py", "G_PRP")} <= found


def test_the_moved_modules_and_classes_warn_and_are_the_same_objects():
    """The group types' modules and classes that moved into the folders stay
    importable for one release from where they were: each warns, naming the new
    path, and gives the very object; a path that moved twice names the last."""
    code = textwrap.dedent("""
        import importlib, warnings
        warnings.simplefilter("error", DeprecationWarning)
        from pipeline.group_types.class3.model import ClassIIISlider
        from pipeline.group_types.rpp import model as rpp
        from pipeline.group_types.rrr.model import RRR
        import pipeline.model, pipeline.model.groups
        for get, want, new in (
                (lambda: pipeline.model.RRR, RRR, "pipeline.group_types.rrr.model"),
                (lambda: pipeline.model.groups.ClassIIISlider, ClassIIISlider,
                 "pipeline.group_types.class3.model"),
                (lambda: importlib.import_module("pipeline.model.groups.ppr"), rpp,
                 "pipeline.group_types.rpp.model"),
                # (the old package's own warning comes first)
                (lambda: importlib.import_module("pipeline.groups.rrr").RRR, RRR,
                 "import pipeline.model.groups ")):
            try:
                get()
                raise SystemExit("no warning")
            except DeprecationWarning as w:
                assert new in str(w), w
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", DeprecationWarning)
                assert get() is want
        print("ok")
        """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=TESTS.parent)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-3000:]


# ------------------------------------------------------------------ a new type
# An RRR dyad parameterised by the link A-B and the ratio L_CB / L_AB: a folder,
# written here as a designer would, reusing the RRR's pieces where they fit.
NEW_TYPE = {
    "__init__.py": '''
        """RRR_ratio: the RRR dyad given by L_AB and the ratio L_CB / L_AB."""

        G_RRR_RATIO = 10

        CODES = {G_RRR_RATIO: "RRR_ratio"}
        ''',
    "model.py": '''
        from __future__ import annotations

        from dataclasses import dataclass

        from ...base import limits as lim
        from ...base.limits import Range
        from ...model.group_base import GroupType
        from . import G_RRR_RATIO

        LINK_RATIO = Range("a ratio of two links", 0.01, 100.0, "", "a link 100 times another")


        @dataclass(frozen=True)
        class RRRRatio(GroupType):
            """B joined to known A by link A-B and to known C by a link ratio * L_AB long."""
            A: str
            C: str
            B: str
            L_AB: float
            ratio: float
            W: int
            name: str = ""

            TYPE = "RRR_ratio"
            SOLVES = ("B",)

            @classmethod
            def parse(cls, g, f, name):
                a, c = f.point(g, "A"), f.point(g, "C")
                b = f.define(g, "B")
                return cls(a, c, b, g.number("L_AB", positive=True, within=lim.LENGTH),
                           g.number("ratio", positive=True, within=LINK_RATIO), f.mode(g),
                           name)

            def reads(self):
                return (self.A, self.C)

            def writes(self):
                return (self.B,)

            def plan_row(self, pt):
                return (G_RRR_RATIO, [pt(self.A), pt(self.C), pt(self.B)],
                        [("L_AB", self.L_AB), ("ratio", self.ratio), ("W", self.W)])

            def transmission(self):
                return [(self.name or f"{self.A}-{self.B}-{self.C}", "dyad",
                         (self.A, self.B, self.C))]

            def segments(self):
                return [(self.A, self.B), (self.C, self.B)]


        STUDY_TYPES = (RRRRatio,)
        ''',
    "kernels.py": '''
        from numba import njit

        from ...kernels.config import JIT
        from ..rrr.kernels import rrr

        __all__ = ("rrr_ratio",)


        @njit(**JIT)
        def rrr_ratio(pos, d1, d2, ia, ic, ib, l_ab, ratio, w, order, sing_tol, slack):
            return rrr(pos, d1, d2, ia, ic, ib, l_ab, ratio * l_ab, w, order, sing_tol, slack)
        ''',
    "emitter.py": '''
        from __future__ import annotations

        from ..rrr.emitter import RRREmitter
        from . import G_RRR_RATIO
        from .model import RRRRatio


        class RRRRatioEmitter(RRREmitter):
            """The RRR's lane form and force lines on L_CB = ratio * L_AB (the kernel's
            product: the same bits)."""
            code = G_RRR_RATIO

            def derived(self):
                return ([(self.k("L_CB"), f"{self.k('ratio')} * {self.k('L_AB')}")]
                        + super().derived())

            def careful(self):
                return [f"# {self.title()}: L_CB = ratio L_AB",
                        f"st, m = rrr_ratio(pos, d1, d2, {self.p(0)}, {self.p(1)}, {self.p(2)}, "
                        f"{self.k('L_AB')}, {self.k('ratio')}, {self.k('W')}, order, sing, slack)"]


        EMITTERS = (RRRRatioEmitter,)


        def warmup(tip):
            return {"RRR_RATIO_C": (38.0, 0.0)}, (
                RRRRatio(A=tip, C="RRR_RATIO_C", B="RRR_RATIO_B", L_AB=41.0, ratio=0.97, W=1),)
        ''',
}

# the shipped warp let-off four-bar (its bodies and its load as shipped) swept, with its
# dyad as the new type and the ratio swept (its sweep module compiles in about half the
# time of the slotted rocker's, which this test swept before: 26 s against 40-50 s)
STUDY_EDITS = (
    ('kind = "scene"', 'kind = "sweep"'),
    ('type = "RRR"\nA = "P2"', 'type = "RRR_ratio"\nname = "fourbar"\nA = "P2"'),
    ("L_CB = 40.0                # DC", "ratio = 0.975609756097561  # DC / BC"),
    ('working_point = "P5"\n', 'working_point = "P5"\nrocker = ["P4", "P3"]\n'),
    ("table_positions = 12\ndense_positions = 360\n", ""),
)
SWEEP = """
[sweep]
candidates = 1024
seed = 16
sampler = "sobol"
positions = 360
chunk_size = 512
stroke_radius = 60.0
objectives = ["peak_acceleration", "peak_reaction"]
metrics = ["peak_acceleration", "peak_reaction", "peak_M_bal", "stroke"]

[sweep.variables]
ratio = { param = "fourbar.ratio", min = 0.9, max = 1.0 }

[sweep.constraints]
stroke = [20.0, 90.0]
"""

SCRIPT = '''
import math, sys
import numpy as np
from pathlib import Path
import pipeline
assert Path(pipeline.__file__).resolve().parent == Path(sys.argv[1]).resolve(), pipeline.__file__
from pipeline.compiler.emit import emitter_classes
from pipeline.compiler.warmup import mechanism
from pipeline.group_types import code_names
from pipeline.kernels import config as kc
from pipeline.model.groups import GROUP_TYPES
from pipeline.runs.sweep import build_problem
from pipeline.solve.scene import solve_curves
from pipeline.study.reader import parse_study
from pipeline.study.sampling import draw_candidates
from pipeline.study.sweep_spec import parameter_rows
from support import naive
from support.lanes import assert_force_lanes_round, assert_lanes_agree

# registered from its folder alone: study type, code, emitter, warm-up
assert GROUP_TYPES["RRR_ratio"].__name__ == "RRRRatio"
assert code_names()[10] == "RRR_ratio"
assert emitter_classes()[10].__name__ == "RRRRatioEmitter"
assert "RRRRatio" in {type(g).__name__ for g in mechanism().groups}
study = parse_study(Path(sys.argv[2]).read_text(), "fourbar_ratio.toml")
plan = study.mechanism.compile()
assert 10 in plan.codes

# the scene: every position of P3 against the naive dyad, the analogs as the RRR's
phis = np.radians(np.arange(0.0, 360.0, 5.0))
c = solve_curves(plan, phis, kc.ACCELERATIONS)
assert c.overall == kc.OK, c.overall
i2, i4, i3 = plan.point("P2"), plan.point("P4"), plan.point("P3")
for k in range(len(phis)):
    want = naive.solve_rrr(c.pos[k, i2], c.pos[k, i4], 41.0, 0.975609756097561 * 41.0, W=1)
    assert np.abs(c.pos[k, i3] - want).max() < 1e-9, (k, c.pos[k, i3], want)
v = np.gradient(c.pos[:, i3, 0], phis)           # (a sanity check of the analogs' sign)
assert np.corrcoef(v[1:-1], c.d1[1:-1, i3, 0])[0, 1] > 0.999

# the sweep in lanes: the lane walk vouches for most lanes and agrees with the careful
# path candidate by candidate; the force lanes to rounding
pb = build_problem(study, study.sweep)
assert pb.kernels.HAS_LANES and pb.kernels.HAS_LANE_FORCES
pars = parameter_rows(pb.plan, study.sweep, draw_candidates(study.sweep, 0))
assert_lanes_agree(pb, np.ascontiguousarray(pars), class3=False)
assert_force_lanes_round(pb, np.ascontiguousarray(pars), 50)
print("new type ok", len(pars))
'''


def test_a_new_group_type_is_one_folder(tmp_path, studies):
    pkg = tmp_path / "pipeline"
    shutil.copytree(PKG, pkg, ignore=shutil.ignore_patterns("__pycache__"))
    folder = pkg / "group_types" / "rrr_ratio"
    folder.mkdir()
    for name, text in NEW_TYPE.items():
        (folder / name).write_text(textwrap.dedent(text).lstrip())
    text = (studies / "warp_feed_fourbar.toml").read_text()
    for old, new in STUDY_EDITS:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    text += SWEEP
    study = tmp_path / "fourbar_ratio.toml"
    study.write_text(text)
    # numba's cache of its own (the copy's kernel sources are not the checkout's), with
    # the compiled kernels of the library and of the other types that the suite has so
    # far: a new type leaves them valid (pipeline/kernels/__init__.py)
    from support.caches import copy_compiled
    kept = [PKG / "kernels"] + [d for d in (PKG / "group_types").iterdir()
                                if (d / "kernels.py").exists()]
    copy_compiled(kept, tmp_path / "nb", to=[pkg / d.relative_to(PKG) for d in kept])
    env = dict(os.environ, PYTHONPATH=f"{tmp_path}{os.pathsep}{TESTS}",
               PIPELINE_CACHE_DIR=str(tmp_path / "cache"), NUMBA_CACHE_DIR=str(tmp_path / "nb"))
    out = subprocess.run([sys.executable, "-c", SCRIPT, str(pkg), str(study)], cwd=tmp_path,
                         env=env, capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-6000:]
    assert "new type ok 512" in out.stdout         # (chunk 0)
    # and the sweep as a user runs it: every candidate recorded, most assembled
    res = tmp_path / "fourbar_ratio.h5"
    out = subprocess.run([sys.executable, "-m", "pipeline.cli", "run", str(study), "-o", str(res),
                          "--no-pictures", "-q"], cwd=tmp_path, env=env, capture_output=True,
                         text=True, timeout=900)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-6000:]
    import h5py
    with h5py.File(res) as f:
        status = f["candidates/status"][:]
        ratio = f["candidates/params"][:, list(f["candidates/variable"].asstr()[:]).index(
            "ratio")]
    assert len(status) == 1024 and (status == 0).mean() > 0.5
    assert 0.9 <= ratio.min() and ratio.max() <= 1.0 and ratio.std() > 0.02
