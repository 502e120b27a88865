"""Compiled numerical kernels.

Only ``@njit`` code over plain arrays lives here; it imports nothing but numpy,
numba and math.  Study files, HDF5, Dask, plots and the CLI live outside.
"""
