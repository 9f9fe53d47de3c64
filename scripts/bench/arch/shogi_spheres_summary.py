"""Summary of shogi_spheres_old_vs_new.sh's log: per scene, both builds' medians and minima
and the paired per-round ratio new / old (median, range); optionally the JSON.

    /usr/bin/python3.11 scripts/bench/arch/shogi_spheres_summary.py LOG.txt [OUT.json]
"""
import json, re, statistics as st, sys
rows = {}
loads = []
for line in open(sys.argv[1]):
    if line.startswith('ROUND'):
        loads.append(float(line.split()[-1]))
    m = re.match(r'(SHOGI|SPHERES) (\d+) (old|new) (\{.*)', line)
    if not m: continue
    kind, r, b, js = m.group(1), int(m.group(2)), m.group(3), json.loads(m.group(4))
    if kind == 'SHOGI':
        for sc, v in js['scenes'].items(): rows.setdefault((sc, b), {})[r] = v['ms_per_step']
        rows.setdefault(('forty 39 asleep', b), {})[r] = js['sleeping']['ms_per_step_39_asleep']
    else:
        rows.setdefault(('spheres us/listed sphere', b), {})[r] = js['per_listed_sphere_us']
out = {}
for key in sorted(set(k for k, _ in rows)):
    o, n = rows[(key, 'old')], rows[(key, 'new')]
    ratios = [n[r] / o[r] for r in o if r in n]
    out[key] = dict(old_median=st.median(o.values()), old_min=min(o.values()), new_median=st.median(n.values()),
                    new_min=min(n.values()), ratio_median=st.median(ratios), ratio_min=min(ratios), ratio_max=max(ratios), rounds=len(ratios))
    print('%-26s old %.3f (%.3f)  new %.3f (%.3f)  paired new/old median %.3f (%.2f-%.2f) n=%d' % (key, out[key]['old_median'], out[key]['old_min'], out[key]['new_median'], out[key]['new_min'], out[key]['ratio_median'], out[key]['ratio_min'], out[key]['ratio_max'], len(ratios)))
print('loads', min(loads), max(loads))
if len(sys.argv) > 2:
    json.dump(dict(log=sys.argv[1], loads_before=loads, rows={'%s/%s' % k: v for k, v in rows.items()}, summary={k: v for k, v in out.items()}), open(sys.argv[2], 'w'), indent=1)
