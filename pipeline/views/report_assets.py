"""The report page's style sheet and script, as text: they live in
``views/templates/`` (report.css, report.js; the explorer's script is
explorer.js) and go inline through the page's template (page.py).  ``CSS`` and
``SCRIPT`` stay importable here for one release."""

from .page import asset

CSS = str(asset("report.css"))
SCRIPT = str(asset("report.js"))
