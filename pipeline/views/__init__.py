"""The views layer: results shown to people.  Pictures (``plots``,
``dynamics_plots``, ``report_figures``), animations (``animate``), one design
drawn and explained (``show``), a sweep's text view (``browse``), the HTML
report (``report``, ``report_assets``), results files as tables (``tables``)
and their CSV/Parquet files (``export``)."""
