#!/usr/bin/env bash
# LTCA validation studies on the embedded paper36 case (issue 3). Re-run:
#   bash validation/ltca_studies.sh            (about 2 minutes on 2 cores)
# Prints one line per run; outputs go to out/validation-ltca/.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
bin=target/release/geardyn
base=out/validation-ltca
mkdir -p "$base"
"$bin" case > "$base/paper36.toml"

value() { grep -m1 "\"$2\"" "$1/summary.json" | sed -E 's/.*: ([-0-9.e+]+),?/\1/'; }

run() { # name, sed expression applied to the case, extra args
  local name=$1 expr=$2; shift 2
  sed -E "$expr" "$base/paper36.toml" > "$base/$name.toml"
  "$bin" ltca "$base/$name.toml" --relief none --out "$base/$name" "$@" > "$base/$name.log" 2>&1
  printf '%-22s k_mean %.5e  k_min %.5e  k_max %.5e  STE_mean %.4f um  STE_pp %.4f um  PE %.4e  ISO %.4e  elements %s  wall %.1f s\n' \
    "$name" "$(value "$base/$name" mesh_stiffness_mean_n_per_m)" "$(value "$base/$name" mesh_stiffness_min_n_per_m)" \
    "$(value "$base/$name" mesh_stiffness_max_n_per_m)" "$(value "$base/$name" ste_mean_um)" \
    "$(value "$base/$name" ste_peak_to_peak_um)" "$(value "$base/$name" potential_energy_mean_n_per_m)" \
    "$(value "$base/$name" iso_c_gamma_n_per_m)" "$(value "$base/$name" elements)" "$(value "$base/$name" wall_s)"
}

echo "# mesh refinement (plane strain, bore 20 mm)"
for h in 0.4 0.2 0.1 0.05; do
  run "fine_$h" "s/^fine_element_mm = [0-9.]+/fine_element_mm = $h/"
done
run "fine_0.1_coarse_0.75" "s/^fine_element_mm = [0-9.]+/fine_element_mm = 0.1/; s/^coarse_element_mm = [0-9.]+/coarse_element_mm = 0.75/"
echo "# plane state"
run "plane_stress" "s/^plane = \"strain\"/plane = \"stress\"/"
echo "# hub definition: bore radius"
for r in 10.0 30.0 40.0; do
  run "bore_$r" "s/^bore_radius_mm = [0-9.]+/bore_radius_mm = $r/"
done
echo "# load"
for t in 50 300; do
  run "torque_$t" "s/^x/x/" --torque-nm "$t"
done
