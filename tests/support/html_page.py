"""Reading a report page the way its offline checks need: its markup with the
text of every <script> left out (plotly.js names web addresses for map tiles
and its logo that the report never fetches: text inside a script, not markup)."""

import re

SCRIPT = re.compile(r"(<script\b[^>]*>).*?(</script>)", re.IGNORECASE | re.DOTALL)


def markup_only(page: str) -> str:
    """``page`` with each <script> element emptied (its tag and attributes kept)."""
    return SCRIPT.sub(r"\1\2", page)
