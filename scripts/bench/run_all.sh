#!/usr/bin/env bash
# make bench: every benchmark, figures as JSON under out/bench/ (not asserted:
# the machines are shared and noisy).  Each benchmark interleaves its variants
# over rounds, records the load with each run and flags busy runs, which stay
# out of min / median / max (doc/performance.md, "How the figures are
# measured"); perf_tables.py prints the doc's tables from the JSON.  About
# 20-30 minutes on 2 idle cores.
#
# Fails loudly: every benchmark runs even when one before it failed, and the
# run ends non-zero naming each benchmark that failed and each JSON that is
# missing or lacks a key the docs read (scripts/bench/bench_schema.py).
set -uo pipefail
cd "$(dirname "$0")/../.."
mkdir -p out/bench
BUILD=${BUILD:-build}
failed=()

# step NAME COMMAND...: runs COMMAND (a function below) with errexit on; a
# failure is recorded, reported at the end, and the next benchmark runs.
step() {
  local name=$1
  shift
  echo "bench: $name"
  (set -e; "$@")
  local rc=$?
  if [ "$rc" -ne 0 ]; then
    failed+=("$name (exit $rc)")
    echo "bench: FAILED: $name (exit $rc; logs under out/bench/)" >&2
  fi
}

ceilings() {
  OMP_WAIT_POLICY=passive "$BUILD"/roofline > out/bench/roofline.json 2> out/bench/roofline.log
  /usr/bin/python3.11 scripts/bench/kernel_ops.py --build "$BUILD" > out/bench/kernel_ops.json
  /usr/bin/python3.11 scripts/bench/perf_tables.py roofline out/bench/roofline.json
}

ompSync() {
  /usr/bin/python3.11 scripts/bench/omp_sync.py --build "$BUILD" --out out/bench/omp_sync.json 2> out/bench/omp_sync.log
}

elements() {
  OMP_WAIT_POLICY=passive "$BUILD"/bench_elements --steps "${QDEM_BENCH_STEPS:-200}" --cubes 3,6 \
    > out/bench/elements_qdem.json 2> out/bench/elements_qdem.log
  /usr/bin/python3.11 scripts/bench/perf_tables.py elements out/bench/elements_qdem.json
  /usr/bin/python3.11 scripts/bench/perf_tables.py roofline out/bench/roofline.json out/bench/elements_qdem.json \
    out/bench/kernel_ops.json | tail -n 20
}

elementParts() {
  "$BUILD"/element_parts --rounds 7 --passes 20 > out/bench/element_parts.json 2> out/bench/element_parts.log
  grep -A1 '"law"' out/bench/element_parts.json | grep -v '^--' || true
  grep '"derived_cpu_median"' out/bench/element_parts.json || true
}

yadeFem() {
  yade -j 2 -n -x scripts/bench/yade_fem_bench.py --cubes 27 --out out/bench/yade_fem.json > out/bench/yade_fem.log 2>&1

  /usr/bin/python3.11 scripts/bench/merge_elements.py out/bench/elements_qdem.json out/bench/yade_fem.json \
    > out/bench/elements.json
  grep -A4 '"qdem_ns_per_tet_step"\|"yade_fem_over_qdem"' out/bench/elements.json || true
}

cubes27() {
  OMP_WAIT_POLICY=passive /usr/bin/python3.11 scripts/bench/bench_cubes27.py --steps "${QDEM_BENCH_CONTACT_STEPS:-600}" --out out/bench
  /usr/bin/python3.11 scripts/bench/perf_tables.py cubes27 out/bench/cubes27.json
}

cubes27DefaultPolicy() {
  env -u OMP_WAIT_POLICY /usr/bin/python3.11 scripts/bench/bench_cubes27.py --steps "${QDEM_BENCH_CONTACT_STEPS:-600}" \
    --abc-steps 0 --out out/bench/cubes27_default_policy > out/bench/cubes27_default_policy.log
  tail -n 20 out/bench/cubes27_default_policy.log
  /usr/bin/python3.11 scripts/bench/contacts/sync_points.py --threads 2 | tee out/bench/sync_points.txt
}

shogi() {
  OMP_WAIT_POLICY=passive yade -n -j 2 -x scripts/bench/bench_shogi.py --rounds "${QDEM_BENCH_SHOGI_ROUNDS:-5}" \
    --out out/bench > out/bench/shogi.log 2>&1
  /usr/bin/python3.11 scripts/bench/perf_tables.py shogi out/bench/shogi.json || true
}

shogiScales() {
  OMP_NUM_THREADS=1 /usr/bin/python3.11 scripts/shogi/scales.py --steps "${QDEM_BENCH_SCALES_STEPS:-30}" --out out/bench
}

timeToSolution() {
  OMP_WAIT_POLICY=passive /usr/bin/python3.11 scripts/bench/bench_time_to_solution.py \
    --steps "${QDEM_BENCH_TTS_STEPS:-200}" --rounds "${QDEM_BENCH_TTS_ROUNDS:-3}" --out out/bench \
    > out/bench/time_to_solution.log 2>&1
  /usr/bin/python3.11 scripts/bench/perf_tables.py timeToSolution out/bench/time_to_solution.json
}

effects() {
  OMP_WAIT_POLICY=passive /usr/bin/python3.11 scripts/bench/bench_effects.py --steps "${QDEM_BENCH_EFFECT_STEPS:-60}" \
    --rounds "${QDEM_BENCH_EFFECT_ROUNDS:-5}" --out out/bench > out/bench/effects.log
  /usr/bin/python3.11 scripts/bench/perf_tables.py effects out/bench/effects.json
}

spheres() {
  yade -j 2 -n -x scripts/bench/bench_spheres.py --steps "${QDEM_BENCH_SPHERE_STEPS:-500}" --out out/bench \
    > out/bench/spheres.log 2>&1
  grep "^bench spheres" out/bench/spheres.log || true
}

accuracyShort() {
  OMP_NUM_THREADS=1 /usr/bin/python3.11 scripts/accuracy/run_accuracy.py --short --out out/accuracy
}

step "the machine's ceilings (FMA peak, triad bandwidth from DRAM and from L3), 1 and 2 threads" ceilings
step "the price of an OpenMP fork, barrier and join, with and without OMP_WAIT_POLICY=passive" ompSync
step "QDEM element + integration and whole step, 165,888 and 1,327,104 tets (Hilbert-ordered as addPiece)" elements
step "the element kernel taken apart (gather, arithmetic, scatter; whole mesh and in L1), 1 thread" elementParts
step "YADE's own tetrahedral FEM on the same mesh (2 threads)" yadeFem
step "27 cubes thrown (seed Figure 6 scene moving): ours amortised over its Verlet rebuilds, cases A/B/C beside it" cubes27
step "the same without OMP_WAIT_POLICY (libgomp's default, what a YADE run gets), and its synchronisations per step" cubes27DefaultPolicy
step "shogi scenes (seed Figures 7-10) through their first hits, QdemEngine in a YADE script" shogi
step "the two rooks at 766, 100, 10 and 1x real size, explicit and implicit viscosity (key scales of shogi.json)" shogiScales
step "time to solution: two rooks, king and pawns, the forty-piece line from its front; 766x and real size; each lever (viscous preconditioner jacobi / cholesky) interleaved" timeToSolution
step "cost of each effect on, off and zero-valued" effects
step "20,000 YADE spheres around one QDEM block: coupling cost, near and far" spheres
step "accuracy against cost, short form (make accuracy for the full study and doc/accuracy.md)" accuracyShort

echo "bench: the JSON behind the docs' figures"
/usr/bin/python3.11 scripts/bench/bench_schema.py out/bench --expect || failed+=("JSON check (above)")

if [ "${#failed[@]}" -ne 0 ]; then
  echo "bench: ${#failed[@]} failed:" >&2
  for f in "${failed[@]}"; do echo "  - $f" >&2; done
  exit 1
fi
echo "bench: all benchmarks ran and every JSON the docs read is complete"
