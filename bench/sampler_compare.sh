#!/bin/bash
# Sobol' against independent (docs/converge.md, "Sobol' against independent"): equal-spp relMSE
# (omega render + omega compare, seeds 1-3) and equal-time relMSE (omega converge), on the Cornell
# box at 256² and veach-mis at 320x180 against Bitterli's Tungsten references in ../shared/scenes.
# Usage: bench/sampler_compare.sh [OUT_DIR]   (from the repository root, after scripts/build)
set -euo pipefail
ROOT=$(pwd)
OMEGA=$ROOT/build/client/omega
REFS=$ROOT/../shared/scenes
OUT=${1:-sampler-compare}
mkdir -p "$OUT" && cd "$OUT"
sed 's/film: {width: 1024, height: 1024,/film: {width: 256, height: 256,/' "$ROOT/scenes/cornell-box.yaml" > cb.yaml
sed 's/film: {width: 1280, height: 720,/film: {width: 320, height: 180,/' "$ROOT/scenes/veach-mis.yaml" > vm.yaml
echo "scene,sampler,spp,seed,relmse" > equal_spp.csv
for sc in cb vm; do
  ref=$REFS/cornell-box/TungstenRender.exr; [ $sc = vm ] && ref=$REFS/veach-mis/TungstenRender.exr
  for spp in ${SPPS:-16 64}; do
    for sampler in sobol independent; do
      for seed in 1 2 3; do
        "$OMEGA" render $sc.yaml --spp $spp --sampler $sampler --seed $seed --threads 2 -q -o $sc-$sampler.exr >/dev/null
        r=$("$OMEGA" compare $sc-$sampler.exr "$ref" | sed -n 's/.*relMSE \([^ ]*\).*/\1/p')
        echo "$sc,$sampler,$spp,$seed,$r" >> equal_spp.csv
      done
    done
  done
done
for sampler in sobol independent; do
  "$OMEGA" converge cb.yaml --reference $REFS/cornell-box/TungstenRender.exr --integrators path,bdpt --budget 16 \
      --runs 2 --threads 2 --sampler $sampler --out-dir conv-cb-$sampler > conv-cb-$sampler.log
  "$OMEGA" converge vm.yaml --reference $REFS/veach-mis/TungstenRender.exr --integrators path,bdpt --budget 16 \
      --runs 2 --threads 2 --sampler $sampler --out-dir conv-vm-$sampler > conv-vm-$sampler.log
done
echo "equal spp: $OUT/equal_spp.csv; equal time: $OUT/conv-*/{path,bdpt}.csv"
