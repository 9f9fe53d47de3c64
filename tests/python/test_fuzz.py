"""Random-scene fuzzer (doc/validation.md, "Random-scene fuzzer").

Hypothesis draws scenes (fuzzscene.sceneSpecs: meshes, materials, placements,
speeds, contact radii, walls, facets, boxes, YADE spheres and clumps, 1-2
threads, O.dt a fraction 0.3-0.95 of the stable step) and fuzzscene.runScene
checks the invariants after every step.  A failure is shrunk by Hypothesis
and printed as a spec: paste it into test_fuzz_regressions.py.

Budget: ``make test`` runs QDEM_FUZZ_EXAMPLES examples (default 25, about 1.5
minutes on two shared cores) derandomized, the same every run; ``make fuzz``
runs random examples for QDEM_FUZZ_SECONDS (default 600) or
QDEM_FUZZ_EXAMPLES, its Hypothesis database under out/fuzz/."""
import os
import time

from hypothesis import HealthCheck, given, settings

import fuzzscene

_EXAMPLES = int(os.environ.get("QDEM_FUZZ_EXAMPLES", "0") or 0)
_SECONDS = float(os.environ.get("QDEM_FUZZ_SECONDS", "0") or 0)
_LONG = bool(_SECONDS) or bool(os.environ.get("QDEM_FUZZ_LONG"))

if _LONG:
    from hypothesis.database import DirectoryBasedExampleDatabase
    _settings = settings(max_examples=_EXAMPLES or 10 ** 6, deadline=None, derandomize=False,
                         database=DirectoryBasedExampleDatabase(os.path.join("out", "fuzz", "hypothesis")),
                         suppress_health_check=list(HealthCheck), print_blob=True)
else:
    _settings = settings(max_examples=_EXAMPLES or 25, deadline=None, derandomize=True, database=None,
                         suppress_health_check=list(HealthCheck), print_blob=True)

_start = [None]
_log = []


@_settings
@given(fuzzscene.sceneSpecs())
def test_random_scenes_keep_the_invariants(spec):
    if _start[0] is None:
        _start[0] = time.time()
    if _SECONDS and time.time() - _start[0] > _SECONDS:
        return  # budget spent: the remaining examples pass at once
    out = fuzzscene.runScene(spec)
    _log.append(out)
    if os.environ.get("QDEM_FUZZ_VERBOSE"):
        print(out, flush=True)
    known = fuzzscene.knownDefect(out)
    if known and not os.environ.get("QDEM_FUZZ_STRICT"):
        print("\nfuzz: known defect (%s): %s\nspec = %r" % (known, out.failure, spec), flush=True)
        return
    fuzzscene.check(out)
