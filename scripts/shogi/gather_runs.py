"""Keeps the results of domino.py runs (each run's hits.json) in one JSON
under bench/logs/, which doc/shogi.md prints its figures from:

    /usr/bin/python3.11 scripts/shogi/gather_runs.py bench/logs/shogi_soft.json \\
        out/shogi/two_rooks_mu0.1_soft out/shogi/two_rooks_mu0.5_soft out/shogi/king_pawns_mu0.1_soft

Written as {"runs": {<run directory name>: <its hits.json>}}."""
import json
import os
import sys


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    runs = {}
    for d in sys.argv[2:]:
        path = os.path.join(d, "hits.json")
        if not os.path.isfile(path):
            sys.exit("gather_runs.py: %s has no hits.json (run scripts/shogi/domino.py first)" % d)
        with open(path) as f:
            runs[os.path.basename(os.path.normpath(d))] = json.load(f)
    with open(sys.argv[1], "w") as f:
        json.dump({"source": "scripts/shogi/domino.py runs, gathered by scripts/shogi/gather_runs.py",
                   "runs": runs}, f, indent=1)
    print("written", sys.argv[1])


if __name__ == "__main__":
    main()
