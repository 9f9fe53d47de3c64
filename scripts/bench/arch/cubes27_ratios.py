"""Old against new from an arch_old_vs_new_run.py JSON of the 27-cube bench: per
thread count, case and phase, min and median of each build and the median of the
paired per-round ratios new/old.

    python3 scripts/bench/arch/cubes27_ratios.py bench/logs/arch_cubes27_quiet_after.json [--json OUT.json]

With --json the figures printed are also written to OUT.json (threads ->
case -> phase), with the runs' load (kept as
bench/logs/arch_cubes27_quiet_after_ratios.json for doc/architecture.md).
"""
import json, statistics as st, sys
d=json.load(open(sys.argv[1]))
runs=[r for r in d['runs'] if 'result' in r]
rounds=sorted(set(r['round'] for r in runs))
out={"source": sys.argv[1], "rounds": len(rounds), "threads": {},
     "load1": {"min": min(float(r['loadavg_before'][0]) for r in runs),
               "max": max(float(r['loadavg_before'][0]) for r in runs)},
     "others_cores_max": max(r['others_cores_during_run'] for r in runs)}
for th in ('1','2'):
  for case in ('ours','C'):
    for key in ('step_ms','pointPolygon','broadPhase','edgeEdge','elements','integrate','obstacles'):
      old=[r['result']['threads'][th][case][key] for r in runs if r['build']=='old']
      new=[r['result']['threads'][th][case][key] for r in runs if r['build']=='new']
      ratios=[]
      for rr in rounds:
        o=[r['result']['threads'][th][case][key] for r in runs if r['build']=='old' and r['round']==rr]
        n=[r['result']['threads'][th][case][key] for r in runs if r['build']=='new' and r['round']==rr]
        if o and n and o[0]>0: ratios.append(n[0]/o[0])
      if key=='step_ms' or case=='ours':
        out["threads"].setdefault(th, {}).setdefault(case, {})[key] = {
          "old_min": min(old), "old_median": st.median(old), "new_min": min(new), "new_median": st.median(new),
          "paired_ratio_median": st.median(ratios), "ratio_of_minima": min(new)/min(old), "n": len(ratios)}
        print("%s thr %-4s %-12s old min %.3f med %.3f | new min %.3f med %.3f | new/old med %.3f min-ratio %.3f (n=%d)"%(th,case,key,min(old),st.median(old),min(new),st.median(new),st.median(ratios),min(new)/min(old),len(ratios)))
if "--json" in sys.argv:
  json.dump(out, open(sys.argv[sys.argv.index("--json")+1], "w"), indent=1)
