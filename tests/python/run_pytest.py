# Runs pytest inside YADE (yade -n -x tests/python/run_pytest.py [pytest args]),
# so that tests can build YADE scenes; exits with pytest's status.
import sys

import pytest

args = sys.argv[1:] or ["-q", "tests/python"]
sys.exit(pytest.main(["-p", "no:cacheprovider"] + args))
