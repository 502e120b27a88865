"""One design over one revolution: the curves of a scene (``scene``), the
joint reactions, balancing moment and pin sizing (``reactions``), the peaks
refined between positions (``peaks``) and the motion of the crank under a
driving moment (``crank_motion``).  Pure computation over the compiled plan:
the results are handed to the results layer, which writes them."""
