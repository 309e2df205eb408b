#!/usr/bin/env bash
# Issue 17: where each renderer's frame goes. For every workload of docs/bench/vs_base.py,
# `perf record` a turntable of warm frames and write OUT/NAME.txt (the functions that take
# at least 1 % of the samples, self time) and, when inferno is installed
# (`cargo install inferno`), OUT/NAME.svg (a flame graph of the whole process).
#
#   docs/bench/profile.sh VOLUX DATA OUT [FRAMES]
#
# VOLUX: a build with `cargo build --profile profiling` (release with debug line info,
# target/profiling/volux); DATA: the directory
# prepared by `python3 docs/bench/vs_base.py --data DATA --setup`.
set -euo pipefail
volux=$1 data=$2 out=$3 frames=${4:-6}
shared="$(cd "$(dirname "$0")/../../../shared" && pwd)"
mkdir -p "$out"
cam=(--camera "$data/camera.json" --size 512x512)
tf=(--tf "$data/tf-37-knots.json")
pt=(--method pt --color psi --sort centroid)
declare -A runs=(
  [grid-ml256]="$data/ml_256.f32.raw ${tf[*]} ${cam[*]} --step 0.5"
  [grid-ct]="$shared/data/invesalius_cranium_ct/cranium_256x256x108_int16.raw.gz --camera $data/camera-ct.json --size 512x512"
  [pt-200k]="$data/tets_200k.vtk ${pt[*]} ${tf[*]} ${cam[*]}"
  [pt-200k-dense]="$data/tets_200k.vtk ${pt[*]} --tf $data/tf-dense.json ${cam[*]}"
  [tetray-200k]="$data/tets_200k.vtk --method raycast --integrator exact ${tf[*]} ${cam[*]}"
)
for name in "${!runs[@]}"; do
  # shellcheck disable=SC2086
  perf record -q -F 499 --call-graph dwarf,16384 -o "$out/$name.data" -- \
    "$volux" render ${runs[$name]} --orbit "$frames:3" --no-write >/dev/null 2>&1
  perf report -i "$out/$name.data" --no-children --percent-limit 1 --stdio 2>/dev/null |
    grep -E '^ +[0-9.]+%' | sed -E 's/ +/ /g' >"$out/$name.txt" || true
  if command -v inferno-collapse-perf >/dev/null; then
    perf script -i "$out/$name.data" 2>/dev/null | inferno-collapse-perf |
      inferno-flamegraph --minwidth 8 --title "volux render $name ($frames frames)" >"$out/$name.svg"
  fi
  rm -f "$out/$name.data"
  echo "$name: $out/$name.txt" >&2
done
