"""The results layer: the HDF5 format, written (from the arrays the computing
layers hand over) and read.  ``storage``: self-describing files, datasets with
units and long names, named dimensions; ``scene_file``, ``sweep_file`` and
``search_file``: the layout of each kind of results file; ``journal``: a
run's finished chunks beside its results file, the source of truth until the
run completes."""
