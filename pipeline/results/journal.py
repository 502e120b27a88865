"""The journal of a run (sweep or search): every finished chunk saved atomically
in a folder ``OUT.h5.parts`` beside the results file, the source of truth until
the run completes (``--resume`` rebuilds the results file from it)."""

from __future__ import annotations

import json
import re
import shutil
import zipfile
from pathlib import Path

import numpy as np

from ..base.errors import ResultsError
from ..base.files import refuse_link, remove_stale_in, replacing
from ..kernels import sweep as ks
from .storage import study_digest
from ..study.sweep_spec import SweepSpec

_BLOCK = re.compile(r"block_(\d{7})_(\d{7})\.npz")
JOURNAL_VERSION = 3        # 2: chunks carry the draws rejected before solving; 3: 18 metric columns


class Journal:
    """Finished chunks saved atomically next to the results file.

    A run that replaces an earlier file (``--overwrite``) writes its new HDF5
    file inside the journal folder (``working_file``), so that the earlier file
    keeps its own name, untouched, until the new one is complete and renamed
    over it (``finish_run``); a run into a new name writes the results file
    itself as it goes (it can be analysed while unfinished)."""

    def __init__(self, out: Path):
        self.dir = out.with_name(out.name + ".parts")
        refuse_link(self.dir, "a run's journal folder")

    def exists(self):
        return (self.dir / "manifest.json").exists()

    def start(self, manifest):
        self.dir.mkdir(parents=True, exist_ok=True)
        self._atomic(self.dir / "manifest.json", json.dumps(manifest, indent=1).encode())

    def manifest(self):
        p = self.dir / "manifest.json"
        try:
            man = json.loads(p.read_text(encoding="utf-8"))
        except (UnicodeDecodeError, ValueError) as e:
            raise ResultsError(p, f"damaged journal manifest ({type(e).__name__}: "
                                  f"{str(e).splitlines()[0][:80]}); the run cannot be resumed: "
                                  "delete the folder and run again") from None
        if not isinstance(man, dict):
            raise ResultsError(p, "damaged journal manifest (not a JSON object); the run "
                                  "cannot be resumed: delete the folder and run again")
        return man

    def working_file(self, out: Path) -> Path:
        """Where this run writes its HDF5 file: ``out``, or, for a run that
        replaces an earlier file, a file in the journal folder."""
        if self.exists() and self.manifest().get("replaces", False):
            return self.dir / "replacement.h5"
        return out

    def clear_stale(self):
        """A killed run's temporary files in the folder removed, once for the
        run: each chunk is then written without looking through the folder
        (which grows by a file a chunk) for its own."""
        remove_stale_in(self.dir)

    def _atomic(self, path, data: bytes):
        with replacing(path) as tmp:    # the one atomic writer (files.replacing)
            tmp.write_bytes(data)

    def _npz(self, path, arrays):
        """``arrays`` (name: array) saved atomically as an uncompressed .npz at
        ``path``, written by np.savez straight into the temporary file: through a
        buffer, a sweep's chunk cost the main thread twice the time (its copies
        into a growing BytesIO), the same bytes."""
        with replacing(path, stale=False) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, **arrays)     # (the folder's stale files: clear_stale, once)

    def save(self, chunk, x, status, metrics, rejected, index=None, counts=None):
        """One chunk's rows; with store = feasible only the rows kept, their
        candidate ``index`` and the chunk's ``counts`` (SweepFile.kept)."""
        extra = {} if index is None else {"index": index, "counts": counts}
        self._npz(self.dir / f"chunk_{chunk:07d}.npz",
                  dict(x=x, status=status, metrics=metrics, rejected=rejected, **extra))

    def save_block(self, chunks):
        """Consecutive chunks ``[(chunk, x, status, metrics, rejected), ...]``
        in one file (a search's generations finished in a fraction of a
        second: one atomic write for them all, not one each)."""
        first, last = chunks[0][0], chunks[-1][0]
        if [c[0] for c in chunks] != list(range(first, last + 1)):
            raise ValueError("a journal block holds consecutive chunks")
        arrays = {}
        for chunk, x, status, metrics, rejected in chunks:
            arrays.update({f"x_{chunk}": x, f"status_{chunk}": status,
                           f"metrics_{chunk}": metrics, f"rejected_{chunk}": rejected})
        self._npz(self.dir / f"block_{first:07d}_{last:07d}.npz", arrays)

    def _blocks(self):
        """{(first, last): path} of the block files."""
        out = {}
        for p in self.dir.glob("block_*.npz"):
            m = _BLOCK.fullmatch(p.name)
            if m:
                out[int(m.group(1)), int(m.group(2))] = p
        return out

    def done(self):
        out = set()
        for p in self.dir.glob("chunk_*.npz"):
            out.add(int(p.stem.split("_")[1]))
        for first, last in self._blocks():
            out.update(range(first, last + 1))
        return sorted(out)

    def load(self, chunk):
        p = self.dir / f"chunk_{chunk:07d}.npz"
        keys, what = ("x", "status", "metrics", "rejected"), "chunk"
        if not p.exists():
            for (first, last), b in self._blocks().items():
                if first <= chunk <= last:
                    p, what = b, "block"
                    keys = tuple(f"{k}_{chunk}" for k in keys)
                    break
        try:
            with np.load(p) as z:
                rows = tuple(z[k] for k in keys)
                if "index" in z:
                    rows += (z["index"], z["counts"])
                return rows
        except (OSError, ValueError, KeyError, zipfile.BadZipFile) as e:
            raise ResultsError(p, f"damaged journal {what} ({e}); delete it and run again with "
                                  f"--resume: only that {what} is computed again") from None

    def remove(self):
        shutil.rmtree(self.dir, ignore_errors=True)


def manifest_for(study, spec: SweepSpec):
    return {"journal_version": JOURNAL_VERSION, **study_digest(study),
            "study_file": str(study.path),
            "candidates": spec.candidates, "chunk_size": spec.chunk_size, "seed": spec.seed,
            "sampler": spec.sampler, "positions": spec.positions, "store": spec.store,
            "metric_columns": ks.N_METRICS}


# what a journal written before a manifest key existed meant by it (18 metric
# columns: journal version 3's)
MANIFEST_DEFAULTS = {"store": "all", "metric_columns": 18, "cad_reports_sha256": ""}
