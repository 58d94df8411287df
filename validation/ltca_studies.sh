#!/usr/bin/env bash
# LTCA validation studies on the embedded paper36 case (issue 3). Re-run:
#   bash validation/ltca_studies.sh            (about 2 minutes on 2 cores)
# Prints one line per run; outputs go to out/validation-ltca/<run>/ (each with its effective
# case.toml). Every variation is a `--set` of the embedded case.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
bin=target/release/geardyn
base=out/validation-ltca
mkdir -p "$base"

# The headline numbers of a run, read from its summary.json with a JSON parser.
line() {
  python3 - "$1" "$2/summary.json" <<'PY'
import json, sys
name, path = sys.argv[1], sys.argv[2]
s = json.load(open(path))
print(f"{name:<22} k_mean {s['mesh_stiffness_mean_n_per_m']:.5e}  k_min {s['mesh_stiffness_min_n_per_m']:.5e}"
      f"  k_max {s['mesh_stiffness_max_n_per_m']:.5e}  STE_mean {s['ste_mean_um']:.4f} um"
      f"  STE_pp {s['ste_peak_to_peak_um']:.4f} um  PE {s['potential_energy_mean_n_per_m']:.4e}"
      f"  ISO {s['iso_c_gamma_n_per_m']:.4e}  elements {s['elements']}  wall {s['wall_s']:.1f} s")
PY
}

run() { # name, then ltca arguments (--set KEY=VALUE, --torque-nm T)
  local name=$1; shift
  "$bin" ltca --relief none --out "$base/$name" "$@" > "$base/$name.log" 2>&1
  line "$name" "$base/$name"
}

echo "# mesh refinement (plane strain, bore 20 mm)"
for h in 0.4 0.2 0.1 0.05; do
  run "fine_$h" --set "mesh.fine_element_mm=$h"
done
run "fine_0.1_coarse_0.75" --set mesh.fine_element_mm=0.1 --set mesh.coarse_element_mm=0.75
echo "# plane state"
run "plane_stress" --set fe.plane=stress
echo "# hub definition: bore radius"
for r in 10.0 30.0 40.0; do
  run "bore_$r" --set "gear1.bore_radius_mm=$r" --set "gear2.bore_radius_mm=$r"
done
echo "# load"
for t in 50 300; do
  run "torque_$t" --torque-nm "$t"
done
