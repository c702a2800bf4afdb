#!/bin/bash
# Before/after speed of two omega binaries to about 1%, on a small noisy machine.
#
# Usage: bench/ab_cores.sh OLD_OMEGA NEW_OMEGA SCENE [INTEGRATOR] [SPP] [REPS]
#        (defaults: path, 32 spp, 3 repetitions; run OLD against OLD first to see the noise floor)
#
# Why not alternate runs: on the 2-core VMs this project builds on, the machine's speed drifts by
# 10% between runs a minute apart, and the two cores differ by about 20% (core 0 also serves
# interrupts). Alternating whole renders, or bench/throughput's ratios to Embree, then spread over
# +-5%, which hides any change of a few percent. Here both binaries render at the same time, one
# thread each, pinned to cores 0 and 1, and then again with the cores swapped: both see the same
# drift, and the geometric mean of the two placements cancels the cores' difference.
# Measured with one binary against itself: 0.988-1.001 (3 repetitions, Cornell box, path).
#
# Prints, per repetition, the samples/s of each binary in each placement and NEW/OLD; then the
# median ratio and its range. Above 1 means NEW is faster.
set -euo pipefail
if [ $# -lt 3 ]; then
  sed -n '2,5p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
OLD=$(realpath "$1"); NEW=$(realpath "$2"); SCENE=$(realpath "$3")
INTEGRATOR=${4:-path}; SPP=${5:-32}; REPS=${6:-3}
if [ "$(nproc)" -lt 2 ]; then echo "ab_cores: needs 2 cores, this machine has $(nproc)" >&2; exit 2; fi
command -v taskset >/dev/null || { echo "ab_cores: needs taskset (util-linux)" >&2; exit 2; }
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

# samples/s of a whole render.
# Read from the --report CSV's last pass (6 digits): the summary line rounds to 3, which made
# every ratio a multiple of about 1%.
rate() {
  tail -1 "$1" | awk -F, '{ print $4 }'
}
# One placement: OLD on core $1, NEW on core $2, at the same time.
pair() {
  taskset -c "$1" "$OLD" render "$SCENE" --spp "$SPP" --threads 1 --integrator "$INTEGRATOR" -o "$WORK/old.exr" --report "$WORK/old.csv" > "$WORK/old.txt" 2>&1 &
  local a=$!
  taskset -c "$2" "$NEW" render "$SCENE" --spp "$SPP" --threads 1 --integrator "$INTEGRATOR" -o "$WORK/new.exr" --report "$WORK/new.csv" > "$WORK/new.txt" 2>&1 &
  local b=$!
  wait $a || { echo "ab_cores: OLD failed:"; cat "$WORK/old.txt"; exit 1; } >&2
  wait $b || { echo "ab_cores: NEW failed:"; cat "$WORK/new.txt"; exit 1; } >&2
  echo "$(rate "$WORK/old.csv") $(rate "$WORK/new.csv")"
}

echo "scene $SCENE  integrator $INTEGRATOR  $SPP spp  1 thread each, cores swapped"
printf '%5s %16s %16s %16s %16s %10s\n' rep "old@0 samples/s" "new@1 samples/s" "old@1 samples/s" "new@0 samples/s" "new/old"
ratios=()
for r in $(seq "$REPS"); do
  read -r a1 b1 <<< "$(pair 0 1)"
  read -r a2 b2 <<< "$(pair 1 0)"
  q=$(awk -v a1="$a1" -v b1="$b1" -v a2="$a2" -v b2="$b2" 'BEGIN { printf "%.4f", sqrt((b1 / a1) * (b2 / a2)) }')
  ratios+=("$q")
  printf '%5d %16.0f %16.0f %16.0f %16.0f %10.3f\n' "$r" "$a1" "$b1" "$a2" "$b2" "$q"
done
printf '%s\n' "${ratios[@]}" | sort -g | awk '{v[NR] = $1} END {
  med = NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
  printf "new/old: median %.3f, range %.3f-%.3f over %d repetitions\n", med, v[1], v[NR], NR }'
