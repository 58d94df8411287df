#!/usr/bin/env python3
"""Compare two `geardyn fe` runs of the same scene (e.g. with and without mass scaling) on
what a quasi-static analysis sees: the DTE low-passed alike (a centred moving average over
SPAN_S, the longer mesh-mode period of the two) and binned by driver rotation over the same
window (the last whole base pitch both records cover), and k(theta) bin by bin from their
stiffness.csv as written (each low-passed over its own mesh-mode period) and recomputed from the
records with the common low-pass, k = sum W / sum (R_b2 theta - e) per bin. Prints the DTE mean and peak-to-peak of each and the relative differences.

usage: compare_fe_runs.py RUN_A RUN_B [SPAN_S]
"""
import csv, json, math, sys


def load(run):
    with open(f"{run}/history.csv") as f:
        rows = list(csv.DictReader(f))
    t = [float(r["time_s"]) for r in rows]
    rot = [float(r["driver_rotation_rad"]) for r in rows]
    dte = [float(r["dte_rad"]) for r in rows]
    force = [float(r["mesh_force_n"]) for r in rows]
    with open(f"{run}/summary.json") as f:
        summary = json.load(f)
    with open(f"{run}/stiffness.csv") as f:
        table = list(csv.DictReader(f))
    k = [float(r["mesh_stiffness_n_per_m"]) for r in table]
    e = [float(r["unloaded_te_um"]) * 1e-6 for r in table]
    return t, rot, dte, summary, k, force, e


def lowpass(values, width):
    half = width // 2
    out = [None] * len(values)
    for i in range(half, len(values) - half):
        out[i] = sum(values[i - half:i + half + 1]) / (2 * half + 1)
    return out


def main():
    a, b = sys.argv[1], sys.argv[2]
    runs = [load(a), load(b)]
    periods = [r[3]["dte_lowpass"]["period_s"] for r in runs]
    span = float(sys.argv[3]) if len(sys.argv) > 3 else max(periods)
    pitch = 2 * math.pi / 36  # driver's angular pitch of paper36
    bins = 64
    # Common window: the last whole base pitch both records cover after both statistics starts.
    start = max(r[3]["statistics_start_s"] if "statistics_start_s" in r[3] else r[3]["stats_window_s"][0] for r in runs)
    stats = []
    kbins = []
    for t, rot, dte, summary, _, force, e in runs:
        dt = t[2] - t[1]
        lp = lowpass(dte, max(1, round(span / dt)))
        wlp = lowpass(force, max(1, round(span / dt)))
        # R_b2 from the paper's k0 = T/(mean DTE R_b2^2) the summary states beside the mean DTE.
        rb2 = math.sqrt(summary["scene"]["torque"] / (summary["mesh_stiffness_from_mean_dte_n_per_m"] * summary["dte_mean_rad"]))
        wsum = [0.0] * bins
        dsum = [0.0] * bins
        end_rot = min(r[1][-1] for r in runs) - 0.5 * span * max(r[3]["scene"]["driver_speed"] for r in runs)
        begin_rot = end_rot - pitch
        sums = [0.0] * bins
        counts = [0] * bins
        for i, (ti, ri, v) in enumerate(zip(t, rot, lp)):
            if v is None or ti < start or ri < begin_rot or ri >= end_rot:
                continue
            j = min(bins - 1, int((ri - begin_rot) / pitch * bins))
            sums[j] += v
            counts[j] += 1
            # k = sum W / sum (R_b2 theta - e) per bin of the stiffness table (centred on
            # j pitch/64 of driver rotation), from signals low-passed over the common span.
            m = round((ri % pitch) / pitch * bins) % bins
            wsum[m] += wlp[i]
            dsum[m] += rb2 * v - e[m]
        kbins.append([w / d for w, d in zip(wsum, dsum) if d > 0])
        binned = [s / c for s, c in zip(sums, counts) if c > 0]
        mean = sum(binned) / len(binned)
        stats.append((mean, max(binned) - min(binned), len(binned), begin_rot))
    ka, kb = runs[0][4], runs[1][4]
    worst = max(abs(x / y - 1) for x, y in zip(ka, kb))
    mean_k = (sum(ka) / len(ka)) / (sum(kb) / len(kb)) - 1
    ca, cb = kbins
    worst_common = max(abs(x / y - 1) for x, y in zip(ca, cb)) if len(ca) == len(cb) else float("nan")
    mean_common = (sum(ca) / len(ca)) / (sum(cb) / len(cb)) - 1
    print(f"low-pass span {span*1e3:.3f} ms, window from {start*1e3:.2f} ms, driver rotation {math.degrees(stats[0][3]):.2f} deg + one base pitch, {stats[0][2]} bins")
    for name, (mean, pp, _, _), r in zip((a, b), stats, runs):
        print(f"{name}: DTE mean {mean:.5e} rad, peak-to-peak {pp:.5e} rad, k mean {sum(r[4])/len(r[4]):.5e} N/m, wall {r[3]['wall_s']:.0f} s, mass scaling {r[3]['mass_scaling']['factor']:.1f}")
    print(f"A/B - 1: DTE mean {stats[0][0]/stats[1][0]-1:+.3%}, peak-to-peak {stats[0][1]/stats[1][1]-1:+.3%}; stiffness.csv k mean {mean_k:+.3%}, worst bin {worst:.3%}; k with the common low-pass ({len(ca)}/{len(cb)} bins) mean {mean_common:+.3%}, worst bin {worst_common:.3%}")


main()
