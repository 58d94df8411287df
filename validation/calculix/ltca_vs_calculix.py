#!/usr/bin/env python3
"""The LTCA's static transmission error against CalculiX (an independent FE code) on the same mesh.

geardyn writes the LTCA's own meshes of both gears (`geardyn mesh`, VTK, 8-node quadrilaterals)
and runs its LTCA (`geardyn ltca --positions N --relief none`). This script places both meshes
as the LTCA does (`GearPair::mesh_placement`: gear 1 at the origin turned by -psi1 - pi/2 + theta1,
gear 2 at (a, 0) turned by pi/2 - psi2 - theta1 z1/z2), and for every LTCA position writes a
CalculiX model:

* CPE8 plane-strain elements (CalculiX expands them into 20-node bricks with reduced
  integration: a different element from geardyn's fully integrated Q8), E, nu and the face
  width of the case;
* frictionless surface-to-surface penalty contact between the drive flanks (tooth-local left
  side, the tip land's left half and the fillet above r = 54.5 mm included) of the fine teeth;
* gear 1's bore held, gear 2's bore turned rigidly by phi (counter-clockwise: the driven gear
  lagging) in 8 equal increments up to 1.12 x the LTCA's STE there;

reads the reaction torque on gear 2's bore per increment, and interpolates the rotation at the
LTCA's torque (a quadratic through the three increments nearest it). That rotation is the
static transmission error the LTCA reports as ste_urad (its unloaded TE is below 0.001 um for
these unmodified teeth); the mesh stiffness at the position is T / (r_b2^2 phi).

Only for the paper36 geometry (z = 36, a = 114.48 mm, zero shift): the constants below.
Not a runtime dependency of geardyn: a cross-check whose numbers are in README.md here.

usage: ltca_vs_calculix.py --geardyn PATH --out DIR [--set KEY=VALUE]... [--positions 8]
                           [--penalty 5e7] [--only J,...]
needs: ccx (Debian: apt-get install calculix-ccx), numpy
"""
import argparse, csv, math, os, re, subprocess, sys, time
import numpy as np

Z = 36                      # teeth of either gear (paper36)
A_MM = 114.48               # centre distance (zero backlash)
PSI = math.pi / (2 * Z)     # half the tooth angle on the working pitch circle (zero shift)
R_FLANK_MIN = 54.5          # contact surface from here outward (form circle 54.76 mm)
E_MPA, NU, WIDTH_MM = 206000.0, 0.3, 25.4
DENSITY_T_PER_MM3 = 7.85e-9 # 7850 kg/m^3 in tonne, mm, s (forces in N, frequencies in Hz)
R_B2_MM = 53.788005613785394
TORQUE_NMM = 143600.0


def rot(t):
    return np.array([[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]])


def read_vtk(path):
    lines = open(path).read().split("\n")
    i = next(k for k, l in enumerate(lines) if l.startswith("POINTS"))
    n = int(lines[i].split()[1])
    pts = np.array([[float(v) for v in lines[i + 1 + k].split()[:2]] for k in range(n)])
    j = next(k for k, l in enumerate(lines) if l.startswith("CELLS"))
    m = int(lines[j].split()[1])
    cells = np.array([[int(v) for v in lines[j + 1 + k].split()[1:]] for k in range(m)])
    f = next(k for k, l in enumerate(lines) if l.startswith("SCALARS fine"))
    fine = np.array([int(lines[f + 2 + k]) for k in range(m)])
    return pts, cells, fine


def boundary_edges(cells):
    """(element, local edge 0..3) of the edges that belong to one element only."""
    owners = {}
    for e, c in enumerate(cells):
        for s in range(4):
            a, b = c[s], c[(s + 1) % 4]
            owners.setdefault((min(a, b), max(a, b)), []).append((e, s, c[4 + s]))
    return [v[0] for v in owners.values() if len(v) == 1]


def drive_flank_edges(pts, cells, fine):
    """Boundary edges of fine elements beyond R_FLANK_MIN on the tooth-local left side."""
    out = []
    for e, s, mid in boundary_edges(cells):
        p = pts[mid]
        if not fine[e] or math.hypot(*p) < R_FLANK_MIN:
            continue
        k = round((math.atan2(p[1], p[0]) - math.pi / 2) / (2 * math.pi / Z))
        if (rot(-(k * 2 * math.pi / Z)) @ p)[0] < 0:
            out.append((e, s))
    return out


def bore_nodes(pts):
    r = np.hypot(pts[:, 0], pts[:, 1])
    return np.where(r < r.min() + 1e-6)[0]


def write_pair(f, gears, theta1, penalty, density=False):
    """Nodes, elements, material, the drive-flank surfaces, the contact and gear 1's held bore
    of the pair at driver rotation theta1; returns gear 2's bore nodes (CalculiX numbers), their
    positions from its centre, and the next free node number."""
    place = [(np.zeros(2), -PSI - math.pi / 2 + theta1),
             (np.array([A_MM, 0.0]), math.pi / 2 - PSI - theta1)]
    off_n = [0, gears[0][0].shape[0]]
    off_e = [0, gears[0][1].shape[0]]
    f.write("*NODE, NSET=NALL\n")
    for i, (pts, _, _) in enumerate(gears):
        x = pts @ rot(place[i][1]).T + place[i][0]
        f.writelines(f"{n + 1 + off_n[i]},{p[0]:.12f},{p[1]:.12f}\n" for n, p in enumerate(x))
    for i, (_, cells, _) in enumerate(gears):
        f.write(f"*ELEMENT, TYPE=CPE8, ELSET=G{i + 1}\n")
        f.writelines(f"{e + 1 + off_e[i]}," + ",".join(str(v + 1 + off_n[i]) for v in c8) + "\n"
                     for e, c8 in enumerate(cells))
    f.write(f"*MATERIAL, NAME=STEEL\n*ELASTIC\n{E_MPA},{NU}\n")
    if density:
        f.write(f"*DENSITY\n{DENSITY_T_PER_MM3}\n")
    for i in (1, 2):
        f.write(f"*SOLID SECTION, ELSET=G{i}, MATERIAL=STEEL\n{WIDTH_MM}\n")
    for i, (pts, cells, fine) in enumerate(gears):
        # CalculiX's faces of a plane element: S1 = nodes 1-2, S2 = 2-3, S3 = 3-4, S4 = 4-1
        f.write(f"*SURFACE, NAME=DRIVE{i + 1}\n")
        f.writelines(f"{e + 1 + off_e[i]},S{s + 1}\n" for e, s in drive_flank_edges(pts, cells, fine))
    f.write("*NSET, NSET=BORE1\n")
    f.writelines(f"{n + 1}\n" for n in bore_nodes(gears[0][0]))
    f.write("*SURFACE INTERACTION, NAME=SI\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n"
            f"{penalty:.6e},1e-3\n")
    f.write("*CONTACT PAIR, INTERACTION=SI, TYPE=SURFACE TO SURFACE\nDRIVE1,DRIVE2\n")
    b2 = bore_nodes(gears[1][0])
    x2 = gears[1][0] @ rot(place[1][1]).T
    return b2 + 1 + off_n[1], x2[b2], off_n[1] + gears[1][0].shape[0] + 1


def write_model(path, gears, theta1, phi, penalty, increments=8):
    """The static model: gear 2's bore turned rigidly by phi [rad] in `increments` steps."""
    with open(path, "w") as f:
        ids, arms, _ = write_pair(f, gears, theta1, penalty)
        f.write("*NSET, NSET=BORE2\n")
        f.writelines(f"{n}\n" for n in ids)
        f.write(f"*STEP, INC=200\n*STATIC, DIRECT\n{1.0 / increments},1.0\n*BOUNDARY\nBORE1,1,2\n")
        for n, x in zip(ids, arms):
            u = rot(phi) @ x - x
            f.write(f"{n},1,1,{u[0]:.10e}\n{n},2,2,{u[1]:.10e}\n")
        f.write("*NODE PRINT, NSET=BORE2\nRF\n*END STEP\n")
    return ids, arms


def write_modal_model(path, gears, theta1, phi, penalty, modes=4):
    """The modal model, as geardyn's `ltca::modal` with the driver held: gear 2's bore nodes
    tied to a rigid hub rotation psi (u = psi z x X, an *EQUATION per node and direction on a
    hub node's first DOF), loaded by turning the hub by phi (the static model's rotation at the
    torque), then the lowest modes about that contact state (*FREQUENCY, PERTURBATION: the
    active contact's penalty springs in the stiffness, the hub free to turn)."""
    with open(path, "w") as f:
        ids, arms, hub = write_pair(f, gears, theta1, penalty, density=True)
        f.write(f"*NODE, NSET=HUB2\n{hub},{A_MM},0.0\n*EQUATION\n")
        for n, (x, y) in zip(ids, arms):
            f.write(f"2\n{n},1,1.0,{hub},1,{y:.12f}\n2\n{n},2,1.0,{hub},1,{-x:.12f}\n")
        f.write(f"*STEP, INC=200\n*STATIC, DIRECT\n0.125,1.0\n*BOUNDARY\nBORE1,1,2\n{hub},2,3,0.0\n"
                f"{hub},1,1,{phi:.10e}\n*END STEP\n")
        f.write(f"*STEP, PERTURBATION\n*FREQUENCY\n{modes}\n*BOUNDARY, OP=NEW\nBORE1,1,2\n{hub},2,3,0.0\n"
                "*END STEP\n")


def frequencies(dat):
    """The eigenfrequencies [Hz] CalculiX printed (its time unit is the second here)."""
    out, on = [], False
    for line in open(dat):
        if "E I G E N V A L U E   O U T P U T" in line:
            on = True
            continue
        if on and "P A R T I C I P A T I O N" in line:
            break
        f = line.split()
        if on and len(f) == 5 and f[0].isdigit():
            out.append(float(f[3]))
    return out


def torques(dat, ids, arms):
    """(increment time, reaction torque about gear 2's centre [N mm]) from the .dat file."""
    arm = dict(zip(ids.tolist(), arms))
    out, cur = [], None
    for line in open(dat):
        m = re.match(r"\s*forces \(fx,fy,fz\) for set BORE2 and time\s+(\S+)", line)
        if m:
            cur = [float(m.group(1)), 0.0]
            out.append(cur)
            continue
        f = line.split()
        if cur is not None and len(f) == 4 and f[0].isdigit() and int(f[0]) in arm:
            x = arm[int(f[0])]
            cur[1] += x[0] * float(f[2]) - x[1] * float(f[1])
    return out


def rotation_at(incs, phi_max, torque):
    phi = np.array([0.0] + [t for t, _ in incs]) * phi_max
    m = np.array([0.0] + [q for _, q in incs])
    if len(m) < 3 or m[-1] < torque or np.any(np.diff(m) <= 0):
        raise SystemExit(f"the reaction torque {m[-1]:.1f} N mm over {len(m) - 1} increments does not rise past "
                         f"{torque:.1f}: raise phi_max or look at the .sta/.log files")
    k = min(max(int(np.searchsorted(m, torque)), 1), len(m) - 2)
    return float(np.polyval(np.polyfit(m[k - 1:k + 2], phi[k - 1:k + 2], 2), torque))


def run_ccx(name):
    """ccx on name.inp, its output kept in name.log; stops on a failed run."""
    run = subprocess.run(["ccx", "-i", name], capture_output=True, text=True)
    open(name + ".log", "w").write(run.stdout + run.stderr)
    if run.returncode != 0 or "*ERROR" in run.stdout:
        raise SystemExit(f"ccx failed on {name}.inp: see {name}.log")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--geardyn", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--positions", type=int, default=8)
    ap.add_argument("--penalty", type=float, default=5e7, help="contact pressure per overclosure [N/mm^3]")
    ap.add_argument("--only", default="", help="comma-separated positions (default: all)")
    ap.add_argument("--modal", action="store_true",
                    help="also the driver-held modes about each loaded state, against `geardyn validate frequencies`")
    a = ap.parse_args()
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.makedirs(a.out, exist_ok=True)
    sets = sum((["--set", s] for s in a.set), [])
    subprocess.run([a.geardyn, "mesh", *sets, "--out", f"{a.out}/mesh"], check=True, capture_output=True)
    subprocess.run([a.geardyn, "ltca", "--positions", str(a.positions), "--relief", "none", *sets,
                    "--out", f"{a.out}/ltca"], check=True, capture_output=True)
    gears = [read_vtk(f"{a.out}/mesh/mesh_gear{i}.vtk") for i in (1, 2)]
    if a.modal:
        # its exit status is the lumped model's 2 % target, not wanted here: the CSV is
        modes_csv = f"{a.out}/frequencies/mesh_modes.csv"
        if os.path.exists(modes_csv):
            os.remove(modes_csv)
        subprocess.run([a.geardyn, "validate", "frequencies", "--positions", str(a.positions), *sets,
                        "--out", f"{a.out}/frequencies"], capture_output=True)
        ours = [float(m["fe_modal_hz"]) for m in csv.DictReader(open(f"{a.out}/frequencies/mesh_modes.csv"))
                if m["hubs"] == "DriverHeld"]
    rows = list(csv.DictReader(open(f"{a.out}/ltca/ltca_none.csv")))
    only = {int(j) for j in a.only.split(",") if j}
    result = []
    for j, r in enumerate(rows):
        if only and j not in only:
            continue
        theta1 = math.radians(float(r["driver_rotation_deg"]))
        ste = float(r["ste_urad"]) * 1e-6
        phi_max = 1.12 * ste
        name = f"{a.out}/pos{j}"
        ids, arms = write_model(name + ".inp", gears, theta1, phi_max, a.penalty)
        t0 = time.time()
        run_ccx(name)
        wall = time.time() - t0
        phi = rotation_at(torques(name + ".dat", ids, arms), phi_max, TORQUE_NMM)
        k_ccx = TORQUE_NMM / (R_B2_MM ** 2 * phi) * 1e3   # N/mm -> N/m
        k_ltca = float(r["mesh_stiffness_n_per_m"])
        modal = {}
        if a.modal:
            write_modal_model(name + "_modal.inp", gears, theta1, phi, a.penalty)
            run_ccx(name + "_modal")
            hz = frequencies(name + "_modal.dat")
            modal = {"mesh_mode_geardyn_hz": f"{ours[j]:.2f}", "mesh_mode_calculix_hz": f"{hz[0]:.2f}",
                     "mesh_mode_rel_diff": f"{hz[0] / ours[j] - 1:+.5f}",
                     "calculix_next_modes_hz": " ".join(f"{h:.1f}" for h in hz[1:])}
        result.append({"position": j, "roll_angle_deg": r["roll_angle_deg"],
                       "ste_ltca_urad": f"{ste * 1e6:.4f}", "ste_calculix_urad": f"{phi * 1e6:.4f}",
                       "ste_rel_diff": f"{phi / ste - 1:+.5f}", "mesh_stiffness_ltca_n_per_m": f"{k_ltca:.6e}",
                       "mesh_stiffness_calculix_n_per_m": f"{k_ccx:.6e}", "calculix_wall_s": f"{wall:.1f}", **modal})
        print(result[-1], flush=True)
    with open(f"{a.out}/ltca_vs_calculix.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(result[0]))
        w.writeheader()
        w.writerows(result)
    kl = np.mean([float(x["mesh_stiffness_ltca_n_per_m"]) for x in result])
    kc = np.mean([float(x["mesh_stiffness_calculix_n_per_m"]) for x in result])
    print(f"mean mesh stiffness over {len(result)} positions: LTCA {kl:.5e}, CalculiX {kc:.5e} N/m ({kc / kl - 1:+.3%})")


if __name__ == "__main__":
    sys.exit(main())
