"""A search's results file: the sweep's layout (``SweepFile``) with generation
g in its own block of rows, ``candidates/generation`` (which generation
proposed each candidate) and the per-generation history in ``/search``; and
reading it back (``read_history``, ``search_summary``)."""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path

import h5py
import numpy as np

from ..study.objectives import Feasibility
from ..study.search_spec import HV_REFERENCE, NORMALISATION, SearchSpec
from .storage import COMPRESSION, attach, attr_text, coordinate, hdf5_writing, units_attr
from .sweep_file import SweepFile, summarize
from ..study.sweep_spec import SweepSpec

# per generation, in /search: name, dtype, units, long name
HISTORY = (
    ("evaluations", "i8", "1", "designs evaluated up to and including the generation"),
    ("hypervolume", "f8", "1", "hypervolume of the feasible front so far (normalised objectives, "
                               "reference point 1.1)"),
    ("front_size", "i8", "1", "designs on the feasible front so far"),
    ("feasible", "i8", "1", "feasible designs so far"),
    ("repaired", "i8", "1", "proposals moved inside the triangle inequalities while the "
                            "generation was made"),
)


# ----------------------------------------------------------------- the results file
@dataclass(frozen=True)
class GenerationLayout(SweepSpec):
    """The sweep spec as the results file sees a search: chunk c of the sweep
    layout is generation c, rows offsets[c] .. offsets[c + 1]."""
    offsets: tuple = (0,)

    @property
    def n_chunks(self):
        return len(self.offsets) - 1

    def chunk_bounds(self, c):
        return self.offsets[c], self.offsets[c + 1]


def generation_layout(spec: SweepSpec, search: SearchSpec, sizes) -> GenerationLayout:
    offsets = tuple(int(v) for v in np.concatenate([[0], np.cumsum(sizes)]))
    n = offsets[-1]
    kw = {f.name: getattr(spec, f.name) for f in fields(SweepSpec)}
    kw.update(candidates=n, chunk_size=min(n, max(max(sizes), 10000)), seed=search.seed,
              sampler=f"{search.method} search (pymoo)")
    return GenerationLayout(**kw, offsets=offsets)


class SearchFile:
    """A search's results file: the sweep layout (``SweepFile``) with
    candidates/generation and the per-generation history in /search.
    ``problem``: the sweep's problem (``pipeline.runs.sweep.SweepProblem``), as
    ``SweepFile`` takes it."""

    def __init__(self, path: Path, study, problem, search: SearchSpec, sizes, attrs: dict):
        self.sf = SweepFile(path, study, problem)
        self.sf.spec = generation_layout(problem.spec, search, sizes)
        self.path = Path(path)
        self.search = search
        self.sizes = list(sizes)
        self.attrs = attrs

    def create(self, scale):
        """The file, with every candidate unwritten (its reference design
        evaluated: the first evaluation, which compiles a new mechanism)."""
        self.sf.create()
        n, ngen = sum(self.sizes), len(self.sizes)
        with hdf5_writing(self.path, expendable=False) as f:
            for k, v in self.attrs.items():
                f.attrs[k] = v
            f.attrs["kind_detail"] = "search"
            f.attrs["n_generations"] = ngen
            d = f["candidates"].create_dataset("generation", (n,), "i4",
                                               chunks=(self.sf.spec.chunk_size,),
                                               **COMPRESSION, fillvalue=-1)
            d.attrs.update(units="1", long_name="generation of the search that proposed the "
                                                "candidate (0: the first population)")
            attach(d, ("candidate",))
            g = f.create_group("search")
            g.attrs.update(long_name="adaptive search, per generation", method=self.search.method,
                           population=self.search.population, offspring=self.search.offspring,
                           normalisation=NORMALISATION,
                           hv_reference_point=np.full(len(scale), HV_REFERENCE),
                           hv_scale=np.asarray(scale, float),
                           objectives=list(self.sf.spec.objectives))
            coordinate(g, "generation", np.arange(ngen), "1", "generation of the search")
            for name, dtype, units, long in HISTORY:
                h = g.create_dataset(name, (ngen,), dtype,
                                     fillvalue=np.nan if dtype == "f8" else -1)
                h.attrs.update(units=units_attr(units), long_name=long)
                attach(h, ("generation",))

    def datasets(self, f):
        d = self.sf.datasets(f)
        d["candidates/generation"] = f["candidates/generation"]
        for name, *_ in HISTORY:
            d[f"search/{name}"] = f[f"search/{name}"]
        return d

    def write(self, d, gen, x, status, metrics, judged: Feasibility, row):
        """Generation ``gen``'s candidates, their constraints and feasibility
        (``study.objectives.feasibility``) and its history ``row``."""
        self.write_many(d, [(gen, x, status, metrics, judged, row)])

    def write_many(self, d, generations):
        """Consecutive generations at once, each ``(gen, x, status, metrics,
        judged, row)``: a few large writes instead of some thirty small ones
        per generation (a search's generations are small)."""
        gens = [g[0] for g in generations]
        first, end = gens[0], gens[-1] + 1
        if gens != list(range(first, end)):
            raise ValueError(f"generations {gens} are not consecutive")
        x, status, metrics = (np.concatenate([g[i] for g in generations]) for i in (1, 2, 3))
        judged = Feasibility.joined([g[4] for g in generations])
        self.sf.write_chunks(d, range(first, end), x, status, metrics, judged,
                             np.zeros((len(gens), len(self.sf.spec.triangles)), np.int64))
        lo, hi = self.sf.spec.chunk_bounds(first)[0], self.sf.spec.chunk_bounds(end - 1)[1]
        d["candidates/generation"][lo:hi] = np.repeat(gens, [len(g[1]) for g in generations])
        for name, *_ in HISTORY:
            d[f"search/{name}"][first:end] = [g[5][name] for g in generations]


# ----------------------------------------------------------------- reading it back
@dataclass
class SearchHistory:
    method: str
    evaluations: np.ndarray
    hypervolume: np.ndarray
    front_size: np.ndarray
    feasible: np.ndarray
    normalisation: str
    scale: np.ndarray


def read_history(f) -> SearchHistory | None:
    """The per-generation history of an open results file (None for a sweep)."""
    if "search" not in f:
        return None
    g = f["search"]
    return SearchHistory(method=str(attr_text(g.attrs.get("method", "?"))),
                         evaluations=g["evaluations"][()], hypervolume=g["hypervolume"][()],
                         front_size=g["front_size"][()], feasible=g["feasible"][()],
                         normalisation=str(attr_text(g.attrs.get("normalisation", ""))),
                         scale=np.asarray(g.attrs.get("hv_scale", [])))


def search_summary(out) -> dict:
    """The sweep's summary with the search's lines."""
    s = summarize(out)
    with h5py.File(out, "r") as f:
        h = read_history(f)
        if h is not None:
            s["search"] = (f"{h.method}, {len(h.evaluations)} generations, "
                           f"{int(h.evaluations[-1]):,} evaluations" if len(h.evaluations)
                           else h.method)
            if len(h.hypervolume):
                s["hypervolume"] = (f"{h.hypervolume[-1]:.4f} (feasible front; "
                                    f"{NORMALISATION})")
            seeded = attr_text(f.attrs.get("seeded_from", ""))
            if seeded:
                s["seeded from"] = f"{int(f.attrs.get('n_seeded', 0))} designs of {seeded}"
    return s
