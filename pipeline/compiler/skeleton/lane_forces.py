"""The force lanes' driver of a generated module (``pipeline.compiler.lane_forces``
writes ``force_lanes`` and ``force_lane_in`` above it): a full block of force
lanes solved together, then each lane's metrics (``force_flush``), and the
scalar force stage for a lane the force lanes could not vouch for
(``force_refused``).

The text below the marker line is pasted into the generated module
(``pipeline.compiler.lane_forces``); the imports above it declare, for linters
and readers, the names the generated module gives it."""

from .header import (math, np, njit, JIT, JIT_INNER, OK, M_FORCES_DONE, M_PEAK_ACC,
                     M_PEAK_EPS, M_MIN_TRANS, SET_WANT_FORCES, SET_WANT_PEAKS,
                     SET_WANT_TRANSMISSION, SET_WANT_EQUILIBRIUM, SET_WANT_SHAKING,
                     SET_SCALAR_FORCES, SET_OMEGA1, SET_EPS1, SET_WORK_POINT,
                     T_NEWTON_TOL, T_SINGULAR, fold_cd, may_reach, function_at)
from ._mechanism import (N_JOINTS, LANES, N_FROWS, FT_COLS, ACC_COL, N_TRANS, TR_COL, F_pm,
                         F_pe, F_bad)
from .sweep_stages import (LANE_FORCES, reaction_peak, force_peaks_out, AT_FORCE_LANES,
                           FORCE_LANES_FN)

# ---- the skeleton: from here on, pasted into the generated module ----
@njit(**JIT)
def lane_forces_apply(settings):
    """Whether the force lanes compute what the settings ask for: the
    kinetostatics' peaks, with or without the working point's and the rocker's
    and the smallest transmission angle (the virtual-power residual and the
    shaking take the scalar force stage), and the settings do not ask for the
    scalar force stage (SET_SCALAR_FORCES: the baseline of the force lanes'
    tests and benchmark)."""
    return (settings[SET_WANT_FORCES] != 0.0 and settings[SET_SCALAR_FORCES] == 0.0
            and settings[SET_WANT_EQUILIBRIUM] == 0.0 and settings[SET_WANT_SHAKING] == 0.0)


# its own function, which calls nothing of settle's: the process beside the run
# compiles it from the start (pipeline.compiler.beside)
@njit(**JIT_INNER)
def force_flush(fidx, filled, FS, FT, RB, phis, tols, settings, loads, status, metrics,
                called):
    """The force lanes of candidates fidx[:filled] (the rest of the block a copy
    of lane 0), then each candidate's force metrics into its row from the
    lanes; a candidate whose lane could not vouch for it (FS's F_bad) is left
    to the scalar force stage (``force_refused``).  The force lanes through their
    address (``called``: ``callees()``)."""
    npos = phis.shape[0]
    for l in range(filled, LANES):
        for r in range(N_FROWS):
            FS[r * LANES + l] = FS[r * LANES]
        for k in range(npos):
            for q in range(FT_COLS):
                FT[k, q * LANES + l] = FT[k, q * LANES]
    function_at(called[AT_FORCE_LANES], FORCE_LANES_FN)(
        FS, FT, RB, fidx.shape[0], npos, tols[T_NEWTON_TOL], tols[T_SINGULAR],
        settings[SET_OMEGA1], settings[SET_EPS1], loads, np.int64(settings[SET_WORK_POINT]))
    want_p = settings[SET_WANT_PEAKS] != 0.0
    want_t = settings[SET_WANT_TRANSMISSION] != 0.0
    for l in range(filled):
        i = fidx[l]
        if FS[F_bad * LANES + l] != 0.0:
            continue            # (force_refused)
        # the peak reaction from the lanes' reactions: force_stage's own loop
        peak = -1.0
        peak_j = -1
        peak_phi = math.nan
        for k in range(npos):
            for j in range(N_JOINTS):
                peak, peak_j, peak_phi = reaction_peak(RB[k, 2 * j * LANES + l],
                                                       RB[k, (2 * j + 1) * LANES + l], j,
                                                       phis[k], peak, peak_j, peak_phi)
        force_peaks_out(metrics[i], peak, peak_j, peak_phi, FS[F_pm * LANES + l], False,
                        0.0, False, 0.0, 0.0)
        if want_p:
            # the working point's peak |a| from the lanes' accelerations: force_stage's loop
            peak_a = 0.0
            for k in range(npos):
                ax = RB[k, ACC_COL * LANES + l]
                ay = RB[k, (ACC_COL + 1) * LANES + l]
                if may_reach(ax, ay, peak_a):
                    a = math.hypot(ax, ay)
                    if a > peak_a or not math.isfinite(a):
                        peak_a = a
            metrics[i, M_PEAK_ACC] = peak_a / 1000.0        # m/s^2
            metrics[i, M_PEAK_EPS] = FS[F_pe * LANES + l]
        if want_t:
            # the smallest transmission angle from the lanes' |u x w|, |u . w| of every
            # item: force_stage's loop over transmission() (fold_angle's skip and atan2)
            trans = math.inf
            trans_cos = math.nan
            trans_sin = math.nan
            for k in range(npos):
                t = math.inf
                for q in range(N_TRANS):
                    t = min(t, fold_cd(RB[k, (TR_COL + 2 * q) * LANES + l],
                                       RB[k, (TR_COL + 2 * q + 1) * LANES + l], trans_cos,
                                       trans_sin))
                if t < trans or (not math.isfinite(t) and t != math.inf):
                    trans = t
                    trans_cos = math.cos(t)
                    trans_sin = math.sin(t)
            metrics[i, M_MIN_TRANS] = trans if trans <= 0.5 * math.pi else math.nan
        metrics[i, M_FORCES_DONE] = 1.0
        status[i] = OK


# inline='always': one call site (flush_forces)
@njit(inline='always', **JIT)
def force_refused(pars, fidx, filled, FS, FT, phis, phi_close, tols, settings, loads, col,
                  trail, qmax, qmin, wk, fw, ww, corr, status, metrics, settle_at,
                  called):
    """The scalar force stage (``settle_cpu`` with LANE_FORCES, called as
    ``settle_at``: through its address, with ``called``) of the candidates
    fidx[:filled] of a flushed block whose lane could not vouch for them, from
    the lane walk's class III solutions (FT's first columns)."""
    npos = phis.shape[0]
    for l in range(filled):
        if FS[F_bad * LANES + l] != 0.0:
            i = fidx[l]
            for k in range(npos):
                for q in range(trail.shape[1]):
                    trail[k, q] = FT[k, q * LANES + l]
            status[i] = settle_at(pars[i], np.int64(LANE_FORCES), phis, phi_close, tols,
                                  settings, loads, col, trail, qmax, qmin, 0.0, np.int64(-1),
                                  0.0, 0.0, wk, fw, ww, corr, metrics[i], called)
