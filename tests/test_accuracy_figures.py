"""The table "Accuracy figures" of the guide's page docs/guide/accuracy.md (once
the README's) and tests/support/tolerances.py state the same numbers: every figure
lives once in tolerances.py (where the tests assert it), and this test fails when
the page says something else."""

import re
from pathlib import Path

from support import tolerances

PAGE = Path(__file__).resolve().parent.parent / "docs" / "guide" / "accuracy.md"
NUMBER = re.compile(r"(?<![\w.])\d+(?:\.\d+)?e[-+]?\d+(?![\w.])")    # 1e-7, 5.1e-5, 7.2e-12


def page_figures():
    """The table's rows: first cell -> the numbers written in its figure cell."""
    text = PAGE.read_text()
    head = text.index("**Accuracy figures**")
    rows = {}
    for line in text[head:].splitlines()[1:]:
        if rows and not line.startswith("|"):
            break
        if not line.startswith("|") or line.startswith("|---") or line.startswith("| what |"):
            continue
        what, figure = (c.strip() for c in line.strip("|").split("|", 1))
        rows[what] = [float(x) for x in NUMBER.findall(figure)]
    return rows


def test_the_page_has_one_table_of_figures():
    text = PAGE.read_text()
    assert text.count("**Accuracy figures**") == 1
    assert len(page_figures()) == len(tolerances.README_FIGURES)


def test_the_page_figures_are_the_tolerances():
    rows = page_figures()
    for start, names in tolerances.README_FIGURES.items():
        found = [what for what in rows if what.startswith(start)]
        assert len(found) == 1, f"accuracy.md table: no single row starting {start!r}: {found}"
        written = rows[found[0]]
        held = [getattr(tolerances, n) for n in names]
        assert written == held, (f"accuracy.md row {found[0]!r} states {written}, "
                                 f"tests/support/tolerances.py {dict(zip(names, held))}")


def test_the_parser_reads_what_is_written():
    """The number pattern takes figures, not settings written as words or counts."""
    assert NUMBER.findall("within 5.1e-5 at 12 positions; 7.5e-4 at 720; 3x; 8th-order") == \
        ["5.1e-5", "7.5e-4"]
