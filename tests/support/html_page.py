"""Reading a report page the way its offline checks need: its markup with the
text of every <script> left out (plotly.js names web addresses for map tiles
and its logo that the report never fetches: text inside a script, not markup)."""

import re

SCRIPT = re.compile(r"(<script\b[^>]*>).*?(</script>)", re.IGNORECASE | re.DOTALL)


def markup_only(page: str) -> str:
    """``page`` with each <script> element emptied (its tag and attributes kept)."""
    return SCRIPT.sub(r"\1\2", page)


def packed_element(page: str, element_id: str) -> str:
    """The text of the packed <script> element ``element_id`` (page.packed)."""
    return page.split(f'id="{element_id}">', 1)[1].split("</script>", 1)[0]


def explorer_data(page: str) -> dict:
    """The explorer's data in a report page as its script reads it: the JSON of
    #explorer-data, inflated, with each array of the binary block in
    #explorer-arrays (ids, feasible, every column's values) as a NumPy array."""
    import json

    from pipeline.views.page import block_array, unpacked
    d = json.loads(unpacked(packed_element(page, "explorer-data")))
    block = unpacked(packed_element(page, "explorer-arrays"))
    d["ids"] = block_array(block, d["ids"])
    d["feasible"] = block_array(block, d["feasible"])
    for c in d["columns"]:
        c["values"] = block_array(block, c["values"])
    return d
