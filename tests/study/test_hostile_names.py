"""Names are data, never code.

Every name a study gives (points, groups, inputs, bodies, the bodies a load or
a slide names, sweep variables, dynamics cases, ...) is either refused while
the study is read, in one line naming the field, or taken as data: in the
generated kernel source it appears only inside comments written by ascii(),
and every identifier there comes from the plan's indices.  So:

* refused: the empty name, a character that is not printable (NUL, tab, CR,
  LF, U+0085, U+2028, U+2029, zero-width and other format characters, spaces
  other than U+0020), surrounding spaces, more than MAX_NAME_LENGTH characters;
* legal: anything else printable, quotes ' and " (and triple quotes), #,
  backslashes, ../ and letters of any script.

A legal hostile name leaves the generated code token for token the same as a
plain name does (comments aside), and a payload written to escape a comment or
a docstring never runs, also end to end through `pipeline run`; a hostile
study stored in a results file stops `pipeline show` and `pipeline report` with
one line (exit code 2).

The tests here read studies and generate source (no kernel runs), except one
end-to-end run; the stored-study cases copy the session's sweep of the main job.
"""

import io
import json
import re
import tokenize
from pathlib import Path

import h5py
import pytest

from pipeline.cli import main
from pipeline.compile import source
from pipeline.base.limits import MAX_NAME_LENGTH
from pipeline.study.reader import parse_study
from pipeline.base.errors import StudyError

STUDIES = Path(__file__).resolve().parents[2] / "studies"
CAM = (STUDIES / "cam_rocker_input.toml").read_text()
CAM_SWEEP = (STUDIES / "cam_rocker_input_sweep.toml").read_text()
TAKEUP = (STUDIES / "takeup_dynamics.toml").read_text()

# printable, so legal: the generated source keeps them in ascii() comments
LEGAL = [
    "it's",
    'say "hi"',
    '"""',
    "'''",
    'x"""; __import__("os").mkdir("PWNED"); """',
    "back\\slash",
    "\\n",                     # a backslash and an n: two characters, not a line break
    "../../etc/passwd",
    "# not a comment",
    "a.b",
    "{braces} %s %(x)s",
    "\u00d6se \u03a9 \u4e2d",  # letters of other scripts
    "x" * MAX_NAME_LENGTH,
]

# not printable, empty, padded or too long: refused while reading
ILLEGAL = [
    "a\nb",
    "rocker\nimport os; os.mkdir('PWNED')\n#",
    "a\rb",
    "a\x00b",
    "a\tb",
    "a\x0bb",
    "a\x0cb",
    "a\x85b",
    "a\u2028b",
    "a\u2029b",
    "a\u200bb",                # zero-width space (format)
    "a\u00a0b",                # no-break space
    "\x1b[31mred",             # a terminal escape
    " padded",
    "",
    "x" * (MAX_NAME_LENGTH + 1),
    "y" * 10_000,              # a 10 kB name
]


def toml(s):
    """``s`` as a TOML basic string (JSON's escapes are TOML's)."""
    return json.dumps(s)


def renamed(text, old, new):
    """The study text with the name ``old`` (every quoted occurrence, a key of
    [mechanism.fixed], and a sweep parameter's label) turned into ``new``."""
    q = toml(new)
    text = text.replace(f'"{old}"', q).replace(f'"{old}.', q[:-1] + ".")
    if re.fullmatch(r"P\d+", old):             # a point: a key of [mechanism.fixed]
        text = re.sub(rf"^{old} = \[", lambda m: f"{q} = [", text, flags=re.M)
    return text


# (study text, the name in it, what it is, the field the parser checks first)
ROLES = [
    (CAM, "P7", "a fixed point (a key of mechanism.fixed)", "mechanism.fixed."),
    (CAM, "P2", "a moving point (the crank's tip, a body's joint)", "mechanism.crank.tip"),
    (CAM, "lift", "a group's name", "mechanism.groups[1].name"),
    (CAM, "rocker", "an input's name and a body's", "mechanism.groups[0].name"),
    (CAM, "sinker bar", "a body named by a slide and a load", "mechanism.bodies[3].name"),
    (CAM, "main shaft", "the crank's body", "mechanism.bodies[0].name"),
    (CAM_SWEEP.replace('links = ["4_5", "5_6"]\n', ""), "P5",
     "the output rocker's point (the sweep's lane kernel)", "mechanism.groups[0].tip"),
    (CAM_SWEEP, "rocker", "a swept input's label", "mechanism.groups[0].name"),
]
ROLE_IDS = [f"{r[1]}:{r[2]}" for r in ROLES]


def code_tokens(src):
    """The generated source's tokens, comments aside.  A sweep's module imports
    from its mechanism's module by that module's name, the hash of its text,
    comments (and so the names) included: a module name of that form stands as
    one token, whatever its hash."""
    out = []
    for t in tokenize.generate_tokens(io.StringIO(src).readline):
        if t.type in (tokenize.COMMENT, tokenize.NL):
            continue
        if t.type == tokenize.NAME and t.string.startswith("pipeline_mech_"):
            assert re.fullmatch(r"pipeline_mech_[0-9a-f]{20}", t.string), t.string
            out.append((t.type, "pipeline_mech_HASH"))
        else:
            out.append((t.type, t.string))
    return out


@pytest.fixture(scope="module")
def twins():
    """The generated source of every role with a plain name (the reference)."""
    return {i: source(parse_study(renamed(text, old, "zz"), "twin.toml"))
            for i, (text, old, _, _) in enumerate(ROLES)}


@pytest.mark.parametrize("role", range(len(ROLES)), ids=ROLE_IDS)
@pytest.mark.parametrize("name", LEGAL, ids=[ascii(n)[:24] for n in LEGAL])
def test_a_legal_name_is_only_a_comment_of_the_generated_source(twins, role, name):
    text, old, _, _ = ROLES[role]
    study = parse_study(renamed(text, old, name), "hostile.toml")
    src = source(study)
    compile(src, "generated", "exec")        # Python source, never run here
    assert src.isascii()
    # the code is token for token the one a plain name gives: the name is in no
    # identifier, no string and no statement
    assert code_tokens(src) == code_tokens(twins[role])
    # it is there for the reader, in comments, as ascii() writes it (alone or in a
    # label: 'S[name]', 'name.mass'); the code above holds no trace of it
    comments = [t.string for t in tokenize.generate_tokens(io.StringIO(src).readline)
                if t.type == tokenize.COMMENT]
    assert any(ascii(name)[1:-1] in c for c in comments)
    if not name.isascii():
        assert name not in src                # escaped wherever it appears


@pytest.mark.parametrize("role", range(len(ROLES)), ids=ROLE_IDS)
@pytest.mark.parametrize("name", ILLEGAL, ids=[ascii(n)[:24] for n in ILLEGAL])
def test_an_illegal_name_is_refused_in_one_line_naming_the_field(role, name):
    text, old, _, field = ROLES[role]
    if name == "" and field.endswith("].name") and "groups" in field:
        # an empty group name is no name: the group takes its type and position
        study = parse_study(text.replace(f'name = "{old}"', 'name = ""', 1), "h.toml") \
            if 'kind = "scene"' in text else None
        if study is not None:
            assert study.mechanism.groups[int(field[-7])].name == ""
            return
        field = "mechanism.bodies[1].name"     # the sweep's rocker: its body's name
    with pytest.raises(StudyError) as e:
        parse_study(renamed(text, old, name), "hostile.toml")
    msg = str(e.value)
    assert len(msg.splitlines()) == 1 and msg.isprintable(), msg
    assert msg.startswith("hostile.toml: ") and field in msg, msg
    assert len(msg) < 400, msg                # a 10 kB name is not repeated


OTHER_FIELDS = [
    # (study text, old, new, the field in the message)
    (TAKEUP, 'name = "runup"', 'name = "run\\nup"', "dynamics.cases[0].name"),
    (TAKEUP, 'name = "runup"', f'name = "{"r" * 100}"', "dynamics.cases[0].name"),
    (CAM_SWEEP, "swing = {", '"sw\\ning" = {', "sweep.variables.'sw\\ning'"),
    (CAM_SWEEP, 'param = "rocker.travel_angle"', 'param = "rocker.travel_angle\\u2028"',
     "sweep.variables.swing.param"),
    (CAM_SWEEP, 'min = 30.0, max = 50.0 }', 'min = 30.0, max = 50.0, units = "deg\\r" }',
     "sweep.variables.swing.units"),
    (CAM_SWEEP, 'objectives = ["peak_acceleration"', 'objectives = ["peak\\u0085"',
     "sweep.objectives"),
    (CAM, 'working_point = "P6"', 'working_point = "P6\\u0000"', "output.working_point"),
    (CAM, 'links = ["4_5"', 'links = ["4_5\\n"', "output.links"),
    (CAM, 'title = "Cam', 'title = "\\u2029Cam', "study.title"),
    (CAM, 'title = "Cam', f'title = "{"t" * 300}', "study.title"),
    (CAM, 'name = "cam_rocker_input"', 'name = "cam\\u200e"', "study.name"),
    (CAM, 'slider = "sinker bar"', 'slider = "sinker bar\\n"', "mechanism.slides[0].slider"),
    (CAM, 'body = "sinker bar"', 'body = "sinker bar\\t"', "mechanism.loads[0].body"),
    (CAM, '[study]\n', '[study]\n"x\\ny" = 1\n', "study.'x\\ny'"),
]


@pytest.mark.parametrize("text, old, new, field", OTHER_FIELDS,
                         ids=[f"{i}-{f[3]}" for i, f in enumerate(OTHER_FIELDS)])
def test_every_other_name_field_is_checked(text, old, new, field):
    assert old in text, old
    with pytest.raises(StudyError) as e:
        parse_study(text.replace(old, new, 1), "hostile.toml")
    msg = str(e.value)
    assert len(msg.splitlines()) == 1 and msg.isprintable() and field in msg, msg


def test_names_that_would_collide_with_the_plans_own_labels_are_refused():
    """A group's name labels its parameters (label.key): it may not take the
    crank's, an unnamed group's ('RRP[2]': type and position) or a centre of
    mass's ('S[body]'); a point may not take a centre of mass's either."""
    cases = [(renamed(CAM, "lift", "crank"), r"groups\[1\]\.name: .*label of the crank"),
             (renamed(CAM, "lift", "S[link]"),
              r"groups\[1\]\.name: .*label of the centre of mass of body 'link'"),
             (renamed(CAM, "rocker", "RRP[2]").replace('name = "lift"\n', ""),
              r"groups\[0\]\.name: .*label of the unnamed group mechanism.groups\[1\]"),
             (renamed(CAM, "P7", "S[link]"), r"bodies\[2\]\.name: the centre of mass")]
    for text, pattern in cases:
        with pytest.raises(StudyError, match=pattern):
            parse_study(text, "x.toml")


# ------------------------------------------------------------ end to end
def test_a_payload_in_legal_names_never_runs(tmp_path, monkeypatch):
    """Names written to close the comment or the docstring they used to be
    pasted in, through `pipeline run`: the run succeeds, nothing is created,
    and every file of the kernel cache is named by a hash."""
    text = renamed(CAM, "lift", 'x"""; __import__("os").mkdir("PWNED1"); """')
    text = renamed(text, "sinker bar", "y'''; __import__('os').mkdir('PWNED2'); '''")
    text = renamed(text, "P2", '# \\"; __import__("os").mkdir("PWNED3") #')
    text = renamed(text, "rocker", "../../PWNED4")
    study = tmp_path / "hostile.toml"
    study.write_text(text)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    monkeypatch.setenv("PIPELINE_CACHE_DIR", str(tmp_path / "cache"))
    # on the plan path (the names in no source at all), then on the generated module
    # (the names in its comments, as ascii() writes them)
    for plan_path in ("1", "0"):
        monkeypatch.setenv("PIPELINE_PLAN_PATH", plan_path)
        assert main(["run", str(study), "-o", str(work / "r.h5"), "-q", "--no-pictures",
                     "--overwrite"]) == 0
        assert not list(tmp_path.rglob("PWNED*"))     # the payloads' folders, relative to work
        assert [p.name for p in work.iterdir() if not p.name.startswith(".")] == ["r.h5"]
    from pipeline.compiler.notice import COMPILE_RECORD      # the last compile's seconds
    names = [p.name for p in (tmp_path / "cache").rglob("*") if p.is_file()
             and p.name != COMPILE_RECORD]
    assert any(n.startswith("pipeline_mech_") for n in names), names
    assert all(re.match(r"pipeline_(mech|plan)_[0-9a-f]{20}[.]", n) for n in names), names


@pytest.fixture(scope="module")
def sweep_file(synthesis_sweep):
    """The session's sweep of the main job (tests/conftest.py), copied by each test."""
    return synthesis_sweep


@pytest.mark.parametrize("command", [["show", "--candidate", "0"], ["report"]])
@pytest.mark.parametrize("new", ['name = "triad\\nimport os; os.mkdir(\'PWNED\')\\n#"',
                                 'name = "triad\\u2028__import__(\'os\').mkdir(\'PWNED\')"',
                                 f'name = "{"t" * 10_000}"'])
def test_a_hostile_stored_study_is_one_line(sweep_file, tmp_path, monkeypatch, capsys,
                                            command, new):
    """The study stored in a results file reaches the generator through show
    and report: a hostile one stops them in one line naming the results file
    and the field, and nothing runs."""
    bad = tmp_path / "sweep.h5"
    bad.write_bytes(sweep_file.read_bytes())
    with h5py.File(bad, "r+") as f:
        text = f.attrs["study_toml"]
        text = text.decode() if isinstance(text, bytes) else str(text)
        assert 'name = "triad"' in text
        f.attrs["study_toml"] = text.replace('name = "triad"', new)
        f.attrs["study_file"] = "studies/x\nimport os.toml"     # the origin is data too
    monkeypatch.chdir(tmp_path)
    argv = [command[0], str(bad)] + command[1:]
    assert main(argv + ["-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    assert f"{bad} (the study stored from" in err and "mechanism.groups[0].name" in err, err
    assert len(err) < 600, err
    assert not list(tmp_path.rglob("PWNED*"))
