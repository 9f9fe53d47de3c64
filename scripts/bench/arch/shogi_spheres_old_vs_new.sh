#!/bin/bash
# Old build against new build, interleaved (order alternating by round): the
# shogi scenes through the core (arch_shogi_cached.py: cached meshes, 200
# steps before any hit, and the 40 pieces with 39 asleep) and the YADE
# spheres coupling bench (bench_spheres.py, 5,000 spheres, 2 threads), the
# 1-minute load before each pair.  Summarise with shogi_spheres_summary.py.
#
#   scripts/bench/arch/shogi_spheres_old_vs_new.sh OLD/python NEW/python CACHE.npz ROUNDS OUTDIR > log.txt
#
# CACHE.npz: made once with arch_shogi_cached.py CACHE.npz 200 --make.
set -u
OLD=$1 NEW=$2 CACHE=$3 ROUNDS=$4 OUT=$5
cd "$(dirname "$0")/../../.."
mkdir -p "$OUT"
for r in $(seq 1 "$ROUNDS"); do
  if [ $((r % 2)) = 0 ]; then ORDER="new old"; else ORDER="old new"; fi
  for b in $ORDER; do
    if [ "$b" = old ]; then P=$OLD; else P=$NEW; fi
    echo "ROUND $r $b load $(cut -d' ' -f1 /proc/loadavg)"
    PYTHONPATH=$P OMP_WAIT_POLICY=passive timeout 600 /usr/bin/python3.11 scripts/bench/arch/arch_shogi_cached.py \
      "$CACHE" 200 2>&1 | tail -1 | sed "s/^/SHOGI $r $b /"
    PYTHONPATH=$P OMP_WAIT_POLICY=passive timeout 900 yade -j 2 -n -x scripts/bench/bench_spheres.py --spheres 5000 \
      --warm 1000 --steps 200 --out "$OUT/sph_${b}_$r" > "$OUT/sph_${b}_$r.log" 2>&1
    echo "SPHERES $r $b $(/usr/bin/python3.11 -c "import json,sys; d=json.load(open(sys.argv[1])); print(json.dumps({k: v for k, v in d.items() if not isinstance(v, (list, dict))}))" "$OUT/sph_${b}_$r/spheres.json" 2>&1)"
  done
done
