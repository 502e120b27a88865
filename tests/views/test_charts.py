"""The report's charts (pipeline.views.charts): figures as plotly.js data, a
user's text never markup, limits drawn where they are and named where they
are off the axis; a chart's element cannot be closed by its data."""

import json
import re
from types import SimpleNamespace

import numpy as np

from pipeline.kernels import config as kc
from pipeline.views import charts


class FakeTolerance(SimpleNamespace):
    """What ``tolerance_chart`` reads of a runs.tolerance.ToleranceAnalysis."""

    def sigma_linear(self):
        return np.array([0.01, 0.5])

    def sigma_sampled(self):
        return np.nanstd(self.values, axis=0)

    def quantiles(self, q):
        return np.nanquantile(self.values, q, axis=0)


def _tolerance(constraints):
    rng = np.random.default_rng(0)
    values = np.column_stack([rng.normal(11.0, 0.01, 400), rng.normal(674, 0.5, 400)])
    status = np.full(400, kc.OK, np.int8)
    status[:4] = 3
    return FakeTolerance(metrics=("stroke", "peak_reaction"), units=("mm", "N"),
                         status=status, values=values, nominal=np.array([11.0, 674.0]),
                         constraints=constraints, label="<b>knee</b>", yield_=0.99)


def _data(html_text):
    spec = re.search(r'<script type="application/json" class="chart-data">(.*?)</script>',
                     html_text, re.S).group(1)
    return json.loads(spec)


def test_tolerance_chart_draws_near_limits_and_names_far_ones():
    fig, height = charts.tolerance_chart(_tolerance((("stroke", 10.99, 15.0),)))
    lay = fig["layout"]
    lines = [s for s in lay["shapes"] if s["type"] == "line" and s["line"]["color"] == charts.LIMIT]
    assert [s["x0"] for s in lines] == [10.99]            # the near limit, drawn on panel 1
    lo, hi = lay["xaxis"]["range"]
    assert lo < 10.99 and hi < 12                          # the far one does not stretch it
    far = [a["text"] for a in lay["annotations"] if "limit" in a["text"]]
    assert far == ["limit 15 &#8594;"]
    # the builds that assemble only; the title counts the others
    assert len(fig["data"][0]["x"]) == 396 and "4 do not assemble" in lay["title"]["text"]
    assert height > 300


def test_a_users_text_is_never_markup_in_a_chart():
    fig, _ = charts.tolerance_chart(_tolerance(()))
    title = fig["layout"]["title"]["text"]
    assert "&lt;b&gt;knee&lt;/b&gt;" in title and "<b>knee" not in title
    page = charts.chart_html((fig, 400), 'the "knee" </script>')
    assert page.count("</script>") == 1 and "&quot;knee&quot;" in page
    assert _data(page)["layout"]["title"]["text"] == title


def test_comparison_chart_says_when_no_design_has_forces():
    path = np.column_stack([np.linspace(0, 1, 5), np.linspace(0, 2, 5)])
    design = SimpleNamespace(label="reference design", working_point="P8", path=path,
                             phi=np.linspace(0, -360, 5), motion={"stroke": 2.2}, M_bal=None)
    cmp = SimpleNamespace(designs=[design], rows=[], labels=["reference design"])
    fig, _ = charts.comparison_chart(cmp)
    notes = [a["text"] for a in fig["layout"]["annotations"]]
    assert notes.count("no force analysis in any design") == 2
    assert fig["layout"]["xaxis2"]["autorange"] == "reversed"     # the crank turns negative
