"""A design as a CAD drawing (`pipeline export RESULTS --dxf DIR [--svg]`).

One DXF file per design (R2013, units millimetres: ``$INSUNITS`` = 4), read from
a scene results file (a sweep's design is re-run as a scene first,
``views.export.export_drawing``):

* the mechanism at chosen crank angles, one block per position
  (``POSITION_1`` ...), every block inserted at the origin so that its own
  coordinates are the mechanism's, in mm;
* a layer per link, named with the link's name (a body's name; without mass
  data ``crank`` or ``link P2-P3``) made fit for DXF's layer names;
* every point a POINT and a CIRCLE (layer ``JOINTS``): of the pin diameter
  d_min where the scene sized the pins (a force analysis, ``[output.pins]``),
  else of the nominal diameter ``NOMINAL_MARK_MM``; fixed pivots marked as
  ground (layer ``GROUND``); every guide or slot a line over the length its
  slider travels in a revolution (layer ``GUIDES``: in the blocks where the
  guide moves, once where it is fixed);
* the working point's path, and with ``paths`` every moving point's, as a
  polyline through the dense positions (layer ``PATHS``);
* an aligned dimension of every link length (a drawn segment whose length
  stays the same over the revolution; layer ``DIMENSIONS``) at the first
  drawn position, and a text block with the design's parameters, the study's
  name and the file it came from (layer ``TEXT``).

Each point's circle, POINT and path, each dimension and each block insert
carries what it stands for as extended data of the application ``PIPELINE``
(a point's name, a pin's d_min, a crank angle), so that a program reading the
file back finds them without guessing.  ``svg`` also renders the drawing to
SVG with ezdxf's drawing add-on.
"""

from __future__ import annotations

import logging
import math
import re
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..base.files import (check_output, check_output_folder, replacing, safe_name,
                          write_text)
from ..kernels import config as kc
from ..results.storage import attr_text, open_results
from ..base.errors import ResultsError
from ..study.reader import stored_study

APPID = "PIPELINE"            # the extended data's application name
NOMINAL_MARK_MM = 4.0          # the circle's diameter at a point without pin sizing
DXF_VERSION = "R2013"
MM = 4                         # $INSUNITS: millimetres
ANGLE_MATCH_DEG = 1e-9         # a requested angle is a stored position's within this
LENGTH_CONSTANT_MM = 1e-9      # a segment is a link length if it varies less than this
LAYER_COLOURS = (1, 5, 3, 6, 4, 30, 140, 200, 210, 40)   # ACI colours of the links' layers


@dataclass
class Geometry:
    """What the drawing reads of one design (a scene results file)."""
    study: object
    plan: object
    names: list                 # visible point names, in the file's order
    table_phi: np.ndarray       # deg, as stored
    table_pos: np.ndarray       # (n, points, 2) mm
    dense_phi: np.ndarray       # deg
    dense_pos: np.ndarray
    dense_ok: bool              # the revolution solved and closed
    pins: dict                  # point name -> pin diameter d_min, mm (sized joints only)
    tolerances: np.ndarray | None
    source: str


def read_geometry(path) -> Geometry:
    """The positions, the study and the pin diameters of a scene results file."""
    with open_results(path) as f:
        return geometry_of(f, path)


def geometry_of(f, source) -> Geometry:
    """``read_geometry`` of the open scene file ``f`` (``source``: its name
    in messages)."""
    kind = attr_text(f.attrs.get("kind"))
    if kind != "scene":
        raise ResultsError(source, f"is a {kind} result; the drawing reads a scene's positions "
                                   "(give a sweep's design with --candidate ID)")
    study = stored_study(f.attrs, source)
    if study is None:
        raise ResultsError(source, "has no stored study (attribute study_toml)")
    names = [str(attr_text(x)) for x in f["mechanism"].attrs["point_names"]]
    geo = dict(table_phi=f["table/phi1"][()], table_pos=f["table/position"][()],
               dense_phi=f["dense/phi1"][()], dense_pos=f["dense/position"][()],
               dense_ok=bool((f["dense/status"][()] == kc.OK).all())
               and attr_text(f.attrs.get("status")) == "OK")
    tols = (kc.stored_tolerances(f["mechanism/tolerances"][()])
            if "tolerances" in f["mechanism"] else None)
    sized = {}
    if "peaks" in f and "pin_d_min" in f["peaks"]:
        d = f["peaks/pin_d_min"]
        sized = dict(zip((str(attr_text(x)) for x in d.dims[0][0][()]), d[()].tolist()))
    plan = study.mechanism.compile()
    pins = {}
    for name, ip in zip(plan.joint_names, plan.joint_point):
        p, d = plan.point_names[int(ip)], sized.get(name, math.nan)
        if math.isfinite(d):
            pins[p] = max(d, pins.get(p, 0.0))      # two joints at one point: the larger pin
    return Geometry(study, plan, names, tolerances=tols, pins=pins, source=str(source), **geo)


# ----------------------------------------------------------------- which positions
def default_angles(geo: Geometry) -> list:
    """The study's first table position and the positions of the output's two
    extremes among the dense positions (the output rocker's angle; without a
    rocker, the working point along the direction it moves most), deg."""
    out = [float(geo.table_phi[0])]
    pos, names, output = geo.dense_pos, geo.names, geo.study.output
    good = np.isfinite(pos).all(axis=(1, 2))
    if not good.any():
        return out
    if output.rocker is not None:
        a, b = (names.index(q) for q in output.rocker)
        v = pos[good, b] - pos[good, a]
        value = np.unwrap(np.arctan2(v[:, 1], v[:, 0]))
    else:
        w = pos[good, names.index(output.working_point)]
        w = w - w.mean(axis=0)
        value = w @ np.linalg.svd(w, full_matrices=False)[2][0]
    phis = geo.dense_phi[good]
    for k in (int(np.argmin(value)), int(np.argmax(value))):
        if all(abs(phis[k] - q) > ANGLE_MATCH_DEG for q in out):
            out.append(float(phis[k]))
    return out


def positions_at(geo: Geometry, angles_deg) -> list:
    """(crank angle deg, (points, 2) positions mm) at each angle: the stored
    position where the angle is one of the file's (table or dense), else the
    design solved along the revolution through it.  An angle where the design
    does not assemble is an error naming it."""
    crank = geo.study.mechanism.crank
    out, missing = [], []
    for q in angles_deg:
        q = float(q)
        if not math.isfinite(q):
            raise ValueError(f"--phi: {q} is not a crank angle")
        tau = (crank.rot * (q - math.degrees(crank.phi0))) % 360.0   # travel from phi0
        q = math.degrees(crank.phi0) + crank.rot * tau                # within the revolution
        for phis, pos in ((geo.table_phi, geo.table_pos), (geo.dense_phi, geo.dense_pos)):
            k = np.flatnonzero(np.abs(phis - q) <= ANGLE_MATCH_DEG)
            if k.size:
                out.append((float(phis[k[0]]), pos[k[0]]))
                break
        else:
            out.append((q, None))
            missing.append(tau)
    if missing:
        solved = _solve_at(geo, missing)
        out = [(q, p if p is not None else solved.pop(0)) for q, p in out]
    for q, p in out:
        if not np.isfinite(p).all():
            raise ValueError(f"{geo.source}: the design is not assembled at phi1 = {q:g} deg "
                             "(its revolution fails before; see the results file's status)")
    return out


def _solve_at(geo, taus):
    """Positions at crank travels ``taus`` (deg from phi0), solved by the walk
    over the dense positions and those angles (continuation from the start)."""
    from ..solve.scene import solve_curves
    crank = geo.study.mechanism.crank
    n = geo.dense_phi.shape[0]
    grid = 360.0 * np.arange(n) / n
    travel = np.union1d(grid, np.asarray(taus, float))
    phis = crank.phi0 + crank.rot * np.deg2rad(travel)
    tols = geo.tolerances if geo.tolerances is not None else kc.default_tolerances()
    c = solve_curves(geo.plan, phis, kc.POSITIONS, np.ascontiguousarray(tols, float))
    out = []
    for t in taus:
        k = int(np.searchsorted(travel, t))
        if c.status[k] != kc.OK:
            raise ValueError(f"{geo.source}: the design does not assemble at phi1 = "
                             f"{math.degrees(crank.phi0) + crank.rot * t:g} deg "
                             f"({kc.STATUS_NAMES.get(int(c.status[k]), c.status[k])})")
        out.append(c.pos[k, :len(geo.names)])
    return out


# ----------------------------------------------------------------- links
def links(study) -> list:
    """(link name, [(a, b) segments]) of the drawing: the crank's and every
    group's segments, each on the body that carries both its points, else on
    a link of its own (``crank``, ``link P2-P3``: the segments a rigid link
    carries through its groups together)."""
    from ..study.slide_check import _carries
    m = study.mechanism
    segs = [(m.crank.pivot, m.crank.tip)] + [s for g in m.groups for s in g.segments()]
    carriers = [(b.name, _carries(b, m.groups)) for b in m.bodies]
    out, loose = {}, []
    for a, b in segs:
        owner = next((b_.name for b_ in m.bodies if a in b_.joints and b in b_.joints),
                     None)                    # jointed at both ends first, then carried
        owner = owner or next((name for name, pts in carriers if a in pts and b in pts), None)
        if owner is None:
            loose.append((a, b))
        else:
            out.setdefault(owner, []).append((a, b))
    rigid = []                       # [points carried, segments]
    for a, b in loose:
        for pts, ss in rigid:
            if a in pts and b in pts:
                ss.append((a, b))
                break
        else:
            pts = {a, b}
            for g in m.groups:
                pts.update(g.carried(pts))
            rigid.append((pts, [(a, b)]))
    for _, ss in rigid:
        if ss[0] == (m.crank.pivot, m.crank.tip) and "crank" not in out:
            name = "crank"
        else:
            seen = []
            for s in ss:
                seen += [p for p in s if p not in seen]
            name = "link " + "-".join(seen)
        out.setdefault(name, []).extend(ss)
    return list(out.items())


def layer_name(label: str, taken: set) -> str:
    """``label`` as a DXF layer name every CAD reads: letters, digits, spaces
    and - _ . $ only (the others become _), at most 255 characters, not one
    of ``taken`` (layer names ignore case; ``taken`` holds them upper-cased),
    which it joins."""
    name = re.sub(r"[^A-Za-z0-9 _.$-]", "_", str(label)).strip() or "LINK"
    name = name[:240]
    base, k = name, 2
    while name.upper() in taken:
        name, k = f"{base}_{k}", k + 1
    taken.add(name.upper())
    return name


def guides(study, names, dense):
    """(slider point, host points or None, line(positions) -> (start, end))
    of every guide and slot: the line over the length the slider travels
    along it in the revolution (``dense``: the dense positions), drawn at any
    position from the guide's own frame (its link's direction, its host
    point) there.  host None: the guide is fixed (one line for all)."""
    m = study.mechanism
    good = dense[np.isfinite(dense).all(axis=(1, 2))]
    out = []
    for g in m.groups:
        for point, (link, angle), host, _words, _keys in g.guides(m.fixed):
            if point not in names or not len(good):
                continue
            ip = names.index(point)

            def frame(pos, link=link, angle=angle, host=host, ip=ip):
                if link:
                    a, b = (pos[..., names.index(q), :] for q in link)
                    base = np.arctan2(b[..., 1] - a[..., 1], b[..., 0] - a[..., 0])
                else:
                    base = np.zeros(pos.shape[:-2])
                u = np.stack([np.cos(base + angle), np.sin(base + angle)], axis=-1)
                origin = (pos[..., names.index(host[0]), :] if host else good[0, ip])
                return origin, u

            origin, u = frame(good)
            rel = good[:, ip] - origin
            s = np.einsum("ij,ij->i", rel, u)
            nrm = np.stack([-u[:, 1], u[:, 0]], axis=-1)
            off = float(np.mean(np.einsum("ij,ij->i", rel, nrm)))
            lo, hi = float(s.min()), float(s.max())

            def line(pos, frame=frame, lo=lo, hi=hi, off=off):
                o, e = frame(pos)
                n = np.array([-e[1], e[0]])
                return o + lo * e + off * n, o + hi * e + off * n

            out.append((point, tuple(host) if host else None, line))
    return out


# ----------------------------------------------------------------- the drawing
def _span(geo, drawn):
    pts = [p for _, p in drawn] + [geo.dense_pos[np.isfinite(geo.dense_pos).all(axis=(1, 2))]
                                   .reshape(-1, 2)]
    every = np.concatenate([np.reshape(p, (-1, 2)) for p in pts])
    every = every[np.isfinite(every).all(axis=1)]
    lo, hi = every.min(axis=0), every.max(axis=0)
    return lo, hi, float(max(np.max(hi - lo), 1.0))


def _mtext_escaped(line: str) -> str:
    """A line of the study's text as MTEXT shows it (its backslash and braces
    are MTEXT's formatting codes)."""
    line = "".join(c if c.isprintable() else " " for c in str(line))
    line = line.replace("\\", "\\\\").replace("{", "\\{").replace("}", "\\}")
    return line.replace("^", "^ ")            # a caret followed by a space is a caret


def _parameter_lines(plan):
    from ..results.scene_file import parameter_units
    out = []
    for name, value in zip(plan.par_names, plan.par):
        if name.startswith("S["):
            continue
        unit = parameter_units(name)
        if unit == "rad":
            value, unit = math.degrees(value), "deg"
        out.append(f"{name} = {value:.10g} {unit if unit != '1' else ''}".rstrip())
    return out


def build_document(geo: Geometry, drawn, *, paths=False, origin_lines=()):
    """The DXF document (ezdxf) of ``geo`` at the positions ``drawn`` ((crank
    angle deg, positions) of ``positions_at``)."""
    import ezdxf
    doc = ezdxf.new(DXF_VERSION, setup=True, units=MM)
    doc.header["$MEASUREMENT"] = 1                  # metric
    doc.appids.add(APPID)
    msp = doc.modelspace()
    study, names = geo.study, geo.names
    fixed = set(study.mechanism.fixed)
    lo, hi, span = _span(geo, drawn)
    h = span / 80.0                                 # text height
    taken = {"0", "DEFPOINTS"}
    layer_of = {}
    for k, (label, _) in enumerate(links(study)):
        layer_of[label] = layer_name(label, taken)
        doc.layers.add(layer_of[label], color=LAYER_COLOURS[k % len(LAYER_COLOURS)])
    for name, colour in (("JOINTS", 7), ("GROUND", 8), ("GUIDES", 6), ("PATHS", 9),
                         ("DIMENSIONS", 3), ("TEXT", 7)):
        doc.layers.add(layer_name(name, taken), color=colour)
    segs = [(layer_of[label], a, b) for label, ss in links(study) for a, b in ss]
    the_guides = guides(study, names, geo.dense_pos)
    for k, (phi, pos) in enumerate(drawn):
        blk = doc.blocks.new(name=f"POSITION_{k + 1}")
        for layer, a, b in segs:
            blk.add_line(pos[names.index(a)], pos[names.index(b)], dxfattribs={"layer": layer})
        for i, p in enumerate(names):
            d = geo.pins.get(p)
            xdata = [(1000, p), (1040, phi)] + ([(1000, "pin d_min"), (1040, d)] if d
                                                else [(1000, "nominal mark")])
            c = blk.add_circle(pos[i], (d or NOMINAL_MARK_MM) / 2.0, dxfattribs={"layer": "JOINTS"})
            c.set_xdata(APPID, xdata)
            blk.add_point(pos[i], dxfattribs={"layer": "JOINTS"}).set_xdata(APPID, xdata[:2])
            if k == 0:
                blk.add_text(p, height=h, dxfattribs={"layer": "TEXT"}).set_placement(
                    (pos[i][0] + 0.6 * h, pos[i][1] + 0.6 * h))
        for point, host, line in the_guides:
            if host is not None:
                a, b = line(pos)
                blk.add_line(a, b, dxfattribs={"layer": "GUIDES"}).set_xdata(
                    APPID, [(1000, f"guide of {point}"), (1040, phi)])
        wp = pos[names.index(study.output.working_point)]
        blk.add_text(f"phi1 = {phi:g} deg", height=h, dxfattribs={"layer": "TEXT"}).set_placement(
            (wp[0] + 0.6 * h, wp[1] - (1.8 + 1.5 * k) * h))
        ref = msp.add_blockref(blk.name, (0.0, 0.0), dxfattribs={"layer": "0"})
        ref.set_xdata(APPID, [(1000, "crank angle phi1 [deg]"), (1040, phi)])
    for point, host, line in the_guides:                # fixed guides: once
        if host is None:
            a, b = line(drawn[0][1])
            msp.add_line(a, b, dxfattribs={"layer": "GUIDES"}).set_xdata(
                APPID, [(1000, f"guide of {point}")])
    for p in fixed:                                     # ground marks under the fixed pivots
        if p not in names:
            continue
        x, y = drawn[0][1][names.index(p)]
        s = 1.5 * NOMINAL_MARK_MM
        msp.add_lwpolyline([(x, y), (x - s, y - 1.5 * s), (x + s, y - 1.5 * s)], close=True,
                           dxfattribs={"layer": "GROUND"})
        for j in range(4):
            x0 = x - s + j * (2 * s / 3)
            msp.add_line((x0, y - 1.5 * s), (x0 - s / 2, y - 2.1 * s),
                         dxfattribs={"layer": "GROUND"})
    moving = [p for p in names if p not in fixed]
    for p in (moving if paths else [study.output.working_point]):
        path = geo.dense_pos[:, names.index(p)]
        if not np.isfinite(path).all():
            path = path[np.isfinite(path).all(axis=1)]
        if len(path) < 2:
            continue
        pl = msp.add_lwpolyline([tuple(q) for q in path], format="xy", close=geo.dense_ok,
                                dxfattribs={"layer": "PATHS"})
        pl.set_xdata(APPID, [(1000, p)])
    first = drawn[0][1]
    for label, ss in links(study):                     # link lengths: constant segments
        for a, b in ss:
            ia, ib = names.index(a), names.index(b)
            length = np.hypot(*(geo.dense_pos[:, ib] - geo.dense_pos[:, ia]).T)
            length = length[np.isfinite(length)]
            if not len(length) or np.ptp(length) > LENGTH_CONSTANT_MM * max(1.0, length.max()):
                continue
            dim = msp.add_aligned_dim(p1=first[ia], p2=first[ib], distance=2.5 * h,
                                      override={"dimtxt": h, "dimasz": h, "dimdec": 3},
                                      dxfattribs={"layer": "DIMENSIONS"})
            dim.render()
            dim.dimension.set_xdata(APPID, [(1000, label), (1000, a), (1000, b)])
    lines = [f"Study: {study.name}", f"Title: {study.title}", *origin_lines,
             "Units: mm; crank angles phi1 in deg",
             "Positions: " + ", ".join(f"phi1 = {q:g}" for q, _ in drawn),
             "Parameters:", *_parameter_lines(geo.plan)]
    text = msp.add_mtext("\\P".join(_mtext_escaped(t) for t in lines),
                         dxfattribs={"layer": "TEXT", "char_height": h})
    text.set_location((hi[0] + 8 * h, hi[1]))
    return doc


def audit_errors(doc) -> list:
    """ezdxf's audit of ``doc``: the errors it found (none for a drawing
    written here)."""
    auditor = doc.audit()
    return [str(e.message) for e in auditor.errors]


def svg_text(doc) -> str:
    """The drawing's model space rendered to SVG by ezdxf's drawing add-on."""
    from ezdxf.addons.drawing import Frontend, RenderContext, layout, svg
    backend = svg.SVGBackend()
    Frontend(RenderContext(doc), backend).draw_layout(doc.modelspace(), finalize=True)
    return backend.get_string(layout.Page(0, 0, layout.Units.mm,
                                          margins=layout.Margins.all(10)))


@contextmanager
def _quiet_ezdxf():
    """ezdxf's own log lines (the tables it sets up, what its audit adds) are
    not the user's business: shown only with -v."""
    log = logging.getLogger("ezdxf")
    level = log.level
    if not logging.getLogger().isEnabledFor(logging.DEBUG):
        log.setLevel(logging.WARNING)
    try:
        yield
    finally:
        log.setLevel(level)


def write_drawing(geo: Geometry, outdir, *, phis=None, paths=False, svg=False, stem=None,
                  origin_lines=None, inputs=()) -> list[Path]:
    """The DXF (and with ``svg`` the SVG) of the design ``geo`` written into
    ``outdir`` (never over a file of ``inputs``); returns the files written."""
    drawn = positions_at(geo, default_angles(geo) if not phis else phis)
    if origin_lines is None:
        origin_lines = [f"From: {geo.source}"]
    outdir = check_output_folder(outdir)
    stem = safe_name(stem or geo.study.name or Path(geo.source).stem, "design")
    target = outdir / f"{stem}.dxf"
    for p in [target] + ([target.with_suffix(".svg")] if svg else []):
        check_output(p, inputs=inputs)         # all checked before the first is written
    with _quiet_ezdxf():
        doc = build_document(geo, drawn, paths=paths, origin_lines=origin_lines)
        errors = audit_errors(doc)
        if errors:       # a fault of this module, not of the user's file: say what it is
            raise RuntimeError(f"the DXF drawing fails ezdxf's audit: {errors[0]}")
        with replacing(target) as tmp:
            doc.saveas(tmp)
        out = [target]
        if svg:
            out.append(write_text(outdir / f"{stem}.svg", svg_text(doc)))
    return out
