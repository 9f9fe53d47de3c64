#!/bin/sh
# Reproduces the figures of doc/hard_cases.md, "Issue 12: what tipped the
# dropped cube" (run from the worktree root after `make build`).
#   1. mesh symmetry of boxMesh, before (the old splits, transcribed) and after;
#   2. reaction centre of a graded block pressed uniformly on a floor, with
#      and without the area weights;
#   3. a soft cube landing flat: booked friction and ledger error, spring
#      and regularised laws (the "before" rows of the regularised law need
#      the old law restored in pkg/contact/ContactLaw.hpp: explicit,
#      F = min(mu Fn, c |vt|), slipWork = -dt Ft.vt; drag alone implicit,
#      vFree = vt);
#   4. the README's drop, 6 and 12 tets per cell (about a minute each).
set -e
export OMP_NUM_THREADS=1
PYTHONPATH=$PWD/build/python /usr/bin/python3.11 scripts/hard_cases/mesh_symmetry.py
./build/qdem_tests --gtest_filter='ContactWeights.ReactionCentreIsTheAreaCentre:RegularizedFriction.*' |
    grep -E 'tets/cell: weighted|spring:|OK|FAILED'
cd /tmp
for k in 6 12; do
    PYTHONPATH=$OLDPWD/build/python yade -n -x $OLDPWD/scripts/hard_cases/readme_drop.py $k 10000 | tail -1
done
