"""Shared helpers for the sweep tests."""

import h5py
import numpy as np

VOLATILE = {"created", "wall_time_s", "engine"}


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
                assert np.array_equal(np.asarray(oa.attrs[key]), np.asarray(ob.attrs[key])), (n, key)
            if isinstance(oa, h5py.Dataset):
                np.testing.assert_array_equal(oa[()], ob[()], err_msg=n)
