# Runs pytest inside YADE (yade -n -x tests/python/run_pytest.py [pytest args]),
# so that tests can build YADE scenes; exits with pytest's status.
#
# With pytest-xdist (-n 2) the workers are started with sys.executable, plain
# /usr/bin/python3.11 rather than YADE's launcher: they import yade as a
# module (YADE supports it) from the directory this YADE was loaded from,
# put on their PYTHONPATH here.
import os
import sys

import pytest
import yade

here = os.path.dirname(os.path.dirname(os.path.abspath(yade.__file__)))
os.environ["PYTHONPATH"] = os.pathsep.join([here] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])

args = sys.argv[1:] or ["-q", "tests/python"]
sys.exit(pytest.main(["-p", "no:cacheprovider"] + args))
