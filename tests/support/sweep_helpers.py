"""Shared helpers for the sweep tests."""

import h5py
import numpy as np

VOLATILE = {"created", "wall_time_s", "engine"}
REFERENCES = {"DIMENSION_LIST", "REFERENCE_LIST"}   # dimension-scale object references


def assert_same_results(a, b):
    """Every dataset and attribute of two results files equal (bit for bit),
    except the run's date, duration and engine."""
    with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
        names_a, names_b = [], []
        fa.visit(names_a.append)
        fb.visit(names_b.append)
        assert names_a == names_b
        for key in set(fa.attrs) | set(fb.attrs):
            if key not in VOLATILE:
                assert np.array_equal(np.asarray(fa.attrs[key]), np.asarray(fb.attrs[key])), key
        for n in names_a:
            oa, ob = fa[n], fb[n]
            for key in oa.attrs:
                if key in REFERENCES:   # object references: the names they point to
                    continue
                assert np.array_equal(np.asarray(oa.attrs[key]), np.asarray(ob.attrs[key])), (n, key)
            if isinstance(oa, h5py.Dataset):
                assert [[s.name for s in d.values()] for d in oa.dims] == \
                    [[s.name for s in d.values()] for d in ob.dims], n
            if isinstance(oa, h5py.Dataset):
                np.testing.assert_array_equal(oa[()], ob[()], err_msg=n)


def run_and_analyze(study_path, out, candidates):
    """`pipeline run` of a sweep study with ``candidates`` into ``out``, then
    `pipeline analyze`; returns the loaded study and ``out``."""
    from pipeline.cli import main
    from pipeline.study import load_study
    assert main(["run", str(study_path), "-o", str(out), "--candidates", str(candidates),
                 "-q"]) == 0
    assert main(["analyze", str(out), "-q"]) == 0
    return load_study(study_path), out


def assert_fronts_are_the_brute_force_rank(path, min_feasible=20):
    """The fronts of a sweep's stored analysis are those of a brute-force
    dominance test over its feasible candidates, and the knee is on front 1."""
    from support.naive_pareto import brute_force_rank
    from pipeline.analysis import read_analysis, read_sweep
    from pipeline.storage import open_results
    data = read_sweep(path)
    with open_results(path, "sweep") as f:
        an = read_analysis(f)
    assert data.feasible.sum() >= min_feasible
    np.testing.assert_array_equal(an.rank, brute_force_rank(data.F, data.feasible))
    assert (an.rank[an.front1] == 1).all() and an.rank[an.knee] == 1
