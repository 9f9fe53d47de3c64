"""Launching MPI runs from the tests: mpiexec with oversubscription, one
OpenMP thread per rank, passive waits (two cores shared by several ranks) and
a timeout, so that a deadlock fails the test instead of hanging CI."""
import json
import os
import shutil
import subprocess
import sys

import pytest

import qdem

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PY = "/usr/bin/python3.11"


#: Set by `make test` (the Makefile's test-py): there a build without MPI, or
#: no mpiexec, fails the MPI tests instead of skipping them.
REQUIRED = os.environ.get("QDEM_TESTS_REQUIRE_MPI", "") not in ("", "0")


def requireMpi():
    """Skips an MPI test where MPI is missing, with the reason and the fix;
    under `make test` (QDEM_TESTS_REQUIRE_MPI=1) fails it instead."""
    missing = None
    if not qdem._core.hasMPI:
        missing = ("this build has no MPI (Open MPI or mpi4py missing when CMake ran): install them "
                   "(scripts/setup/deps.sh) and build again")
    elif shutil.which("mpiexec") is None:
        missing = "mpiexec not found: install openmpi-bin (scripts/setup/deps.sh)"
    if missing is None:
        return
    if REQUIRED:
        pytest.fail("MPI is required in `make test` (QDEM_TESTS_REQUIRE_MPI=1): " + missing, pytrace=False)
    pytest.skip(missing)


def env():
    e = dict(os.environ)
    for k in list(e):
        if k.startswith(("OMPI_", "PMI_", "PMIX_")):
            del e[k]  # a clean launch, whatever launched the tests
    e.update(OMP_NUM_THREADS="1", OMP_WAIT_POLICY="passive", OMPI_MCA_mpi_yield_when_idle="1",
             OMPI_MCA_rmaps_base_oversubscribe="1", PYTHONPATH=os.path.join(ROOT, "build", "python"))
    return e


def mpirun(n, args, timeout=240):
    """Runs `args` on n ranks; returns (returncode, stdout + stderr)."""
    cmd = ["timeout", "-k", "10", str(timeout), "mpiexec", "--allow-run-as-root", "--oversubscribe", "-n", str(n)] + args
    p = subprocess.run(cmd, cwd=ROOT, env=env(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                       timeout=timeout + 30)
    return p.returncode, p.stdout


def result(out):
    """The 'RESULT {json}' line rank 0 printed."""
    for line in out.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[len("RESULT "):])
    raise AssertionError("no RESULT line in the MPI run's output:\n" + out[-4000:])


def python(script, *args):
    return [PY, os.path.join(ROOT, script), *args]
