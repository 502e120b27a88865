"""The runs layer: the life of a sweep or a search over many candidates.
``lifecycle``: what every run into a results file goes through (refusals,
journal, save-then-write, completion); ``sweep``: chunks of drawn candidates
through the generated kernels, on threads, Dask or the GPU (``gpu``: the same
sweep on an NVIDIA GPU, numba.cuda); ``search``: an adaptive search (pymoo)
over the same evaluator, with ``search_problem`` the problem pymoo sees and
``nsga2`` pymoo's NSGA-II on arrays."""
