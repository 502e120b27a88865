"""The users' CSV tables from a results file (`pipeline export OUT.h5 --csv DIR`)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from .files import replacing
from .storage import ResultsError, open_results


def _short(name, letter):
    """P9 -> V9 (velocity columns), other names -> V[name]."""
    if name.startswith("P") and name[1:].isdigit():
        return f"{letter}{name[1:]}"
    return f"{letter}[{name}]"


def export_csv(path, outdir) -> list[Path]:
    """Write points.csv, links.csv (and reactions.csv, peaks.csv, motion_<case>.csv
    when the file has them) into ``outdir``; returns the files written."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    written = []
    with open_results(path) as f:
        if f.attrs["kind"] != "scene":
            raise ResultsError(path, "export --csv writes the tables of a scene; "
                                     f"this is a {f.attrs['kind']} result (use `pipeline browse`)")
        m = f["mechanism"]
        names = list(m.attrs["point_names"])
        links = list(m.attrs["link_labels"])
        t = f["table"]
        phi = t["phi1"][()]
        cols = {"phi1_deg": phi}
        pos, vel, acc = t["position"][()], t["velocity"][()], t["acceleration"][()]
        for i, n in enumerate(names):
            cols[f"{n}_x"] = pos[:, i, 0]
            cols[f"{n}_y"] = pos[:, i, 1]
            cols[f"{_short(n, 'V')}_x"] = vel[:, i, 0]
            cols[f"{_short(n, 'V')}_y"] = vel[:, i, 1]
            cols[f"{_short(n, 'A')}_x"] = acc[:, i, 0]
            cols[f"{_short(n, 'A')}_y"] = acc[:, i, 1]
        written.append(_write(pd.DataFrame(cols), outdir / "points.csv"))
        cols = {"phi1_deg": phi}
        ang, om, ep = t["link_angle"][()], t["link_omega"][()], t["link_eps"][()]
        for j, lab in enumerate(links):
            cols[f"phi_{lab}"] = ang[:, j]
            cols[f"omega_{lab}"] = om[:, j]
            cols[f"eps_{lab}"] = ep[:, j]
        written.append(_write(pd.DataFrame(cols), outdir / "links.csv"))
        if "reactions" in t:
            from .forces import reaction_tables
            for name, df in reaction_tables(t, f["dense"]).items():
                written.append(_write(df, outdir / name))
        if "dynamics" in f:
            from .dynamics import motion_tables
            for name, df in motion_tables(f["dynamics"]).items():
                written.append(_write(df, outdir / name))
    return written


def _write(df, path):
    with replacing(path) as tmp:
        df.to_csv(tmp, index=False, float_format="%.12g")
    return path

