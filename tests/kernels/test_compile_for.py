"""kernels.config.compile_for: a kernel compiled for one signature, once, from
whichever thread asks first; the others wait and find it compiled (numba refused a
second thread that asked before the first disabled compiling)."""

import threading

from numba import njit, types

from pipeline.kernels.config import compile_for


def test_threads_that_ask_at_once_get_one_compiled_signature():
    for _ in range(5):
        @njit(cache=False)
        def twice(x):
            return 2.0 * x

        start, errors = threading.Barrier(4), []

        def ask():
            start.wait()
            try:
                compile_for(twice, types.float64(types.float64))
            except Exception as e:          # (the refusal this guards against)
                errors.append(e)
        threads = [threading.Thread(target=ask) for _ in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert errors == []
        assert len(twice.signatures) == 1 and twice(1.5) == 3.0
        assert not twice._can_compile       # no other signature later
