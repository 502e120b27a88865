"""The views layer: results shown to people.  Pictures (``plots``,
``dynamics_plots``, ``report_figures``), animations (``animate``), one design
drawn and explained (``show``), a sweep's text view (``browse``), the HTML
report (``report``, its templates and assets through ``page``, its explorer in
``explorer`` and ``explorer_designs``), results files as tables (``tables``)
and their CSV/Parquet files (``export``)."""
