"""Error metrics of the validation scenes, shared by tools/convergence and docs/validation.md.

Each metric reads a finished `turbid run` directory (probes.csv, run.json) and compares it with its
reference. The C++ validation tests (tests/validation/) compute the same numbers; keep the two in
step when a definition changes.

  dam_break_2d         RMS of the relative surge-front error (Z_sim - Z_exp) / Z_exp over the
                       Martin & Moyce (1952) points with T <= 3 (scenes/reference/...csv).
  hydrostatic_tank_2d  largest relative error |p - rho0 g (H - y)| / (rho0 g (H - y)) of the
                       pressure probes at the end of the run; also the largest max_speed over
                       sqrt(g H).
  cylinder_2d_re20     relative error of C_D (forces.csv, mean over t >= 2.5 s) against
                       Schaefer & Turek's 5.5795; also the mean C_L.
  cylinder_2d_re100    Schaefer & Turek 2D-2: largest relative error of C_D,max, C_L,max (after a
                       0.03 s moving average) and the Strouhal number (the peak of C_L's
                       periodogram) over the last 2 s, against 3.23, 1.00 and 0.30.
  buoyancy_2d          largest relative error of the mean vertical force (t >= 1 s) on the box
                       and the cylinder against rho0 g V.
  buoyancy_3d          the same for the cube and the cylinder of scenes/buoyancy_3d.yaml,
                       mean over 0.6 s <= t <= 1 s.
  poiseuille_*_2d      L2 error of the steady velocity profile (last VTK frame, bins of one
                       spacing) against physics.md D6; also the plug half-width's relative error.
  lock_exchange_*_2d   front speed U / sqrt(g' H) between x = 0.5 and 1.1 m.
  submarine_landslide* suspended height of the soil (seed paper Table 1): at the last frame (or the
                       one nearest `--time T`), the largest height above the bed, y - max(1.5 - x, 0)
                       (the 45-degree slope, then the flat bottom), of the centre of any particle of
                       a soil material (every fluid material but `water`: slide, turbidity);
                       `suspended-height [--time T] RUN...`.

Run as a script, it plots the dam-break front of one or more runs against the experiment:

  /usr/bin/python3 tools/validation_metrics.py plot-dam-break RUN_DIR [RUN_DIR...] --png FILE
"""

import argparse
import json
import math
import os
import sys

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REFERENCE_DIR = os.path.join(REPO_ROOT, "scenes", "reference")

GRAVITY = 9.81  # m/s^2, as in the scenes

# Martin & Moyce (1952), n^2 = 2: column width a, height 2a; T = t sqrt(2 g / a), Z = x_front / a.
DAM_BREAK_COLUMN_WIDTH = 0.05715  # m (2.25 in)
DAM_BREAK_T_MAX = 3.0             # compare for T <= 3
DAM_BREAK_REFERENCE = os.path.join(REFERENCE_DIR, "martin_moyce1952_surge_front_n2eq2_Ocellaris.csv")

# Hydrostatic tank (scenes/hydrostatic_tank_2d.yaml).
HYDROSTATIC_DEPTH = 1.0      # H [m]
HYDROSTATIC_DENSITY = 1000.0  # rho0 [kg/m^3]
HYDROSTATIC_PROBES = {"p_mid": 0.5, "p_bottom": 0.1}  # probe name -> height y [m]


def read_csv(path):
    """Reads a numeric CSV with a header line; lines starting with '#' are skipped.
    Returns {column name: list of floats}; each column also under its name without the unit
    ("front [m]" as "front"), unless that name is taken."""
    columns = None
    names = []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            cells = [c.strip() for c in line.split(",")]
            if columns is None:
                names = cells
                columns = {n: [] for n in names}
                continue
            for n, c in zip(names, cells):
                columns[n].append(float(c))
    if columns is None:
        raise ValueError(f"{path}: no header line")
    for n in names:
        bare = n.split(" [")[0]
        if bare and bare not in columns:
            columns[bare] = columns[n]
    return columns


def read_run(run_dir):
    """run.json and probes.csv of a finished run."""
    with open(os.path.join(run_dir, "run.json")) as f:
        report = json.load(f)
    if report.get("status") != "completed":
        raise RuntimeError(f"{run_dir}: run status is {report.get('status')!r}: {report.get('error', '')}")
    return report, read_csv(os.path.join(run_dir, "probes.csv"))


def interpolate(x, xs, ys):
    """Linear interpolation of ys(xs) at x; xs increasing. Outside the range: NaN."""
    if not xs or x < xs[0] or x > xs[-1]:
        return math.nan
    lo, hi = 0, len(xs) - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if xs[mid] <= x:
            lo = mid
        else:
            hi = mid
    if xs[hi] == xs[lo]:
        return ys[lo]
    w = (x - xs[lo]) / (xs[hi] - xs[lo])
    return ys[lo] + w * (ys[hi] - ys[lo])


# ---------------------------------------------------------------------------------------------
# Dam break


def dam_break_reference():
    ref = read_csv(DAM_BREAK_REFERENCE)
    return ref["T"], ref["Z"]


def dam_break_front(run_dir):
    """Simulated surge front as (T, Z) lists. The front_position probe gives the centre of the
    leading particle; a particle stands for a cell of width dx, so the water's edge is dx/2
    further on. We add dx/2 (then Z = 1 exactly at T = 0, as in the experiment)."""
    report, probes = read_run(run_dir)
    dx = float(report["particle_spacing"])
    a = DAM_BREAK_COLUMN_WIDTH
    scale = math.sqrt(2.0 * GRAVITY / a)
    T = [t * scale for t in probes["time"]]
    Z = [(x + 0.5 * dx) / a for x in probes["front"]]
    return T, Z


def dam_break_errors(run_dir):
    """Per experimental point with T <= 3: (T, Z_exp, Z_sim, relative error)."""
    T_sim, Z_sim = dam_break_front(run_dir)
    rows = []
    for T, Z in zip(*dam_break_reference()):
        if T > DAM_BREAK_T_MAX:
            continue
        z = interpolate(T, T_sim, Z_sim)
        if math.isnan(z):
            raise RuntimeError(f"{run_dir}: the run does not reach T = {T} (end it later)")
        rows.append((T, Z, z, (z - Z) / Z))
    return rows


def dam_break_error(run_dir):
    """RMS of the relative surge-front error over the Martin & Moyce points with T <= 3."""
    rows = dam_break_errors(run_dir)
    return math.sqrt(sum(r[3] ** 2 for r in rows) / len(rows))


def dam_break_best_offset(run_dir, max_offset=0.4, step=0.005):
    """(dT, RMS) minimising the RMS relative error of the simulated front shifted later by dT,
    Z_sim(T - dT) against Z_exp(T), for 0 <= dT <= max_offset. A small RMS with dT > 0 means the
    front speed is right and the difference is a start-up offset."""
    T_sim, Z_sim = dam_break_front(run_dir)
    points = [(T, Z) for T, Z in zip(*dam_break_reference()) if T <= DAM_BREAK_T_MAX]
    best = None
    for k in range(int(round(max_offset / step)) + 1):
        dT = k * step
        rel = [(interpolate(T - dT, T_sim, Z_sim) - Z) / Z for T, Z in points]
        if any(math.isnan(r) for r in rel):
            continue
        rms = math.sqrt(sum(r * r for r in rel) / len(rel))
        if best is None or rms < best[1]:
            best = (dT, rms)
    return best


# ---------------------------------------------------------------------------------------------
# Hydrostatic tank


def hydrostatic_pressure(y):
    """p = rho0 g (H - y) [Pa]."""
    return HYDROSTATIC_DENSITY * GRAVITY * (HYDROSTATIC_DEPTH - y)


def hydrostatic_errors(run_dir):
    """{'pressure_error': largest relative error of the pressure probes at the end,
        'speed_ratio': largest max_speed over the run / sqrt(g H),
        per probe: relative error at the end}."""
    _, probes = read_run(run_dir)
    out = {}
    worst = 0.0
    for name, y in HYDROSTATIC_PROBES.items():
        exact = hydrostatic_pressure(y)
        err = abs(probes[name][-1] - exact) / exact
        out[name] = err
        worst = max(worst, err)
    out["pressure_error"] = worst
    out["speed_ratio"] = max(probes["vmax"]) / math.sqrt(GRAVITY * HYDROSTATIC_DEPTH)
    return out


# ---------------------------------------------------------------------------------------------
# Metric by scene name (tools/convergence)

# Schaefer & Turek (1996) 2D-1 (scenes/reference/dfg_cylinder_reference_values.csv).
DFG_CD = 5.57953523384
DFG_FROM = 2.5  # s: the wake has formed


def forces_mean(run_dir, column, t_from, t_to=None):
    f = read_csv(os.path.join(run_dir, "forces.csv"))
    t = f["time [s]"]
    vals = [v for tt, v in zip(t, f[column]) if tt >= t_from and (t_to is None or tt <= t_to)]
    if not vals:
        raise ValueError(f"{run_dir}: no forces.csv rows after t = {t_from} s")
    return sum(vals) / len(vals)


def dfg_error(run_dir):
    return abs(forces_mean(run_dir, "cylinder.C_D [-]", DFG_FROM) - DFG_CD) / DFG_CD


# Schaefer & Turek (1996) 2D-2 (same file): C_D,max 3.23, C_L,max 1.00, St = f D / U_mean 0.30.
DFG2_REFERENCE = {"C_D_max": 3.23, "C_L_max": 1.00, "St": 0.30}
DFG2_WINDOW = 2.0  # s: the last two seconds of the run (about six shedding periods)
DFG2_D, DFG2_U = 0.1, 1.0  # m, m/s


def moving_average(t, y, width):
    """Centred moving average over `width` seconds; only points whose whole window lies in the data."""
    half = 0.5 * width
    out_t, out_y = [], []
    lo = hi = 0
    total = 0.0
    for k, tk in enumerate(t):
        if tk - half < t[0] or tk + half > t[-1]:
            continue
        while hi < len(t) and t[hi] <= tk + half:
            total += y[hi]
            hi += 1
        while t[lo] < tk - half:
            total -= y[lo]
            lo += 1
        out_t.append(tk)
        out_y.append(total / (hi - lo))
    return out_t, out_y


# A weakly compressible run's forces carry acoustic noise (tens of Hz) on top of the 3 Hz shedding,
# and a coarse run sheds irregularly: maxima are taken after a 0.03 s moving average (keeps 98.7%
# of a 3 Hz amplitude), and the shedding frequency is the peak of C_L's periodogram between 0.5 and
# 10 Hz, evaluated every 0.005 Hz (a zero-padded Fourier transform), instead of zero crossings, which
# miss the weak periods of an irregular signal.
DFG2_SMOOTH_PEAKS = 0.03  # s


def dominant_frequency(t, y, f_lo=0.5, f_hi=10.0, df=0.005):
    mean = sum(y) / len(y)
    best_f, best_p = f_lo, -1.0
    n = int(round((f_hi - f_lo) / df))
    for k in range(n + 1):
        f = f_lo + k * df
        w = 2.0 * math.pi * f
        c = sum((yk - mean) * math.cos(w * tk) for tk, yk in zip(t, y))
        s = sum((yk - mean) * math.sin(w * tk) for tk, yk in zip(t, y))
        if c * c + s * s > best_p:
            best_f, best_p = f, c * c + s * s
    return best_f


def dfg2_values(run_dir):
    """{'C_D_max', 'C_L_max', 'C_D_mean', 'St', 'periods'} over the last DFG2_WINDOW seconds of forces.csv."""
    f = read_csv(os.path.join(run_dir, "forces.csv"))
    t_all = f["time [s]"]
    t_from = t_all[-1] - DFG2_WINDOW
    rows = [(t, cd, cl) for t, cd, cl in zip(t_all, f["cylinder.C_D [-]"], f["cylinder.C_L [-]"]) if t >= t_from]
    if len(rows) < 50:
        raise ValueError(f"{run_dir}: too few forces.csv rows in the last {DFG2_WINDOW} s (forces_every <= 0.04 s)")
    t = [r[0] for r in rows]
    _, cd = moving_average(t, [r[1] for r in rows], DFG2_SMOOTH_PEAKS)
    ts, cl = moving_average(t, [r[2] for r in rows], DFG2_SMOOTH_PEAKS)
    freq = dominant_frequency(ts, cl)
    return {"C_D_max": max(cd), "C_L_max": max(cl), "C_D_mean": sum(r[1] for r in rows) / len(rows),
            "St": freq * DFG2_D / DFG2_U, "periods": round(freq * (ts[-1] - ts[0]), 1)}


def dfg2_error(run_dir):
    v = dfg2_values(run_dir)
    return max(abs(v[k] - ref) / ref for k, ref in DFG2_REFERENCE.items())


def buoyancy_error(run_dir, volumes=None, column="Fy [N/m]", t_from=1.0, t_to=None):
    """Largest relative error of the mean vertical force against rho0 g V over the bodies."""
    volumes = volumes or {"box": 0.2 * 0.2, "cylinder": math.pi * 0.1 * 0.1}
    worst = 0.0
    for name, v in volumes.items():
        expected = HYDROSTATIC_DENSITY * GRAVITY * v
        worst = max(worst, abs(forces_mean(run_dir, f"{name}.{column}", t_from, t_to) - expected) / expected)
    return worst


BUOYANCY_3D_VOLUMES = {"cube": 0.15 ** 3, "cylinder": math.pi * 0.075 ** 2 * 0.3}


def lock_exchange_speed(run_dir, contrast, x_from=0.5, x_to=1.1, depth=0.2):
    """Front speed U / sqrt(g' H) of a lock-exchange run: least-squares slope of the probe 'front'
    while it is between x_from and x_to (the constant-speed phase), g' = g * contrast."""
    rows = read_csv(os.path.join(run_dir, "probes.csv"))
    pts = [(t, x) for t, x in zip(rows["time"], rows["front"]) if x_from <= x <= x_to]
    if len(pts) < 3:
        raise SystemExit(f"{run_dir}: the front never crosses {x_from}-{x_to} m")
    mt = sum(t for t, _ in pts) / len(pts)
    mx = sum(x for _, x in pts) / len(pts)
    slope = sum((t - mt) * (x - mx) for t, x in pts) / sum((t - mt) ** 2 for t, _ in pts)
    return slope / math.sqrt(9.81 * contrast * depth)



# ---------------------------------------------------------------------------------------------
# Steady yield-stress Poiseuille flow (physics.md D6), from the last VTK frame of a run; the same
# metric as tests/validation/test_poiseuille.cpp (keep the two in step).

POISEUILLE_HALF_WIDTH = 0.01  # H [m]: plates at y = 0 and 2H
# scene -> (G = rho g_x [Pa/m], tau_y [Pa], K [Pa s^n], n [-]), as in scenes/poiseuille_*_2d.yaml
POISEUILLE_CASES = {
    "poiseuille_bingham_2d": (1000 * 0.0556, 0.2224, 0.1, 1.0),
    "poiseuille_hb_thinning_2d": (1000 * 0.043, 0.129, 0.145, 0.5),
    "poiseuille_hb_thickening_2d": (1000 * 0.0238, 0.0714, 0.0454, 1.5),
}


def poiseuille_profile(run_dir):
    """Bin centres y [m], mean u_x [m/s] and mean shear rate [1/s] of the fluid particles of the
    last frame in bins of one spacing across the channel."""
    from turbid_vtp import frames, read_vtp

    report, _ = read_run(run_dir)
    dx = report["particle_spacing"]
    a = read_vtp(frames(run_dir)[-1][1])
    fluid = a["kind"] == 0
    y = a["Points"][fluid, 1].astype(float)
    u = a["velocity"][fluid, 0].astype(float)
    rate = a["shear_rate"][fluid].astype(float)
    bins = int(round(2 * POISEUILLE_HALF_WIDTH / dx))
    out = ([], [], [])
    for b in range(bins):
        sel = [k for k in range(len(y)) if b * dx <= y[k] < (b + 1) * dx]
        if not sel:
            continue
        out[0].append((b + 0.5) * dx)
        out[1].append(sum(u[k] for k in sel) / len(sel))
        out[2].append(sum(rate[k] for k in sel) / len(sel))
    return out


def poiseuille_errors(run_dir, scene):
    """L2 error of the steady profile and the relative error of the plug half-width (a line fitted
    to the bins' shear rate^n where it exceeds 30% of its largest value, extrapolated to zero)."""
    G, tau_y, K, n = POISEUILLE_CASES[scene]
    H = POISEUILLE_HALF_WIDTH
    y0 = tau_y / G
    e = (n + 1) / n

    def exact(y):
        eta = max(abs(y - H), y0)
        return n / (n + 1) * (G / K) ** (1 / n) * ((H - y0) ** e - (eta - y0) ** e)

    ys, us, rates = poiseuille_profile(run_dir)
    num = sum((u - exact(y)) ** 2 for y, u in zip(ys, us))
    den = sum(exact(y) ** 2 for y in ys)
    g = [r ** n for r in rates]
    pts = [(abs(y - H), gk) for y, gk in zip(ys, g) if gk > 0.3 * max(g)]
    me = sum(p[0] for p in pts) / len(pts)
    mg = sum(p[1] for p in pts) / len(pts)
    slope = sum((p[0] - me) * (p[1] - mg) for p in pts) / sum((p[0] - me) ** 2 for p in pts)
    plug = me - mg / slope
    return {"l2": math.sqrt(num / den), "plug": plug / y0 - 1}


def poiseuille_metric(scene):
    return {
        "description": "L2 error of the steady velocity profile vs physics.md D6 (last frame)",
        "error": lambda d: poiseuille_errors(d, scene)["l2"],
        "extra": {"plug_half_width_rel_error": lambda d: poiseuille_errors(d, scene)["plug"]},
    }


METRICS = {
    **{scene: poiseuille_metric(scene) for scene in POISEUILLE_CASES},
    "lock_exchange_5pct_2d": {
        "description": "front speed U / sqrt(g' H) (theory 0.5, goal 0.43-0.52), 5% denser lock",
        "error": lambda d: lock_exchange_speed(d, 0.05),
        "extra": {},
    },
    "lock_exchange_10pct_2d": {
        "description": "front speed U / sqrt(g' H) (theory 0.5, goal 0.43-0.52), 10% denser lock",
        "error": lambda d: lock_exchange_speed(d, 0.10),
        "extra": {},
    },
    "cylinder_2d_re20": {
        "description": "relative C_D error vs Schaefer & Turek 2D-1 (5.5795), mean over t >= 2.5 s",
        "error": dfg_error,
        "extra": {"C_D": lambda d: forces_mean(d, "cylinder.C_D [-]", DFG_FROM),
                  "C_L": lambda d: forces_mean(d, "cylinder.C_L [-]", DFG_FROM)},
    },
    "cylinder_2d_re100": {
        "description": "largest relative error of C_D,max, C_L,max, St vs Schaefer & Turek 2D-2 (last 2 s)",
        "error": dfg2_error,
        "extra": {k: (lambda d, k=k: dfg2_values(d)[k]) for k in ("C_D_max", "C_L_max", "C_D_mean", "St", "periods")},
    },
    "buoyancy_2d": {
        "description": "largest relative error of the mean F_y (t >= 1 s) vs rho0 g V (box, cylinder)",
        "error": buoyancy_error,
        "extra": {},
    },
    "buoyancy_3d": {
        "description": "largest relative error of the mean F_z (0.6 s <= t <= 1 s) vs rho0 g V (cube, cylinder)",
        "error": lambda d: buoyancy_error(d, BUOYANCY_3D_VOLUMES, "Fz [N]", 0.6, 1.0),
        "extra": {},
    },
    "dam_break_2d": {
        "description": "RMS relative surge-front error vs Martin & Moyce 1952, T <= 3 (front + dx/2)",
        "error": dam_break_error,
        "extra": {},
    },
    "hydrostatic_tank_2d": {
        "description": "max relative error of the pressure probes at the end vs rho0 g (H - y)",
        "error": lambda d: hydrostatic_errors(d)["pressure_error"],
        "extra": {"max_speed_over_sqrt_gH": lambda d: hydrostatic_errors(d)["speed_ratio"]},
    },
}


# ---------------------------------------------------------------------------------------------
# Plot of the dam-break front


def plot_dam_break(run_dirs, png, labels=None):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    T_ref, Z_ref = dam_break_reference()
    ax.plot(T_ref, Z_ref, "ko", label="Martin & Moyce (1952), n$^2$ = 2")
    for i, run_dir in enumerate(run_dirs):
        report, _ = read_run(run_dir)
        T, Z = dam_break_front(run_dir)
        label = labels[i] if labels else f"turbid, dx = {report['particle_spacing']:g} m"
        label += f" (RMS rel. error {100 * dam_break_error(run_dir):.1f}%)"
        ax.plot(T, Z, "-", label=label)
    ax.axvline(DAM_BREAK_T_MAX, color="0.7", lw=0.8, ls="--")
    ax.set_xlabel("T = t sqrt(2g/a)")
    ax.set_ylabel("Z = x_front / a")
    ax.set_xlim(0, max(3.5, max(T_ref) + 0.2))
    ax.set_ylim(0.8, 5)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title("2D dam break: surge front (front probe + dx/2)")
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def plot_lock_exchange(runs, png, labels=None, depth=0.2):
    """Front position against time of lock-exchange runs; `runs` holds (run_dir, contrast) pairs.
    Axes scaled by H and H / sqrt(g' H), so that every run's theory line is the same slope 0.5."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for k, (run_dir, contrast) in enumerate(runs):
        rows = read_csv(os.path.join(run_dir, "probes.csv"))
        scale = math.sqrt(9.81 * contrast * depth)
        t = [ti * scale / depth for ti in rows["time"]]
        x = [xi / depth for xi in rows["front"]]
        label = labels[k] if labels else run_dir
        label += f" (U / sqrt(g'H) = {lock_exchange_speed(run_dir, contrast, depth=depth):.3f})"
        ax.plot(t, x, "-", label=label)
    x0 = 1.0
    ax.plot([0, 25], [x0, x0 + 0.5 * 25], "k--", lw=0.8, label="slope 0.5 (Benjamin 1968)")
    ax.axhspan(0.5 / depth, 1.1 / depth, color="0.9", zorder=0, label="fit range x = 0.5-1.1 m")
    ax.set_xlabel("t sqrt(g' H) / H")
    ax.set_ylabel("front position x_f / H")
    ax.set_xlim(0, 15)
    ax.set_ylim(0, 7.5)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title("lock exchange: front of the dense current")
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


LANDSLIDE_SLOPE_TOE = 1.5  # x [m] where the 45-degree slope of the landslide scenes meets the bottom


def suspended_height(run_dir, time=None):
    """Highest soil particle above the bed at one frame (the last, or the one nearest `time` [s]):
    (height [m], material, x [m], y [m] of that particle, soil particles counted, the frame's time
    [s]); soil = every fluid material but water."""
    from turbid_vtp import frame_at, frames, read_vtp

    report, _ = read_run(run_dir)
    names = [m["name"] for m in report["materials"]]
    t, path = frames(run_dir)[-1] if time is None else frame_at(run_dir, time)
    a = read_vtp(path)
    best = (float("-inf"), None, None, None)
    count = 0
    dims = report["dimensions"]
    for k in range(len(a["kind"])):
        if a["kind"][k] != 0 or names[a["material"][k]] == "water":
            continue
        count += 1
        x, y = float(a["Points"][k][0]), float(a["Points"][k][dims - 1])
        height = y - max(LANDSLIDE_SLOPE_TOE - x, 0.0)
        if height > best[0]:
            best = (height, names[a["material"][k]], x, y)
    return best + (count, t)


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("plot-dam-break", help="plot the surge front of runs against Martin & Moyce")
    p.add_argument("runs", nargs="+", help="run directories of scenes/dam_break_2d.yaml")
    p.add_argument("--png", required=True)
    p.add_argument("--labels", help="comma-separated legend labels, one per run")
    lx = sub.add_parser("plot-lock-exchange", help="plot the front of lock-exchange runs")
    lx.add_argument("runs", nargs="+", help="RUN_DIR:CONTRAST pairs, e.g. runs/lx5:0.05")
    lx.add_argument("--png", required=True)
    lx.add_argument("--labels", help="comma-separated legend labels, one per run")
    sh = sub.add_parser("suspended-height", help="the soil's highest point above the bed (landslide runs)")
    sh.add_argument("runs", nargs="+", help="run directories of a submarine_landslide scene")
    sh.add_argument("--time", type=float, help="the frame nearest this time [s] (default: the last frame)")
    e = sub.add_parser("error", help="print the metric of a run directory")
    e.add_argument("scene", choices=sorted(METRICS))
    e.add_argument("run")
    args = parser.parse_args(argv)
    if args.command == "plot-dam-break":
        labels = args.labels.split(",") if args.labels else None
        plot_dam_break(args.runs, args.png, labels)
        for run_dir in args.runs:
            for T, Z, z, rel in dam_break_errors(run_dir):
                print(f"{run_dir}: T = {T:.2f}  Z_exp = {Z:.2f}  Z_sim = {z:.3f}  rel = {100 * rel:+.1f}%")
            dT, rms = dam_break_best_offset(run_dir)
            print(f"{run_dir}: RMS relative error {100 * dam_break_error(run_dir):.2f}%; "
                  f"shifted by the best offset dT = {dT:.3f}: {100 * rms:.2f}%")
        print(f"wrote {args.png}")
    elif args.command == "plot-lock-exchange":
        runs = [(r.rsplit(":", 1)[0], float(r.rsplit(":", 1)[1])) for r in args.runs]
        plot_lock_exchange(runs, args.png, args.labels.split(",") if args.labels else None)
        print(f"wrote {args.png}")
    elif args.command == "suspended-height":
        for run_dir in args.runs:
            h, material, x, y, n, t = suspended_height(run_dir, args.time)
            print(f"{run_dir}: suspended height {h:.4f} m at t = {t:.3f} s ({material} particle at x = {x:.3f} m, "
                  f"y = {y:.3f} m; {n} soil particles)")
    elif args.command == "error":
        m = METRICS[args.scene]
        print(f"{m['description']}: {m['error'](args.run):.6g}")
        for name, f in m["extra"].items():
            print(f"{name}: {f(args.run):.6g}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
