"""Public entry points behind `pipeline run`: a study file in, results out."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

from .base.errors import ResultsError
from .base.units import unit_text
from .base.files import RunLock, check_output, check_output_folder, safe_name, save_figure
from .solve.scene_study import solve_scene  # noqa: F401  (runner.solve_scene: the API's)
from .study.reader import load_study

log = logging.getLogger("pipeline")


@dataclass
class RunOutcome:
    kind: str
    results: Path
    pictures: list = field(default_factory=list)
    summary: dict = field(default_factory=dict)


def default_output(study):
    """results/<the study file's name>.h5: the study's ``name`` is a label,
    never a path (only -o writes elsewhere)."""
    stem = Path(study.path).stem if getattr(study, "path", None) else study.name
    return Path("results") / f"{safe_name(stem, 'study')}.h5"


def run_study(path, out=None, *, candidates=None, resume=False, overwrite=False,
              scheduler=None, n_jobs=None, chunk_size=None, progress=True,
              pictures=True, seed_from=None, device=None, store=None) -> RunOutcome:
    """Run a scene or a sweep study (a path or a loaded Study) and write its
    results file (and pictures).  A sweep study with a [search] section runs
    its adaptive search, seeded with the front of the results file
    ``seed_from`` if given."""
    from .study.reader import Study
    study = path if isinstance(path, Study) else load_study(path)
    from .solve.scene import check_centres_of_mass
    check_centres_of_mass(study)        # its CAD bodies on its links, before anything else
    path = study.path
    out = Path(out) if out else default_output(study)
    from .results.storage import results_output
    # before anything is computed: never over the study or the --from file, a folder, a
    # file that is not a results file, nor through a link to nothing (an existing results
    # file: the run's own checks below, which know --overwrite, --resume and journals)
    out = results_output(out, inputs=(path, seed_from), overwrite=True)
    if study.kind == "scene":
        if candidates is not None or resume or scheduler or seed_from or device or store:
            raise ValueError(f"{path}: --candidates, --resume, --scheduler, --from, --device "
                             "and --store apply to sweeps; this study is a scene")
        from .base.progress import ticking
        with ticking(f"run {study.name} (scene)"):      # a live line while it solves and draws
            return run_scene_study(study, out, pictures=pictures, overwrite=overwrite)
    if study.search is not None:
        if candidates is not None or chunk_size is not None:
            raise ValueError(f"{path}: --candidates and --chunk-size size a Monte-Carlo sweep; "
                             "this study's [search] sets its own length (population, "
                             "generations or evaluations)")
        if (device or study.sweep.device) != "cpu" or (store or study.sweep.store) != "all":
            raise ValueError(f"{path}: an adaptive search runs on the CPU and keeps every "
                             "design it evaluates: [sweep] device and store (--device, "
                             "--store) apply to Monte-Carlo sweeps")
        from .runs.search import run_search
        return run_search(study, out, seed_from=seed_from, resume=resume, overwrite=overwrite,
                          scheduler=scheduler, n_jobs=n_jobs, progress=progress)
    if seed_from is not None:
        raise ValueError(f"{path}: --from seeds an adaptive search, and this study has no "
                         "[search] section (studies/ov7_search.toml has one)")
    from .runs.sweep import run_sweep
    return run_sweep(study, out, candidates=candidates, resume=resume, overwrite=overwrite,
                     scheduler=scheduler, n_jobs=n_jobs, chunk_size=chunk_size,
                     progress=progress, device=device, store=store)


def peak_summary(res) -> dict:
    """The peaks a designer reads first: the working point's speed and
    acceleration, the largest joint reaction, slide normal force and balancing
    moment, the shaking force and moment on the frame (refined between grid
    positions, with their crank angles); the worst equilibrium residual and
    the crank's counterweight over the dense positions."""
    wp = res.study.output.working_point
    point, moment, transmission, reactions, slides, shaking = {}, {}, {}, [], [], {}
    for p in res.peaks or ():          # one pass, shown in this order
        if p.item == wp and p.quantity in ("velocity", "acceleration"):
            point[f"peak {p.quantity} {wp}"] = f"{p.value:.6g} {p.unit} at phi1 = {p.phi1:.4f} deg"
        elif p.quantity == "reaction":
            reactions.append(p)
        elif p.quantity == "slide_normal":
            slides.append(p)
        elif p.quantity == "M_bal":
            moment["peak_M_bal"] = f"{p.value:.3f} N·m at phi1 = {p.phi1:.4f} deg"
        elif p.quantity in ("shaking_force", "shaking_moment"):
            about = (f" about {res.dense.forces.shaking_about}"
                     if p.quantity == "shaking_moment" else "")
            shaking[f"peak_{p.quantity}"] = (f"{p.value:.6g} {p.unit}{about} at phi1 = "
                                             f"{p.phi1:.4f} deg")
        elif p.quantity == "min_transmission_angle":
            transmission[f"min transmission angle {p.item}"] = (f"{p.value:.3f} deg at phi1 = "
                                                                f"{p.phi1:.4f} deg")
    out = dict(point)
    if reactions:
        p = max(reactions, key=lambda q: q.value)
        from .solve.reactions import pin_diameter
        (length, sigma), = res.study.output.pins([p.item])
        out["peak_reaction"] = (f"{p.value:.1f} N at {p.item}, phi1 = {p.phi1:.4f} deg; pin "
                                f"d_min {float(pin_diameter(p.value, length, sigma)):.2f} mm "
                                f"({length:g} mm, {sigma:g} MPa)")
    if slides:
        p = max(slides, key=lambda q: q.value)
        out["peak_slide_force"] = f"{p.value:.1f} N at {p.item}, phi1 = {p.phi1:.4f} deg"
    out.update(moment)
    import numpy as np
    fr = res.dense.forces
    if fr is not None and fr.residual is not None and np.isfinite(fr.residual).any():
        k = int(np.nanargmax(fr.residual))
        out["equilibrium_residual"] = (f"{fr.residual[k]:.3g} at phi1 = "
                                       f"{np.degrees(fr.phi[k]):g} deg (the worst of the dense "
                                       "positions: virtual power / its largest term)")
    out.update(shaking)
    if res.counterweight is not None:
        out.update(res.counterweight.summary())
    out.update(transmission)
    m = res.motion or {}
    if m:
        out["dwell_error"] = (f"{m['dwell_error']:.4g} (best {m['dwell_deg']:g} deg window from "
                              f"phi1 = {m['dwell_start']:g} deg)")
        out["stroke"] = f"{m['stroke']:.4g} mm"
        if "law_error" in m:
            shift = (f", the law shifted by {m['law_shift']:g} deg to fit best"
                     if m["law_align"] == "best" else "")
            out["law_error"] = (f"{m['law_error']:.4g} RMS, {m['law_error_max']:.4g} at most "
                                f"(normalised rocker angle against the motion law{shift})")
    return out


def run_scene_study(study, out, pictures=True, overwrite=False) -> RunOutcome:
    """Solve a scene and write its results file and pictures: like a sweep, a
    scene takes the run lock of its file and replaces an earlier file only with
    ``overwrite`` (and never an unfinished run's)."""
    out = Path(out)
    if pictures:
        if out.suffix.lower() == ".png":
            raise ResultsError(out, "a scene's picture is named after its results file "
                                    f"({out.stem}.png): it would replace the results; give -o "
                                    "a name ending in .h5 (or --no-pictures)")
        for pic in (out.with_suffix(".png"), out.with_name(f"{out.stem}_kinematics.png")):
            check_output(pic, inputs=(study.path,))
    with RunLock(out):
        from .results.journal import Journal
        if Journal(out).exists():
            raise ResultsError(out, "is being written by an unfinished sweep or search (its "
                                    f"journal {out.name}.parts is beside it); write the scene "
                                    "to another file with -o")
        if out.exists() and not overwrite:
            raise ResultsError(out, "already exists; --overwrite replaces it, -o writes "
                                    "another file")
        return _write_scene_study(study, out, pictures)


def _write_scene_study(study, out, pictures) -> RunOutcome:
    from .kernels import config as kc
    from .results.scene_file import write_scene
    res = solve_scene(study)
    # the constant-speed forces the dynamics cases are compared with (once, not per case)
    constant = constant_forces(res) if res.motion_forces else None
    write_scene(res, out)
    pics = []
    if pictures:
        import matplotlib.pyplot as plt

        from .solve.cyclogram import output_motion
        from .views import plots
        from .views.cyclogram_plots import cyclogram_figure
        from .views.dynamics_plots import dynamics_figure, eps1_figure
        # made and saved one at a time: a figure is closed before the next is drawn
        figures = [(lambda: plots.scene_figure(res), out.with_suffix(".png")),
                   (lambda: plots.kinematics_figure(res), out.with_name(
                       f"{out.stem}_kinematics.png"))]
        if output_motion(res) is not None:
            figures.append((lambda: cyclogram_figure(res), out.with_name(
                f"{out.stem}_cyclogram.png")))
        if res.dense.forces is not None:
            figures.append((lambda: plots.forces_figure(res),
                            out.with_name(out.stem + "_forces.png")))
            if res.dense.forces.shaking is not None:
                from .views.shaking_plots import shaking_figure
                figures.append((lambda: shaking_figure(res),
                                out.with_name(out.stem + "_shaking.png")))
            if getattr(res.dense.forces, "friction", None) is not None:
                from .views.friction_plots import friction_figure
                figures.append((lambda: friction_figure(res),
                                out.with_name(out.stem + "_friction.png")))
        for case in res.dynamics or ():
            name = safe_name(case.name, "case")
            figures.append((lambda case=case: dynamics_figure(case),
                            out.with_name(f"{out.stem}_{name}.png")))
            figures.append((lambda case=case: eps1_figure(case),
                            out.with_name(f"{out.stem}_{name}_eps1.png")))
            if (res.motion_forces or {}).get(case.name):
                from .views.dynamics_plots import motion_forces_figure
                figures.append((lambda case=case: motion_forces_figure(
                    case.name, res.motion_forces[case.name], constant),
                    out.with_name(f"{out.stem}_{name}_forces.png")))
        if res.reduced is not None:
            from .views.dynamics_plots import reduced_figure
            figures.append((lambda: reduced_figure(res.reduced),
                            out.with_name(f"{out.stem}_reduced.png")))
        for make, path in figures:
            fig = make()
            try:
                pics.append(save_figure(fig, path, dpi=110))
            finally:
                plt.close(fig)
    summary = {"status": kc.STATUS_NAMES[res.status]}
    fail = res.failure
    if fail is not None:    # where and what: the crank angle (between positions) and the group
        summary["failure"] = (f"{fail['status']} at phi1 = {fail['phi_deg']:.9g} deg, group "
                              f"{fail['group']!r}" + (f" ({', '.join(fail['points'])})"
                                                      if fail["points"] else ""))
    summary["table_positions"] = int(res.table.phi.shape[0])
    summary["dense_positions"] = int(res.dense.phi.shape[0])
    if res.status == kc.BAD_GEOMETRY:
        from .study.sweep_spec import geometry_problems
        summary["reason"] = "; ".join(geometry_problems(res.plan, res.plan.par))
    summary.update(peak_summary(res))
    fr = getattr(res.dense.forces, "friction", None)
    if fr is not None:      # [mechanism.friction]: losses, efficiency, the bearings' p and p*v
        summary.update(fr.summary(res.dense.phi))
    for case in res.dynamics or ():
        for k, v in case.summary_lines().items():
            summary[f"{case.name} {k}"] = v
        summary.update(motion_force_summary(case.name, (res.motion_forces or {}).get(case.name),
                                            constant))
    if res.reduced is not None:
        summary.update(res.reduced.summary())
    if res.flywheel is not None:
        summary.update(res.flywheel.summary())
    if res.cyclogram is not None and res.cyclogram.rings:
        summary.update(res.cyclogram.summary())
    return RunOutcome("scene", out, pics, summary)


def constant_forces(res):
    """The scene's kinetostatics at its constant crank speed over the dense
    revolution (the forces analysis's own, or computed from the dense
    curves' analogs), or None without bodies or second analogs."""
    import numpy as np
    if res.dense.forces is not None:
        return res.dense.forces
    if not res.study.mechanism.bodies or not np.isfinite(res.dense.d2).any():
        return None
    from .solve.reactions import scene_forces
    return scene_forces(res.study.mechanism, res.plan, res.dense)


def motion_force_summary(name, records, constant) -> dict:
    """Summary lines of a dynamics case's kinetostatics along the motion: the
    peak reaction and the peak |M_bal| of its steady rotation (or of its
    samples), beside the constant-speed peaks."""
    import numpy as np
    if not records:
        return {}
    rec = records.get("steady") or records["samples"]
    where = "steady rotation" if rec.record == "steady" else "samples"
    out = {}
    peaks = rec.peaks()
    if peaks:
        j = max(range(len(peaks)), key=lambda i: peaks[i][1])
        jn, r, t, phi, _ = peaks[j]
        line = f"{r:.1f} N at {jn}, t = {t:.4f} s, phi1 = {phi:.1f} deg ({where})"
        if constant is not None:
            cj = max(constant.peaks(), key=lambda p: p[1])
            line += f"; constant speed: {cj[1]:.1f} N at {cj[0]}, phi1 = {cj[2]:g} deg"
        out[f"{name} peak_reaction"] = line
    mb, t, phi = rec.peak_M_bal()
    line = f"{mb:.4g} N·m at t = {t:.4f} s, phi1 = {phi:.1f} deg ({where})"
    if constant is not None and np.isfinite(constant.M_bal).any():
        k = int(np.nanargmax(np.abs(constant.M_bal)))
        line += (f"; constant speed: {constant.M_bal[k]:.4g} N·m at phi1 = "
                 f"{np.rad2deg(constant.phi[k]):g} deg")
    out[f"{name} peak_M_bal"] = line
    out[f"{name} equilibrium_residual"] = f"{rec.worst_residual():.2g} at worst"
    return out


# ----------------------------------------------------------------- tolerance analysis
def tolerance_setup(source, candidate=None, *, samples=None, metrics=None):
    """(study, design mechanism, label, sweep spec or None, origin attrs,
    ToleranceSpec) of a tolerance analysis: the design (``tolerance_design``),
    its study's [tolerance] (ISO 2768-f without one) with the metrics asked
    for, the sample count checked."""
    from dataclasses import replace

    from .analysis.candidate import tolerance_design
    from .model.metric_catalogue import TOLERANCED_METRICS
    from .study.tolerance_spec import MAX_SAMPLES, ToleranceSpec
    study, mech, label, sweep, origin = tolerance_design(source, candidate)
    from .solve.scene import check_centres_of_mass
    check_centres_of_mass(study)
    spec = study.tolerance or ToleranceSpec()
    if metrics:
        unknown = [m for m in metrics if m not in TOLERANCED_METRICS]
        if unknown:
            raise ValueError(f"--metrics: {unknown[0]!r} is not a metric of a build; known: "
                             f"{', '.join(TOLERANCED_METRICS)}")
        spec = replace(spec, metrics=tuple(metrics))
    if samples is not None and not 2 <= samples <= MAX_SAMPLES:
        raise ValueError(f"--samples must be between 2 and {MAX_SAMPLES:,}, got {samples:,}")
    return study, mech, label, sweep, origin, spec


def run_tolerance(source, candidate=None, out=None, *, samples=None, pictures=True,
                  overwrite=False, n_jobs=None, metrics=None) -> RunOutcome:
    """The tolerance analysis of a design (``tolerance_setup``): its results
    file, pictures and summary."""
    from .base.progress import ticking
    with ticking("tolerance"):          # a live line while it builds, solves and draws
        return _run_tolerance(source, candidate, out, samples=samples, pictures=pictures,
                              overwrite=overwrite, n_jobs=n_jobs, metrics=metrics)


def _run_tolerance(source, candidate, out, *, samples, pictures, overwrite, n_jobs, metrics):
    from .results.storage import results_output
    from .results.tolerance_file import tolerance_output, write_tolerance
    from .runs.tolerance import analyse

    def check(out):     # before the builds: never the source, nor a file not a results file
        out = results_output(out, inputs=(source,), overwrite=overwrite)
        if pictures:
            for suffix in ("histograms", "tornado"):
                check_output(out.with_name(f"{out.stem}_{suffix}.png"), inputs=(source,))
        return out
    if out is not None:
        out = check(Path(out))
    study, mech, label, sweep, origin, spec = tolerance_setup(source, candidate,
                                                              samples=samples, metrics=metrics)
    out = Path(out) if out else tolerance_output(source, origin)
    with RunLock(out):
        check(out)          # again under the lock (the default name is known only now)
        log.info("tolerance analysis of the %s: %s builds", label,
                 f"{samples or spec.samples:,}")
        a = analyse(study, mech, spec, label=label, sweep_spec=sweep, samples=samples,
                    n_jobs=n_jobs, source=source)
        write_tolerance(a, study, out, **origin)
    pics = []
    if pictures:
        import matplotlib.pyplot as plt

        from .views.tolerance_plots import histograms_figure, tornado_figure
        for make, suffix in ((histograms_figure, "histograms"), (tornado_figure, "tornado")):
            fig = make(a)
            try:
                pics.append(save_figure(fig, out.with_name(f"{out.stem}_{suffix}.png"),
                                        dpi=110))
            finally:
                plt.close(fig)
    return RunOutcome("tolerance", out, pics, tolerance_summary(a))


def tolerance_summary(a) -> dict:
    """The lines a designer reads first: the yield, the statuses, and per
    metric the design's value, the spread and the dimension that moves it most."""
    import numpy as np
    out = {"design": a.label, "builds": f"{len(a.status):,} (scrambled Sobol, seed "
                                         f"{a.spec.seed}; ISO 2768-{a.spec.iso_class} "
                                         "at this design's own sizes, where a robust search "
                                         "takes the reference design's)",
           "yield": f"{100 * a.yield_:.2f} % assemble" + (
               " and meet " + ", ".join(_bound_text(*b) for b in a.constraints)
               if a.constraints else " (no constraints given: a sweep's [sweep.constraints] "
                                     "or a scene's [tolerance.constraints] bound its metrics)")}
    counts = a.status_counts()
    if set(counts) != {"OK"}:
        out["statuses"] = ", ".join(f"{k} {v:,}" for k, v in counts.items())
    sig, lin = a.sigma_sampled(), a.sigma_linear()
    p05, p95 = a.quantiles(0.05), a.quantiles(0.95)
    share = a.contributions()
    for k, (m, u) in enumerate(zip(a.metrics, a.units)):
        unit = "" if u == "1" else f" {unit_text(u)}"
        j = int(np.nanargmax(share[k])) if np.isfinite(share[k]).any() else 0
        top = a.dimensions[j]
        part = (share[k, j] / lin[k]) ** 2 if lin[k] > 0 else float("nan")
        out[m] = (f"{a.nominal[k]:.4g}{unit}; sigma {sig[k]:.3g} (linear {lin[k]:.3g}); "
                  f"5-95 % {p05[k]:.4g} to {p95[k]:.4g}; most: {top.param} "
                  f"({100 * part:.0f} % of the variance)")
    out["wall_time"] = f"{a.wall_s:.1f} s"
    return out


def _bound_text(metric, lo, hi):
    import math
    if math.isfinite(lo) and math.isfinite(hi):
        return f"{lo:g} <= {metric} <= {hi:g}"
    return f"{metric} >= {lo:g}" if math.isfinite(lo) else f"{metric} <= {hi:g}"


# ----------------------------------------------------------------- comparison
def compare_output(paths, candidate=None, out_dir=None) -> Path:
    """The comparison's picture: next to the first results file (or in
    ``out_dir``), <stem>_vs_<stem>[...]_compare.png, or for a sweep's design
    (``candidate``: its candidate number, 'knee' resolved)
    <stem>_candidate<N>_vs_reference_compare.png."""
    first = Path(paths[0])
    folder = Path(out_dir) if out_dir else first.parent
    if candidate is not None:
        name = f"{safe_name(first.stem)}_candidate{safe_name(str(candidate))}_vs_reference"
    else:
        name = "_vs_".join(safe_name(Path(p).stem) for p in paths)
    if len(name) > COMPARE_NAME:    # many or long names: cut, and told apart by a hash of all
        import hashlib
        digest = hashlib.sha256(name.encode()).hexdigest()[:12]
        name = f"{name[:COMPARE_NAME - 13]}_{digest}"
    return folder / f"{name}_compare.png"


COMPARE_NAME = 160      # characters of a comparison picture's name before '_compare.png': a
                        # file name (and its temporary name while written) within 255 bytes


def comparison(paths, candidate=None):
    """The comparison of scene results files (the first the base), or of a
    sweep's design ``candidate`` with the sweep's reference design
    (``analysis.compare``), the arguments checked."""
    from .analysis.compare import compare_candidate, compare_files, read_design
    paths = [Path(p) for p in paths]
    if candidate is not None:
        if len(paths) != 1:
            raise ValueError("--candidate compares a design of one sweep's results file with "
                             f"its reference design; got {len(paths)} files")
        return compare_candidate(paths[0], candidate)
    if len(paths) == 1:
        read_design(paths[0])       # a sweep's file says how to pick its design
    if len(paths) < 2:
        raise ValueError(f"{paths[0] if paths else 'compare'}: give two scene results files or "
                         "more (or one sweep's results file with --candidate ID)")
    return compare_files(paths)


def run_compare(paths, candidate=None, out_dir=None, *, pictures=True):
    """`pipeline compare`: the comparison (``comparison``) and its picture;
    returns (Comparison, [picture paths]).  The picture is replaced like
    `pipeline show`'s (written to a temporary name and renamed)."""
    if out_dir is not None:
        if Path(out_dir).exists() and not Path(out_dir).is_dir():
            raise ResultsError(out_dir, "is a file; -o names the folder of the picture")
        out_dir = check_output_folder(out_dir)
    if pictures and (candidate is None or str(candidate).strip().isdigit()):
        # the picture's name is known before the designs are read ('knee' resolves later:
        # save_figure checks that one): never over an input or a results file
        number = None if candidate is None else int(candidate)
        check_output(compare_output(paths, number, out_dir), inputs=paths)
    from .base.progress import ticking
    with ticking("compare"):        # a live line while it re-runs the designs and draws
        return _run_compare(paths, candidate, out_dir, pictures)


def _run_compare(paths, candidate, out_dir, pictures):
    cmp = comparison(paths, candidate)
    pics = []
    if pictures:
        import matplotlib.pyplot as plt

        from .views.compare import comparison_figure
        fig = comparison_figure(cmp)
        try:
            number = cmp.designs[-1].candidate if candidate is not None else None
            pics.append(save_figure(fig, compare_output(paths, number, out_dir), dpi=110))
        finally:
            plt.close(fig)
    return cmp, pics
