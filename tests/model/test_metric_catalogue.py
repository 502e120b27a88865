"""The catalogue of metrics (pipeline.model.metric_catalogue) is the one place a metric is
described: the study format, the stored columns, the results file's attributes
and docs/guide/metrics.md all read it."""

from pathlib import Path

import numpy as np

import pipeline.model.metric_catalogue as mc
from pipeline.kernels import sweep as ks

ROOT = Path(__file__).resolve().parents[2]


def test_every_entry_reads_a_column_of_the_kernels_row():
    """... or, a robust metric, one of the columns after the kernels' own (filled
    from a design's builds, pipeline.runs.builds.RobustBuilds); a friction metric,
    one after the robust ones (pipeline.runs.sweep_friction)."""
    for m in mc.CATALOGUE:
        if m.stage == "robust":
            assert ks.N_METRICS <= m.column < mc.N_ROBUST_ROW, m.name
        elif m.stage == "friction":
            assert mc.N_ROBUST_ROW <= m.column < mc.N_ROW, m.name
        else:
            assert 0 <= m.column < ks.N_METRICS, m.name
        assert m.stage in mc.STAGES, m.name
        assert m.units and m.long_name, m.name
        assert not m.rounding or m.units == "1", m.name     # compared absolutely
    assert len(mc.BY_NAME) == len(mc.CATALOGUE)        # one entry per name
    for m in mc.CATALOGUE:
        if m.larger_is_better:
            alt = mc.BY_NAME[m.larger_is_better]
            assert alt.column == m.column and not alt.larger_is_better


def test_the_study_format_and_the_stored_columns_read_the_catalogue():
    assert mc.METRICS == {m.name: (m.units, m.long_name, m.stage) for m in mc.CATALOGUE}
    assert set(mc.DEFAULT_METRICS) <= set(mc.BY_NAME)
    assert mc.NOT_OBJECTIVES == {"min_transmission_angle": "transmission_deviation",
                                 "build_yield": "build_loss"}
    rows = np.arange(3 * mc.N_ROW, dtype=float).reshape(3, mc.N_ROW) - 7.5
    for m in mc.CATALOGUE:
        want = rows[:, m.column] * m.factor + m.offset
        np.testing.assert_array_equal(mc.metric_values(rows, m.name), want)
    # a conversion to degrees, and the derived deviation of the transmission angle
    np.testing.assert_array_equal(mc.metric_values(rows, "dwell_start"),
                                  np.degrees(rows[:, ks.M_DWELL_START]))
    np.testing.assert_allclose(mc.metric_values(rows, "transmission_deviation"),
                               90.0 - np.degrees(rows[:, ks.M_MIN_TRANS]), rtol=0, atol=1e-12)


def test_the_docs_table_is_the_catalogue():
    assert (ROOT / "docs" / "guide" / "metrics.md").read_text() == mc.markdown_table()


def test_a_journal_of_another_metric_row_is_not_mixed_in(studies, tmp_path):
    """The journal records the width of the metric row: a journal written with
    other columns (before a metric was added) is refused, not resumed."""
    import json

    import pytest

    from pipeline.base.errors import ResultsError
    from pipeline.study.reader import load_study
    from pipeline.runs.sweep import run_sweep
    study = load_study(studies / "ov7_synthesis.toml")
    out = tmp_path / "s.h5"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(study, out, candidates=400, chunk_size=200, progress=False,
                  stop_after_chunks=1)
    man = tmp_path / "s.h5.parts" / "manifest.json"
    m = json.loads(man.read_text())
    assert m["metric_columns"] == ks.N_METRICS
    m["metric_columns"] = ks.N_METRICS - 1
    man.write_text(json.dumps(m))
    with pytest.raises(ResultsError, match="metric_columns"):
        run_sweep(study, out, progress=False, resume=True)
