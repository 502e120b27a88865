"""The suite's files in an order where no worker starts by waiting on the
session's sweep (``support.suite_order``, ``tests/conftest.py``)."""

from support.suite_order import by_file, files_in_order, sweep_readers


def test_readers_of_the_first_half_but_the_first_go_behind_its_other_files():
    names = list("abcdefgh")
    assert files_in_order(names, {"a", "b", "d", "g"}) == list("acbdefgh")
    assert files_in_order(names, {"b", "c", "h"}) == list("abdcefgh")
    for readers in ({"g", "h"}, {"c"}, set()):
        assert files_in_order(names, readers) == names


def test_this_session_s_second_file_does_not_read_the_session_sweep(request):
    """The order this session runs in (every worker collects it): the first file
    that reads the sweep is the first to ask for it, and the first half's other
    files come before any other reader."""
    files = by_file(request.session.items)
    names = list(files)
    readers = sweep_readers(files)
    if len(readers) < 2:
        return              # (a part of the suite run alone)
    first = names.index(readers[0])
    others = [names.index(n) for n in readers[1:]]
    stay = [k for k, n in enumerate(names) if n not in readers and k < len(names) // 2]
    assert first < min(others)
    assert max(stay, default=-1) < min(others)
