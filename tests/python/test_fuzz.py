"""Random-scene fuzzer (doc/validation.md, "Random-scene fuzzer").

Hypothesis draws scenes (fuzzscene.sceneSpecs: meshes, materials, placements,
speeds, contact radii, walls, facets, boxes, YADE spheres and clumps, 1-2
threads, O.dt a fraction 0.3-0.95 of the stable step) and fuzzscene.runScene
checks the invariants after every step.  A failure is shrunk by Hypothesis
and printed as a spec: paste it into test_fuzz_regressions.py.

Budget: ``make test`` runs QDEM_FUZZ_EXAMPLES examples (default 20, about 1.3
minutes on two shared cores) derandomized, the same every run; ``make fuzz``
runs batches of QDEM_FUZZ_EXAMPLES fresh random examples (QDEM_FUZZ_LONG=1)
for QDEM_FUZZ_SECONDS, its Hypothesis database under out/fuzz/.  A failure
matching fuzzscene.KNOWN_DEFECTS is printed, not failed, unless
QDEM_FUZZ_STRICT=1."""
import os

from hypothesis import HealthCheck, given, settings

import fuzzscene

_EXAMPLES = int(os.environ.get("QDEM_FUZZ_EXAMPLES", "0") or 0)
_LONG = bool(os.environ.get("QDEM_FUZZ_LONG"))

if _LONG:
    from hypothesis.database import DirectoryBasedExampleDatabase
    _settings = settings(max_examples=_EXAMPLES or 30, deadline=None, derandomize=False,
                         database=DirectoryBasedExampleDatabase(os.path.join("out", "fuzz", "hypothesis")),
                         suppress_health_check=list(HealthCheck), print_blob=True)
else:
    _settings = settings(max_examples=_EXAMPLES or 20, deadline=None, derandomize=True, database=None,
                         suppress_health_check=list(HealthCheck), print_blob=True)


@_settings
@given(fuzzscene.sceneSpecs())
def test_random_scenes_keep_the_invariants(spec):
    out = fuzzscene.runScene(spec)
    if os.environ.get("QDEM_FUZZ_VERBOSE"):
        print(out, flush=True)
    known = fuzzscene.knownDefect(out)
    if known and not os.environ.get("QDEM_FUZZ_STRICT"):
        print("\nfuzz: known defect (%s): %s\nspec = %r" % (known, out.failure, spec), flush=True)
        return
    fuzzscene.check(out)
