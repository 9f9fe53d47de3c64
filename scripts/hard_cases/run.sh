#!/bin/sh
# Reproduces the figures of doc/hard_cases.md, "Issue 12: what tipped the
# dropped cube" (run from the worktree root after `make build`).
#   1. mesh symmetry of boxMesh, before (the old splits, transcribed) and after;
#   2. reaction centre of a graded block pressed uniformly on a floor, with
#      and without the area weights;
#   3. a soft cube landing flat: booked friction and ledger error, spring
#      and regularised laws (the "before" of the regularised law needs the
#      explicit drag restored in pkg/contact/ContactLaw.hpp: cEff = c and
#      slipWork = -dt ft.vt).
set -e
export OMP_NUM_THREADS=1
PYTHONPATH=$PWD/build/python /usr/bin/python3.11 scripts/hard_cases/mesh_symmetry.py
./build/qdem_tests --gtest_filter='ContactWeights.ReactionCentreIsTheAreaCentre:RegularizedFriction.*' |
    grep -E 'tets/cell: weighted|spring:|OK|FAILED'
