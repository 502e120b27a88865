"""No -0 in what the package prints or writes: the text filter leaves every
other number alone, and a CSV table writes a signed zero as 0."""

import numpy as np
import pandas as pd

from pipeline.base.numbers import signless_zeros, unsigned_zero


def test_unsigned_zero_touches_only_zeros():
    cases = {"-0": "0", "x -0.0 mm": "x 0.0 mm", "[-0.0, 1]": "[0.0, 1]",
             "g: -0.000%": "g: 0.000%", "(-0)": "(0)", "-0.5": "-0.5", "-0.01": "-0.01",
             "1e-05": "1e-05", "lead 2-0": "lead 2-0", "10-0": "10-0", "-0.0e+00": "-0.0e+00",
             "-00": "-00", "x-0": "x-0"}
    for text, want in cases.items():
        assert unsigned_zero(text) == want, text


def test_csv_export_writes_no_minus_zero(tmp_path):
    from pipeline.views.export import _write
    df = pd.DataFrame({"a": [-0.0, 1.5, np.nan, -2.0], "n": [1, -1, 0, 2]})
    df.attrs["units"] = {"a": "mm"}
    out = _write(df, tmp_path / "t.csv", False).read_text()
    assert "-0" not in out.replace("-0.", "#") and out.splitlines()[1] == "0,1"
    back = signless_zeros(df)
    assert not np.signbit(back["a"][0]) and back["a"][3] == -2.0 and np.isnan(back["a"][2])
    assert np.signbit(df["a"][0])           # the caller's table is left as it was
