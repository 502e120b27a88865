"""A search journals the generations finished within a quarter of a second in
one block file; the journal reads chunks and blocks alike (done, load), a
block holds consecutive generations only, and a damaged block is named in one
line that says what to do."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.base.errors import ResultsError
from pipeline.results.journal import Journal


def generation(g, n=5):
    rng = np.random.default_rng(g)
    return (g, rng.random((n, 3)), rng.integers(0, 3, n).astype(np.int8),
            rng.random((n, 4)), np.array([g], np.int64))


def test_blocks_and_chunks_read_alike(tmp_path):
    j = Journal(tmp_path / "s.h5")
    j.start({"journal_kind": "search"})
    j.save(0, *generation(0)[1:])                        # one generation: a chunk file
    j.save_block([generation(g) for g in (1, 2, 3)])     # three: one block file
    j.save_block([generation(4)])
    assert j.done() == [0, 1, 2, 3, 4]
    assert sorted(p.name for p in j.dir.glob("*.npz")) == [
        "block_0000001_0000003.npz", "block_0000004_0000004.npz", "chunk_0000000.npz"]
    for g in range(5):
        want = generation(g)[1:]
        got = j.load(g)
        assert len(got) == 4
        for a, b in zip(want, got):
            assert a.dtype == b.dtype and np.array_equal(a, b)


def test_a_block_holds_consecutive_generations(tmp_path):
    j = Journal(tmp_path / "s.h5")
    j.start({})
    with pytest.raises(ValueError, match="consecutive"):
        j.save_block([generation(1), generation(3)])
    assert j.done() == []


def test_a_damaged_block_is_named_with_what_to_do(tmp_path):
    j = Journal(tmp_path / "s.h5")
    j.start({})
    j.save_block([generation(g) for g in (0, 1)])
    p = j.dir / "block_0000000_0000001.npz"
    p.write_bytes(p.read_bytes()[:100])
    with pytest.raises(ResultsError) as e:
        j.load(1)
    msg = str(e.value)
    assert "block_0000000_0000001.npz" in msg and "damaged journal block" in msg
    assert "--resume" in msg and "\n" not in msg
