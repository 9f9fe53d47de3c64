#!/usr/bin/env bash
# make bench: every benchmark, figures as JSON under out/bench/ (not asserted:
# the machines are shared and noisy).  Each benchmark interleaves its variants
# over rounds, records the load with each run and flags busy runs, which stay
# out of min / median / max (doc/performance.md, "How the figures are
# measured"); perf_tables.py prints the doc's tables from the JSON.  About
# 20-30 minutes on 2 idle cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
mkdir -p out/bench
BUILD=${BUILD:-build}

echo "bench: the machine's ceilings (FMA peak, triad bandwidth from DRAM and from L3), 1 and 2 threads"
OMP_WAIT_POLICY=passive "$BUILD"/roofline > out/bench/roofline.json 2> out/bench/roofline.log
/usr/bin/python3.11 scripts/bench/kernel_ops.py --build "$BUILD" > out/bench/kernel_ops.json
/usr/bin/python3.11 scripts/bench/perf_tables.py roofline out/bench/roofline.json

echo "bench: the price of an OpenMP fork, barrier and join, with and without OMP_WAIT_POLICY=passive"
/usr/bin/python3.11 scripts/bench/omp_sync.py --build "$BUILD" --out out/bench/omp_sync.json 2> out/bench/omp_sync.log

echo "bench: QDEM element + integration and whole step, 165,888 and 1,327,104 tets (Hilbert-ordered as addPiece)"
OMP_WAIT_POLICY=passive "$BUILD"/bench_elements --steps "${QDEM_BENCH_STEPS:-200}" --cubes 3,6 \
  > out/bench/elements_qdem.json 2> out/bench/elements_qdem.log
/usr/bin/python3.11 scripts/bench/perf_tables.py elements out/bench/elements_qdem.json
/usr/bin/python3.11 scripts/bench/perf_tables.py roofline out/bench/roofline.json out/bench/elements_qdem.json \
  out/bench/kernel_ops.json | tail -n 20

echo "bench: the element kernel taken apart (gather, arithmetic, scatter; whole mesh and in L1), 1 thread"
"$BUILD"/element_parts --rounds 7 --passes 20 > out/bench/element_parts.json 2> out/bench/element_parts.log
grep -A1 '"law"' out/bench/element_parts.json | grep -v '^--' || true
grep '"derived_cpu_median"' out/bench/element_parts.json || true

echo "bench: YADE's own tetrahedral FEM on the same mesh (2 threads)"
yade -j 2 -n -x scripts/bench/yade_fem_bench.py --cubes 27 --out out/bench/yade_fem.json > out/bench/yade_fem.log 2>&1 \
  || echo "bench: YADE FEM run failed, see out/bench/yade_fem.log"

/usr/bin/python3.11 scripts/bench/merge_elements.py out/bench/elements_qdem.json out/bench/yade_fem.json \
  > out/bench/elements.json
grep -A4 '"qdem_ns_per_tet_step"\|"yade_fem_over_qdem"' out/bench/elements.json || true

echo "bench: 27 cubes thrown (seed Figure 6 scene moving): ours amortised over its Verlet rebuilds, cases A/B/C beside it"
OMP_WAIT_POLICY=passive /usr/bin/python3.11 scripts/bench/bench_cubes27.py --steps "${QDEM_BENCH_CONTACT_STEPS:-600}" --out out/bench
/usr/bin/python3.11 scripts/bench/perf_tables.py cubes27 out/bench/cubes27.json
echo "bench: the same without OMP_WAIT_POLICY (libgomp's default, what a YADE run gets), and its synchronisations per step"
env -u OMP_WAIT_POLICY /usr/bin/python3.11 scripts/bench/bench_cubes27.py --steps "${QDEM_BENCH_CONTACT_STEPS:-600}" \
  --abc-steps 0 --out out/bench/cubes27_default_policy > out/bench/cubes27_default_policy.log
tail -n 20 out/bench/cubes27_default_policy.log
/usr/bin/python3.11 scripts/bench/contacts/sync_points.py --threads 2 | tee out/bench/sync_points.txt

echo "bench: shogi scenes (seed Figures 7-10) through their first hits, QdemEngine in a YADE script"
OMP_WAIT_POLICY=passive yade -n -j 2 -x scripts/bench/bench_shogi.py --rounds "${QDEM_BENCH_SHOGI_ROUNDS:-5}" \
  --out out/bench > out/bench/shogi.log 2>&1 || echo "bench: shogi run failed, see out/bench/shogi.log"
/usr/bin/python3.11 scripts/bench/perf_tables.py shogi out/bench/shogi.json || true
echo "bench: the two rooks at 766, 100, 10 and 1x real size, explicit and implicit viscosity (key scales of shogi.json)"
OMP_NUM_THREADS=1 /usr/bin/python3.11 scripts/shogi/scales.py --steps "${QDEM_BENCH_SCALES_STEPS:-30}" --out out/bench

echo "bench: cost of each effect on, off and zero-valued"
OMP_WAIT_POLICY=passive /usr/bin/python3.11 scripts/bench/bench_effects.py --steps "${QDEM_BENCH_EFFECT_STEPS:-60}" \
  --rounds "${QDEM_BENCH_EFFECT_ROUNDS:-5}" --out out/bench > out/bench/effects.log
/usr/bin/python3.11 scripts/bench/perf_tables.py effects out/bench/effects.json

echo "bench: 20,000 YADE spheres around one QDEM block: coupling cost, near and far"
yade -j 2 -n -x scripts/bench/bench_spheres.py --steps "${QDEM_BENCH_SPHERE_STEPS:-500}" --out out/bench \
  > out/bench/spheres.log 2>&1 || echo "bench: sphere coupling run failed, see out/bench/spheres.log"
grep "^bench spheres" out/bench/spheres.log || true

echo "bench: accuracy against cost, short form (make accuracy for the full study and doc/accuracy.md)"
OMP_NUM_THREADS=1 /usr/bin/python3.11 scripts/accuracy/run_accuracy.py --short --out out/accuracy
