#!/usr/bin/env bash
# make bench: every benchmark, figures as JSON under out/bench/ (not asserted:
# the machines are shared and noisy, so compare ratios within one run).
set -euo pipefail
cd "$(dirname "$0")/../.."
mkdir -p out/bench
BUILD=${BUILD:-build}

echo "bench: QDEM element + integration on the 165,888-tet Figure 6 mesh"
"$BUILD"/bench_elements "${QDEM_BENCH_STEPS:-200}" 3 > out/bench/elements_qdem.json
cat out/bench/elements_qdem.json

echo "bench: YADE's own tetrahedral FEM on the same mesh (2 threads)"
yade -j 2 -n -x scripts/bench/yade_fem_bench.py --cubes 27 --out out/bench/yade_fem.json > out/bench/yade_fem.log 2>&1 \
  || echo "bench: YADE FEM run failed, see out/bench/yade_fem.log"

/usr/bin/python3.11 scripts/bench/merge_elements.py out/bench/elements_qdem.json out/bench/yade_fem.json \
  > out/bench/elements.json
cat out/bench/elements.json

echo "bench: 27 cubes, seed Figure 6 cases A/B/C and ours, by phase"
/usr/bin/python3.11 scripts/bench/bench_cubes27.py --steps "${QDEM_BENCH_CONTACT_STEPS:-20}" --out out/bench

echo "bench: shogi scenes (seed Figures 7-10), Table 1 material and time step"
/usr/bin/python3.11 scripts/bench/bench_shogi.py --steps "${QDEM_BENCH_SHOGI_STEPS:-200}" --out out/bench
echo "bench: the two rooks at 766, 100, 10 and 1x real size, explicit and implicit viscosity (key scales of shogi.json)"
OMP_NUM_THREADS=1 /usr/bin/python3.11 scripts/shogi/scales.py --steps "${QDEM_BENCH_SCALES_STEPS:-30}" --out out/bench

echo "bench: cost of each effect on, off and zero-valued"
(cd scripts/bench && /usr/bin/python3.11 bench_effects.py --steps "${QDEM_BENCH_EFFECT_STEPS:-20}" --out ../../out/bench)

echo "bench: 20,000 YADE spheres around one QDEM block: coupling cost, near and far"
yade -j 2 -n -x scripts/bench/bench_spheres.py --steps "${QDEM_BENCH_SPHERE_STEPS:-500}" --out out/bench \
  > out/bench/spheres.log 2>&1 || echo "bench: sphere coupling run failed, see out/bench/spheres.log"
grep "^bench spheres" out/bench/spheres.log || true

echo "bench: accuracy against cost, short form (make accuracy for the full study and doc/accuracy.md)"
OMP_NUM_THREADS=1 /usr/bin/python3.11 scripts/accuracy/run_accuracy.py --short --out out/accuracy
