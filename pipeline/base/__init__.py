"""The base layer: what every other layer may use.  The errors a user meets
(file, field, reason), the limits with their reasons, atomic writing of files
(a temporary file renamed when complete, the run lock), the whitelist parser of
load formulas, and the installed version."""
