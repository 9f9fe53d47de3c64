"""Instructions counted by valgrind's callgrind inside World::step only, for
the scripts that compare builds by instruction counts
(scripts/bench/arch/step_instructions.py, scripts/bench/contacts/contact_instructions.py)."""
import os
import re
import subprocess
import tempfile

STEP = "qdem::World::step(double)"


def annotate(build, script, args, zeroBefore=False):
    """Runs `python3 script args` under callgrind with PYTHONPATH=build, one
    OpenMP thread, counting only inside World::step (and from its first call
    on when zeroBefore).  Returns (the script's stdout, callgrind_annotate's
    inclusive listing, the program total)."""
    out = tempfile.mktemp(prefix="callgrind.", dir="/tmp")
    env = dict(os.environ, PYTHONPATH=build, OMP_NUM_THREADS="1", OMP_WAIT_POLICY="passive")
    cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=" + out, "--toggle-collect=" + STEP]
    if zeroBefore:
        cmd.append("--zero-before=" + STEP)
    p = subprocess.run(cmd + ["/usr/bin/python3.11", os.path.abspath(script)] + args, env=env,
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise SystemExit("valgrind run failed:\n" + p.stdout[-2000:] + p.stderr[-3000:])
    ann = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", out],
                         stdout=subprocess.PIPE, text=True).stdout
    os.unlink(out)
    m = re.search(r"^\s*([\d,]+)\s+\(100\.0%\)\s+PROGRAM TOTALS", ann, re.M)
    return p.stdout, ann, int(m.group(1).replace(",", "")) if m else None
