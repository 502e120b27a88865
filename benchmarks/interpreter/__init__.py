"""The plan interpreter the product used before the mechanism compiler:
a frozen copy, kept only so the agreement check (benchmarks/agreement.py) and
the kernel benchmarks can run the old path beside the generated kernels.
Not part of the product; delete when no benchmark needs it."""
