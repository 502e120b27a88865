"""The runs layer: the life of a sweep or a search over many candidates.
``sweep``: chunks of drawn candidates through the generated kernels, on
threads or Dask, journalled, resumable; ``search``: an adaptive search
(pymoo) over the same evaluator, with ``search_problem`` the problem pymoo
sees and ``nsga2`` pymoo's NSGA-II on arrays; ``gpu``: the same sweep on an NVIDIA GPU (numba.cuda)."""
