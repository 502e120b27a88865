"""``storage.put`` names each dataset's dimensions by the nearest dimension scale
of that name (its group's, else the nearest group's above), with the scales it
found for a group kept for the group's next datasets: the same scales as a look
for each dataset, a group's own scale made after a dataset that took one from
above included."""

import h5py
import numpy as np

from pipeline.results.storage import coordinate, put


def _scales(d):
    return [[s.name for s in d.dims[i].values()] for i in range(d.ndim)]


def test_each_dataset_gets_the_nearest_scale_of_each_dimension(tmp_path):
    with h5py.File(tmp_path / "f.h5", "w") as f:
        coordinate(f, "t", [0.0, 1.0, 2.0], "s", "time")
        coordinate(f, "axis", ["x", "y"], "1", "axis")
        g = f.create_group("case")
        put(g, "early", np.zeros(3), "1", "before the group's own t", dims=("t",))
        put(g, "t", np.arange(3) * 0.5, "s", "the group's own time", dims=("t",))
        put(g, "late", np.zeros((3, 2)), "m", "after it", dims=("t", "axis"))
        tail = g.create_group("tail")
        put(tail, "deep", np.zeros(3), "1", "in a group below", dims=("t",))
        put(f, "top", np.zeros(3), "1", "at the root", dims=("t",))
        assert _scales(g["early"]) == [["/t"]]
        assert _scales(g["t"]) == [[]]          # (a scale is not its own)
        assert _scales(g["late"]) == [["/case/t"], ["/axis"]]
        assert _scales(tail["deep"]) == [["/case/t"]]
        assert _scales(f["top"]) == [["/t"]]
        assert h5py.h5ds.is_scale(g["t"].id)
