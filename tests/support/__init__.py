"""Helpers shared by the tests, in one place: the independent slow references
(``naive``, ``naive_pareto``), the tolerances and accuracy figures
(``tolerances``), constructed cases (``lock_cases``, ``stress_cases``), sweep
helpers (``sweep_helpers``, ``sweep_fixture``) and the GPU agreement script
(``gpu_agreement``).  Tests import from here only, never from one another."""
