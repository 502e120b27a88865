"""Command line: subcommands parse, call the public API, return an exit code.
No numerics here."""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys

# OpenBLAS's idle threads (numpy's and scipy's BLAS, one a core) spin for 2^28 cycles
# after each call before they sleep: 0.3 s of CPU in a scene with crank dynamics,
# taken from the integrations beside them.  2^4 cycles: asleep at once, the same threads
# and the same numbers (read when numpy loads BLAS; a user's own setting stays)
os.environ.setdefault("OPENBLAS_THREAD_TIMEOUT", "4")

EXIT_OK = 0
EXIT_USER_ERROR = 2


def _user_errors():
    from .base.expressions import ExpressionError
    from .base.errors import ResultsError, StudyError
    return (StudyError, ResultsError, ExpressionError, FileNotFoundError, ValueError)


def _say(text):
    """Print a command's output: every number as people read it (never -0)."""
    from .base.numbers import unsigned_zero
    print(unsigned_zero(str(text)))


def _print(obj, fmt):
    if fmt == "json":
        _say(json.dumps(obj, indent=2, default=str))
    else:
        for k, v in obj.items():
            _say(f"{k:>24}: {v}")


def cmd_run(a):
    from .runs.draw_ahead import let_go, prefork
    prefork(a.study)    # a sweep's draws: their process forked first (runs.draw_ahead)
    try:
        with _loading("run"):
            from .runner import run_study
            from .study.reader import load_study
            study = load_study(a.study)
        res = run_study(study, a.output, candidates=a.candidates, resume=a.resume,
                        overwrite=a.overwrite, scheduler=a.scheduler, n_jobs=a.jobs,
                        chunk_size=a.chunk_size, progress=not a.quiet,
                        pictures=not a.no_pictures, seed_from=a.seed_from, device=a.device,
                        store=a.store)
    finally:
        let_go()        # (a run that did not take it)
    info = {"results": str(res.results), **res.summary}
    if res.pictures:
        info["pictures"] = ", ".join(str(p) for p in res.pictures)
    if res.kind == "sweep":
        q = _quote(res.results)
        info["next"] = (f"pipeline analyze {q}; pipeline browse {q}; "
                        f"pipeline report {q}")
    elif res.kind == "scene":
        info["next"] = (f"pipeline export {_quote(res.results)} --csv tables/; "
                        f"pipeline show {_quote(res.results)} --animate")
    if not a.quiet:
        _print(info, a.format)
    return EXIT_OK


def _quote(path):
    import shlex
    return shlex.quote(str(path))


def _loading(name):
    """A live line past half a second while a command's modules load (numba, the
    plotting and analysis libraries) and its input is read: seconds on a loaded
    machine before the command's own progress shows."""
    from .base.progress import ticking
    return ticking(name, after=0.5, say_done=False)


def cmd_export(a):
    from .views.export import export, export_design
    wanted = [a.csv, a.parquet, a.dxf, a.study]
    if sum(w is not None for w in wanted) != 1:
        raise ValueError("give one output: --csv DIR, --parquet DIR, --dxf DIR or --study "
                         "OUT.toml")
    if a.dxf is None and a.study is None and (a.candidate or a.phi or a.paths or a.svg):
        raise ValueError("--candidate, --phi, --paths and --svg go with --dxf or --study")
    from .base.progress import ticking
    with ticking("export", after=0.5, say_done=False):    # a big sweep takes seconds
        if a.dxf is not None or a.study is not None:       # one design: a drawing, a study
            files = export_design(a.results, dxf=a.dxf, study=a.study, candidate=a.candidate,
                                  phis=a.phi, paths=a.paths, svg=a.svg)
        else:
            files = export(a.results, a.csv or a.parquet, every=a.every, feasible=a.feasible,
                           front=a.front, parquet=a.parquet is not None)
    if not a.quiet:
        for f in files:
            print(f)
    return EXIT_OK


def cmd_compile(a):
    from .compile import compile_all, source, study_files
    if a.library:
        if a.studies or a.show:
            raise ValueError("--library compiles the installation's kernels, no study's: "
                             "give it no study and no --show")
        import time

        from .base.progress import ticking
        from .compiler.beside import compile_library
        from .compiler.notice import INSTALLATION
        t = time.perf_counter()
        with ticking(f"compiling {INSTALLATION})"):
            compile_library()
        if not a.quiet:
            _say(f"library: {time.perf_counter() - t:.1f} s (compiled, or loaded from the cache)")
        return EXIT_OK
    if a.show:
        from .study.reader import load_study
        for p in study_files(a.studies):
            print(source(load_study(p)))
        return EXIT_OK
    done = compile_all(a.studies, jobs=a.jobs)
    if not a.quiet:
        _print({c.study: f"{c.kind}: {c.seconds:.1f} s, kernels in {c.source}" for c in done},
               a.format)
    return EXIT_OK


def cmd_bench(a):
    from .bench import run_benchmarks
    out = run_benchmarks(quick=a.quick, echo=(lambda *x: None) if a.quiet else print,
                         out=a.output, benchmarks=a.benchmarks)
    if a.quiet:
        _say(out)
    return EXIT_OK


def cmd_analyze(a):
    with _loading("analyze"):
        from .analysis.fronts import analyze
    info = analyze(a.results, n_representatives=a.representatives, max_samples=a.max_samples,
                   n_jobs=a.jobs)
    if not a.quiet:
        _print(info, a.format)
    return EXIT_OK


def cmd_browse(a):
    from .base.progress import ticking
    from .views.browse import browse
    # a live line past half a second: the fronts' first kernel load from numba's cache
    # refreshes its target context (a second, more under load) before anything prints
    with ticking("browse", after=0.5, say_done=False):
        text = browse(a.results, top=a.top, candidate=a.candidate, fmt=a.format, wide=a.wide)
    _say(text)
    return EXIT_OK


def cmd_show(a):
    with _loading("show"):
        from .views.animate import animate, results_kind
    if a.animate:
        info = animate(a.results, a.candidate, a.output, frames=a.frames)
    elif results_kind(a.results) == "scene":
        from .base.errors import ResultsError
        raise ResultsError(a.results, "is a scene result, this command needs a sweep result "
                                      "(`pipeline run` wrote the scene's pictures; `pipeline "
                                      f"show {a.results} --animate` animates it)")
    elif a.candidate is None:
        raise ValueError(f"{a.results} is a sweep: say which design to show with --candidate "
                         "ID (an index, 'knee' or 'reference')")
    else:
        from .views.show import show
        info = show(a.results, a.candidate, a.output)
    if not a.quiet:
        _print(info, a.format)
    return EXIT_OK


def cmd_doctor(a):
    try:
        from .runs.gpu import doctor
    except Exception as e:   # numba.cuda itself does not import
        print(f"numba.cuda does not import: {e}\n--device gpu: not available; "
              "pip install -e '.[gpu]' brings numba-cuda")
        return EXIT_OK
    print(doctor())
    return EXIT_OK


def cmd_report(a):
    with _loading("report"):
        from .views.report import write_report
    info = write_report(a.results, a.output, top=a.top, drawings=a.drawings)
    if not a.quiet:
        _print(info, a.format)
    return EXIT_OK


def cmd_tolerance(a):
    with _loading("tolerance"):
        from .runner import run_tolerance
    res = run_tolerance(a.results, a.candidate, a.output, samples=a.samples,
                        pictures=not a.no_pictures, overwrite=a.overwrite, n_jobs=a.jobs,
                        metrics=[m.strip() for m in a.metrics.split(",")] if a.metrics else None)
    info = {"results": str(res.results), **res.summary}
    if res.pictures:
        info["pictures"] = ", ".join(str(p) for p in res.pictures)
    if not a.quiet:
        _print(info, a.format)
    return EXIT_OK


def cmd_compare(a):
    with _loading("compare"):
        from .runner import run_compare
        from .views.compare import comparison_records, comparison_text
    cmp, pics = run_compare(a.results, a.candidate, a.output, pictures=not a.no_pictures)
    if a.format == "json":
        _say(json.dumps(comparison_records(cmp) | {"pictures": [str(p) for p in pics]},
                        indent=2))
    elif not a.quiet:
        _say(comparison_text(cmp))
        for p in pics:
            print(f"picture: {p}")
    return EXIT_OK

def cmd_bodies(a):
    from .study.cad_report import read_parts
    parts = [p.describe() for report in a.reports for p in read_parts(report)]
    if a.format == "json":
        _say(json.dumps(parts, indent=2))
    else:
        for k, info in enumerate(parts):
            if k:
                print()
            _print(info, a.format)
    return EXIT_OK


def build_parser():
    p = argparse.ArgumentParser(prog="pipeline", description=(
        "Exact analysis and Monte-Carlo synthesis of hinged-lever mechanisms."))
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("-v", "--verbose", action="store_true", help="more log output")
    common.add_argument("-q", "--quiet", action="store_true", help="no progress or summary")
    common.add_argument("--format", choices=("table", "json"), default="table")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("run", parents=[common], help="run a study (scene or sweep)")
    r.add_argument("study", help="study TOML file")
    r.add_argument("-o", "--output",
                   help="results HDF5 file (default results/<study file name>.h5)")
    r.add_argument("--candidates", type=int, help="sweep: number of candidates (overrides study)")
    r.add_argument("--resume", action="store_true", help=(
        "sweep: continue an interrupted run (its candidate count and chunk size come from "
        "its journal)"))
    r.add_argument("--overwrite", action="store_true",
                   help="replace a finished results file of the same name")
    r.add_argument("--scheduler", help="sweep: Dask scheduler address tcp://HOST:PORT")
    r.add_argument("-j", "--jobs", type=int, help="sweep: threads (default: all cores)")
    r.add_argument("--chunk-size", type=int, help="sweep: candidates per chunk")
    r.add_argument("--device", choices=("cpu", "gpu", "auto"), help=(
        "sweep: where the kernels run (default: the study's [sweep] device, else cpu; auto "
        "takes a GPU when numba.cuda finds one and says which); the numbers are the same"))
    r.add_argument("--store", choices=("all", "feasible"), help=(
        "sweep: keep every candidate's row (all, the default) or only the feasible ones, "
        "with the counts of each status (feasible: 10^8 candidates fit on a laptop's disk)"))
    r.add_argument("--no-pictures", action="store_true", help="scene: skip the PNG pictures")
    r.add_argument("--from", dest="seed_from", metavar="RESULTS.h5", help=(
        "search: start the [search] from the Pareto front of an earlier sweep's (or search's) "
        "results file"))
    r.set_defaults(func=cmd_run)

    e = sub.add_parser("export", parents=[common], help=(
        "a results file's tables: a scene's points, links, reactions (every computed "
        "position), a sweep's candidates; or one design as a DXF drawing or a scene study"))
    e.add_argument("results", help="results HDF5 file (scene or sweep)")
    e.add_argument("--csv", metavar="DIR", help="write CSV files (headers with units) into DIR")
    e.add_argument("--parquet", metavar="DIR", help="write Parquet files into DIR (pyarrow)")
    e.add_argument("--every", type=int, default=1, metavar="N",
                   help="scene: every N-th computed position (default: all)")
    e.add_argument("--feasible", action="store_true", help="sweep: the feasible candidates only")
    e.add_argument("--front", type=int, metavar="N",
                   help="sweep: the candidates of Pareto fronts 1 .. N only")
    e.add_argument("--dxf", metavar="DIR", help=(
        "write the design as a DXF drawing (R2013, mm) into DIR: the mechanism at --phi's "
        "crank angles, a layer per link, pins, ground, guides, the working point's path, "
        "link-length dimensions and the design's parameters"))
    e.add_argument("--svg", action="store_true", help="with --dxf: the same drawing as SVG")
    e.add_argument("--paths", action="store_true",
                   help="with --dxf: every moving point's path, not only the working point's")
    e.add_argument("--phi", type=float, nargs="+", metavar="DEG", help=(
        "with --dxf: crank angles phi1 to draw (default: the first table position and the "
        "positions of the output's two extremes)"))
    e.add_argument("--candidate", metavar="ID", help=(
        "--dxf, --study: a design of a sweep or search: a number, 'knee' or 'reference'"))
    e.add_argument("--study", metavar="OUT.toml", help=(
        "write a sweep's design (--candidate) as a scene study of its own: `pipeline run "
        "OUT.toml` gives `pipeline show --candidate`'s numbers"))
    e.set_defaults(func=cmd_export)

    c = sub.add_parser("compile", parents=[common], help=(
        "generate and compile the kernels of the studies (all of studies/ here by default) "
        "ahead of time, so their runs compile nothing"))
    c.add_argument("studies", nargs="*", metavar="STUDY",
                   help="study files (default: every studies/*.toml of the current folder)")
    c.add_argument("--show", action="store_true",
                   help="print the generated source of each study's kernels instead")
    c.add_argument("--library", action="store_true",
                   help="compile the kernels every mechanism's scenes share instead, once per "
                        "installation (about a minute from an empty cache; the process beside "
                        "the first sweep does it too): no scene compiles after it")
    c.add_argument("-j", "--jobs", type=int,
                   help="processes compiling side by side (default: all cores)")
    c.set_defaults(func=cmd_compile)

    an = sub.add_parser("analyze", parents=[common], help=(
        "rank a sweep's feasible candidates into Pareto fronts, model each objective and "
        "pick representative designs (written into the file as /analysis)"))
    an.add_argument("results", help="results HDF5 file of a sweep")
    an.add_argument("-n", "--representatives", type=int, default=5, metavar="N",
                    help="representative front-1 designs to pick (default 5)")
    an.add_argument("--max-samples", type=int, default=20000, metavar="N",
                    help="feasible candidates used per model, train + test (default 20000)")
    an.add_argument("-j", "--jobs", type=int, default=1, help=(
        "processes for the refined peaks of fronts 1-3 (from 128 designs) and threads for the "
        "models (default 1; the numbers do not depend on it)"))
    an.set_defaults(func=cmd_analyze)

    # browse also writes CSV: its own copy of the common options
    common_csv = argparse.ArgumentParser(add_help=False)
    common_csv.add_argument("-v", "--verbose", action="store_true", help="more log output")
    common_csv.add_argument("-q", "--quiet", action="store_true", help="no progress or summary")
    common_csv.add_argument("--format", choices=("table", "json", "csv"), default="table",
                            help="csv: the designs table (or one candidate's values)")
    b = sub.add_parser("browse", parents=[common_csv], help=(
        "a sweep file's contents, counts by status and best designs, or one candidate"))
    b.add_argument("results", help="results HDF5 file of a sweep")
    b.add_argument("--top", type=int, default=10, metavar="N",
                   help="rows per table: front 1 spread along the front, and the N best per "
                        "objective (default 10)")
    b.add_argument("--candidate", metavar="ID",
                   help="one candidate: an index, 'knee' or 'reference'")
    b.add_argument("--wide", action="store_true",
                   help="full-width tables and the file's datasets (default: 100 columns)")
    b.set_defaults(func=cmd_browse)

    from .views.animate import FPS, MAX_FRAMES
    s = sub.add_parser("show", parents=[common], help=(
        "re-run one candidate of a sweep as a scene and draw it: mechanism, output motion "
        "over the OV-7 cyclogram, joint reactions; or, with --animate, animate it (or a "
        "scene) over one revolution"))
    s.add_argument("results", help="results HDF5 file of a sweep (or, with --animate, of a "
                                    "scene)")
    s.add_argument("--candidate", metavar="ID",
                   help="a sweep's design: an index, 'knee' or 'reference'")
    s.add_argument("--animate", action="store_true", help=(
        f"write an animation of the mechanism over one revolution instead: a GIF ({FPS} "
        "frames/s), or an MP4 if -o ends in .mp4 and ffmpeg is installed"))
    s.add_argument("--frames", type=int, default=MAX_FRAMES, metavar="N",
                   help=f"--animate: frames per revolution (2 to {MAX_FRAMES}, the default)")
    s.add_argument("-o", "--output", metavar="FILE", help=(
        "picture (default: next to the results file, <name>_candidate<ID>.png); with "
        "--animate the animation (default <name>_candidate<ID>.gif, or <name>_animation.gif "
        "for a scene)"))
    s.set_defaults(func=cmd_show)

    rp = sub.add_parser("report", parents=[common], help=(
        "one self-contained HTML page about a sweep (runs analyze first if needed)"))
    rp.add_argument("results", help="results HDF5 file of a sweep")
    rp.add_argument("-o", "--output", metavar="HTML",
                    help="report file (default: next to the results file, <name>_report.html)")
    rp.add_argument("--top", type=int, default=20, metavar="N",
                    help="rows of the front-1 table (default 20)")
    rp.add_argument("--drawings", type=int, default=None, metavar="N",
                    help="front-1 designs whose cycle (drawing, motion, reactions) the "
                         "explorer embeds, with the knee and the reference design (default: "
                         "all of front 1 up to 50, about 40 ms each; 0: none)")
    rp.set_defaults(func=cmd_report)

    tl = sub.add_parser("tolerance", parents=[common], help=(
        "how a design holds up when it is made: its builds within the study's [tolerance] "
        "(ISO 2768-f by default) through the exact kernels, the spread of every metric, the "
        "yield and the sensitivities"))
    tl.add_argument("results", help="results HDF5 file of a scene or a sweep, or a study file")
    tl.add_argument("--candidate", metavar="ID",
                    help="a sweep's design: a number, 'knee' or 'reference'")
    tl.add_argument("--samples", type=int, metavar="N",
                    help="builds to draw (default: the study's [tolerance] samples, 4096)")
    tl.add_argument("--metrics", metavar="M1,M2", help=(
        "the metrics of every build (default: the study's [tolerance] metrics, else every one "
        "the mechanism has); stroke and dwell error alone skip the force stage"))
    tl.add_argument("-o", "--output", metavar="FILE", help=(
        "results file (default: next to the results file, <name>[_candidate<ID>]_tolerance.h5; "
        "for a study file results/<study>_tolerance.h5)"))
    tl.add_argument("--overwrite", action="store_true",
                    help="replace an earlier tolerance results file of the same name")
    tl.add_argument("--no-pictures", action="store_true", help="skip the PNG pictures")
    tl.add_argument("-j", "--jobs", type=int, help="threads (default: all cores)")
    tl.set_defaults(func=cmd_tolerance)

    cp = sub.add_parser("compare", parents=[common], help=(
        "designs side by side: stroke, dwell error, the working point's peaks, the smallest "
        "transmission angle, every joint's peak reaction and pin diameter, peak M_bal and "
        "shaking, each with its crank angle, and one picture overlaying them"))
    cp.add_argument("results", nargs="+", metavar="RESULTS.h5", help=(
        "scene results files (the first is the base the others are measured against), or one "
        "sweep's results file with --candidate"))
    cp.add_argument("--candidate", metavar="ID", help=(
        "a sweep's design (a number or 'knee'), compared with the sweep's reference design, "
        "both re-run as scenes"))
    cp.add_argument("-o", "--output", metavar="DIR", help=(
        "folder of the picture (default: the first results file's folder; the picture "
        "<name>_vs_<name>_compare.png, or <name>_candidate<ID>_vs_reference_compare.png)"))
    cp.add_argument("--no-pictures", action="store_true", help="print the table only")
    cp.set_defaults(func=cmd_compare)

    bd = sub.add_parser("bodies", parents=[common], help=(
        "what a CAD mass properties report holds, in the study's units: m (kg), the centre "
        "of mass (x, y mm in the part's frame; as lS, US from the part's origin and x axis), "
        "J_S (kg*m^2, Lzz at the centre of mass), and a warning where the part is not "
        "symmetric about the mechanism's plane"), description=(
        "Read CAD mass properties reports as a body's cad = { report = ..., origin = ..., "
        "x_axis = [...] } in [[mechanism.bodies]] reads them, and print what they hold in "
        "the study's units. A report is the text SolidWorks' Mass Properties dialog saves "
        "(any of its units; a decimal comma reads as a point) or a CSV with one row per "
        "part: name, mass, unit, x, y, z, length unit, Lzz, inertia unit. A bad report ends "
        "in one line naming the file, the line and what was expected."))
    bd.add_argument("reports", nargs="+", metavar="REPORT", help=(
        "a SolidWorks mass properties report (.txt) or a .csv of parts"))
    bd.set_defaults(func=cmd_bodies)

    bn = sub.add_parser("bench", parents=[common], help=(
        "speed and accuracy: run time against error and the throughput table, "
        "written under results/bench/ or -o DIR"))
    bn.add_argument("--quick", action="store_true", help="small sizes (about a minute)")
    bn.add_argument("-o", "--output", metavar="DIR",
                    help="folder for the tables, plots and summary.md (default: results/bench/ "
                         "of the source checkout)")
    bn.add_argument("--benchmarks", metavar="DIR",
                    help="the checkout's benchmarks/ folder (default: benchmarks/ here)")
    bn.set_defaults(func=cmd_bench)

    dr = sub.add_parser("doctor", parents=[common], help=(
        "what numba.cuda sees on this machine (package, driver, toolkit, GPUs) and whether "
        "--device gpu can run"))
    dr.set_defaults(func=cmd_doctor)
    p.commands = tuple(sub.choices)
    return p


def _unknown_command(parser, argv):
    """Refuse a misspelt command with the nearest one (argparse 3.11 lists them
    all): `pipeline analyse` -> did you mean 'analyze'?"""
    import difflib
    cmd = next((a for a in argv if not a.startswith("-")), None)
    if cmd is None or cmd in parser.commands:
        return
    near = difflib.get_close_matches(cmd, parser.commands, n=1)
    parser.error(f"unknown command {cmd!r}" + (f"; did you mean {near[0]!r}?" if near else
                                               f"; commands: {', '.join(parser.commands)}"))


def main(argv=None) -> int:
    parser = build_parser()
    _unknown_command(parser, sys.argv[1:] if argv is None else list(argv))
    args = parser.parse_args(argv)
    # pictures go to files (a notebook keeps its own backend): matplotlib draws with Agg
    # when a command imports it; not imported here, since a sweep never draws (0.09 s)
    if "matplotlib" in sys.modules:
        sys.modules["matplotlib"].use("Agg")
    else:
        os.environ["MPLBACKEND"] = "Agg"
    logging.basicConfig(level=logging.DEBUG if args.verbose else
                        (logging.WARNING if args.quiet else logging.INFO),
                        format="%(message)s")
    try:
        return args.func(args)
    except _user_errors() as e:
        print(f"pipeline {args.command}: error: {_one_line(e)}", file=sys.stderr)
        return EXIT_USER_ERROR
    except (KeyError, IndexError, RuntimeError) as e:
        path = getattr(args, "results", None)
        if path is None:
            raise
        # a results file that opens but lacks what its kind must hold, or whose bytes
        # are damaged (HDF5 then fails inside a read: h5py's RuntimeError)
        print(f"pipeline {args.command}: error: {path}: damaged or incomplete results file "
              f"({type(e).__name__}: {_one_line(e)})", file=sys.stderr)
        return EXIT_USER_ERROR
    except OSError as e:
        # the operating system's word (no space left, read-only, locked): one line
        # naming the file; every write is atomic, so earlier results are intact
        from .base.files import os_error_text
        text = os_error_text(e)
        named = _file_of(args)
        if named and not e.filename and str(named) not in text:
            text = f"{named}: {text}"
        print(f"pipeline {args.command}: error: {_one_line(text)}", file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt as e:
        # a sweep says how much is saved and how to resume
        print(f"pipeline {args.command}: {str(e) or 'interrupted'}", file=sys.stderr)
        return 130


def _file_of(args):
    """The file a command works on, to name where an error does not."""
    for key in ("results", "output", "study"):
        v = getattr(args, key, None)
        if v:
            return v
    return None


def _one_line(e) -> str:
    """An error's text on one line (HDF5 and NumPy texts can span several)."""
    return " ".join(str(e).split())


def script() -> int:
    """The `pipeline` program (and `python -m pipeline.cli`): ``main``, then a
    quick exit.  The interpreter's last garbage collection walks every object a
    command made (numba's, matplotlib's: 0.3 million) and kept a finished
    command silent for a second before the prompt came back; the objects are
    frozen out of it (``gc.freeze``), the operating system takes the memory.
    Fewer collections on the way (``base.processes.collect_seldom``).
    Not in ``main``, which tests and notebooks call in a process that goes on."""
    import gc

    from .base.processes import collect_seldom
    collect_seldom()
    code = main()
    gc.freeze()
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(script())
