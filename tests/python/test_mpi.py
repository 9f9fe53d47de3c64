"""QDEM split across MPI ranks (doc/parallel.md), against serial runs.

Each test launches mpiexec -n P (oversubscribed, one thread per rank, passive
waits, a timeout: a deadlock fails instead of hanging)."""
import numpy as np
import pytest

from mpi_launch import mpirun, python, requireMpi, result


@pytest.mark.parametrize("P", [2, 3, 4])
def test_contact_free_scene_matches_serial(P):
    requireMpi()
    rc, out = mpirun(P, python("tests/mpi/check_contact_free.py"))
    assert rc == 0, out[-4000:]
    r = result(out)
    # Every node owned exactly once, by the rank the (common) split names.
    assert r["sameSplitEverywhere"]
    assert r["ownedPerRank"] == r["ownedByOwnerArray"]
    assert sum(r["ownedPerRank"]) == r["nNodes"]
    assert sum(r["tetsPerRank"]) == r["nTets"]
    assert all(n > 0 for n in r["tetsPerRank"])
    assert r["imbalance"] <= 1.05 + 1e-12
    # Neighbour relation symmetric.
    for a, nb in enumerate(r["neighbours"]):
        for b in nb:
            assert a in r["neighbours"][b]
    # Trajectories: only the order of the partial force sums differs from
    # serial (a ghost's partial force is added after the owner's own tets).
    assert r["maxDisplacement"] > 0.01
    assert r["dx"] <= 1e-13 * r["maxDisplacement"]
    assert r["dv"] <= 1e-10 * r["vmax"]
    # Floor reaction (summed over the ranks) and energies as serial.
    s, ss = np.array(r["series"]), np.array(r["serialSeries"])
    fmax = np.abs(ss[:, :3]).max()
    assert fmax > 1.0, "the scene must push on the floor during the run"
    assert np.abs(s[:, :6] - ss[:, :6]).max() <= 1e-9 * fmax
    assert np.abs(s[:, 6:] - ss[:, 6:]).max() <= 1e-10 * np.abs(ss[:, 6:]).max()
    # Momentum and energy ledgers as serial (energy: the total above, every 50 steps).
    pm, ps = np.array(r["momentum"]), np.array(r["serialMomentum"])
    assert np.abs(pm - ps).max() <= 1e-10 * max(np.abs(ps).max(), 1e-12)


@pytest.mark.parametrize("P", [2, 3])
def test_error_on_one_rank_stops_every_rank(P):
    requireMpi()
    rc, out = mpirun(P, python("tests/mpi/check_errors.py"), timeout=120)
    assert rc == 0, out[-4000:]
    r = result(out)
    caught = r["caught"]
    assert len(caught) == P
    # (a) the start-overlap refusal of the rank(s) owning the piece: the same
    # message on every rank, naming the rank and the fix.
    msgs = {tuple(c["a"]) for c in caught}
    assert len(msgs) == 1
    kind, msg = msgs.pop()
    assert kind == "ValueError" and "starts inside obstacle" in msg and msg.startswith("QDEM rank ")
    # (b) a NaN on one rank's node: every rank stops with the same StabilityError.
    msgs = {tuple(c["b"]) for c in caught}
    assert len(msgs) == 1
    kind, msg = msgs.pop()
    assert kind == "StabilityError" and "not finite" in msg
    # (c) ranks whose YADE copies hold other spheres: refused on every rank, naming the fix.
    for c in caught:
        assert c["c"][0] == "ValueError" and "YADE bodies" in c["c"][1] and "seed" in c["c"][1]
    # (d) ranks with different scenes: refused on every rank, naming the fix.
    for c in caught:
        assert c["d"][0] == "ValueError" and "different scenes" in c["d"][1] and "seed" in c["d"][1]
    # (f) an impact deeper than the contact's reach: every rank stops with the
    # same StabilityError in the same step, the one it happens in.
    msgs = {tuple(c["f"]) for c in caught}
    assert len(msgs) == 1 and len({c["fIter"] for c in caught}) == 1
    kind, msg = msgs.pop()
    assert kind == "StabilityError" and "deeper than their contact can see" in msg and "closing at" in msg
    assert caught[0]["fIter"] < 30
    # (e) scenes that differ in velocities, loads, O.dt, settings or gravity:
    # refused on every rank, naming what differs (they ran on silently).
    for c in caught:
        for what, (kind, msg) in c["e"].items():
            assert kind == "ValueError" and what in msg and "every rank" in msg, (what, kind, msg)


@pytest.mark.parametrize("case", ["typo", "save"])
def test_script_error_on_some_ranks_ends_the_job(case, tmp_path):
    """A script error on rank 0 alone (a typo inside `if rank == 0:`), or a
    save that fails on the writing rank only (a missing directory), ended
    rank 0 while the others waited in the next step for good: the job hung
    until its time limit.  Now it ends at once with the message."""
    requireMpi()
    rc, out = mpirun(2, ["yade", "-n", "-x", "tests/mpi/yade_rank_errors.py", case, str(tmp_path)], timeout=90)
    assert rc not in (0, 124, 137), "the job %s:\n%s" % ("hung" if rc in (124, 137) else "did not fail", out[-4000:])
    assert "stopping every rank" in out, out[-4000:]
    assert "FINISHED" not in out
    if case == "typo":
        assert "no_such_attribute" in out
    else:
        assert "does not exist" in out and "no_such_dir" in out


@pytest.mark.parametrize("case", ["steps", "save0", "state0"])
def test_collectives_reached_on_some_ranks_only_end_the_job(case, tmp_path):
    """More steps on one rank, or O.save / saveState inside `if rank == 0:`:
    each rank waited for the other for good.  Every QDEM collective (a step,
    a gather, the script's end) is agreed first, and a mismatch ends the job
    naming both calls."""
    requireMpi()
    rc, out = mpirun(2, ["yade", "-n", "-x", "tests/mpi/yade_rank_errors.py", case, str(tmp_path)], timeout=90)
    assert rc not in (0, 124, 137), "the job %s:\n%s" % ("hung" if rc in (124, 137) else "did not fail", out[-4000:])
    assert "reached different collective operations" in out, out[-4000:]
    want = "at the end of the script" if case == "steps" else "in gatherState"
    assert want in out and "in a step" in out, out[-4000:]


def test_failed_save_is_raised_on_every_rank(tmp_path):
    """The writer's failure reaches every rank as an exception the script can
    catch, and the run goes on alike."""
    requireMpi()
    rc, out = mpirun(2, ["yade", "-n", "-x", "tests/mpi/yade_rank_errors.py", "savecaught", str(tmp_path)],
                     timeout=90)
    assert rc == 0, out[-4000:]
    assert "RANK 0 CAUGHT OSError" in out and "RANK 1 CAUGHT RuntimeError" in out, out[-4000:]
    assert "RANK 0 FINISHED iter 40" in out and "RANK 1 FINISHED iter 40" in out, out[-4000:]


@pytest.mark.parametrize("P,warm,pre", [(2, False, "cholesky"), (3, False, "cholesky"), (2, True, "cholesky"),
                                         (3, True, "cholesky"), (2, False, "jacobi"), (3, True, "jacobi")])
def test_implicit_viscosity_on_ranks_as_serially(P, warm, pre):
    # The distributed conjugate gradients (doc/parallel.md): C p by one pass
    # over the owned tets with the ghosts' partial sums sent back, dot
    # products summed in rank order, the serial stopping rule.  From zero
    # (viscousWarmStart False) the result depends on the state alone: equal
    # to serial to rounding.  Warm, each step's solve error carries into the
    # next start and rounding differences grow (within the tolerance): equal
    # to serial within what separates 1 and 2 threads serially.
    requireMpi()
    # The Cholesky preconditioner's pieces split over ranks are gathered
    # (CorotatedCholesky.hpp): the serial preconditioner, the same counts.
    rc, out = mpirun(P, python("tests/mpi/check_implicit_viscosity.py", pre, *(["warm"] if warm else [])), timeout=400)
    assert rc == 0, out[-4000:]
    r = result(out)
    lim = r["limits"]
    assert lim["combinedImplicit"] > 20 * lim["combinedExplicit"]  # viscosity would limit an explicit step
    assert all(t > 0 for t in r["ownedTets"])
    # Every rank took the same number of iterations at every step, and the
    # solve did iterate: the first from 0, the others (warm) from the last
    # step's change, fewer.
    its = r["iterations"]
    assert len(its) == P and all(i == its[0] for i in its)
    if pre == "jacobi":
        assert its[0][0] >= 10
    else:
        assert 1 <= its[0][0] and max(its[0]) <= 4  # (Jacobi: >= 10)
    assert its[0] == r["serialIterations"] or warm
    if warm and pre == "jacobi":
        assert np.mean(its[0]) < 0.5 * its[0][0]  # (the warm starts paid)
    if warm:
        # A rebalance forced half-way moved nodes; their last changes moved
        # with them: the next solve is as warm as the others (11 iterations
        # instead of 3 when the rows are not migrated).
        half = r["steps"] // 2
        assert r["moved"][0] > 0
        assert its[0][half] <= max(2 * np.median(its[0][1:]), 2), (its[0][half - 3:half + 3], np.median(its[0][1:]))
    # Trajectories as serial, within what separates 1 and 2 threads serially
    # (the order of the partial sums is the only difference).
    d = r["maxDisplacement"]
    assert d > 1e-3
    # Warm starts carry each step's rounding into the next solve's start,
    # and the solve stops at its tolerance (1e-3 by default), not at the
    # same bits: on 3 ranks with Jacobi 1.2e-13 of 8.9e-3 m and 2.5e-9 of
    # 0.65 m/s, where 1 and 2 threads happened to part by 10-30x less (one
    # sample of that spread).  Cold, the serial thread difference holds.
    assert r["dx"] <= max(10 * r["dxThreads"], (1e-10 if warm else 1e-13) * d)
    assert r["dv"] <= max(10 * r["dvThreads"], (1e-7 if warm else 1e-10) * r["vmax"])
    # Floor reaction, energy ledger (total, viscous dissipation, kinetic) as serial.
    s, ss = np.array(r["series"]), np.array(r["serialSeries"])
    assert ss[-1, 4] > 1e-3 * ss[-1, 3], "viscosity must dissipate a visible share"
    licence = np.abs(np.array(r["serialSeries2Threads"]) - ss).max(axis=0) if warm else 0 * ss[0]
    assert (np.abs(s[:, :3] - ss[:, :3]).max(axis=0) <= np.maximum(10 * licence[:3],
                                                                  1e-9 * np.abs(ss[:, :3]).max())).all()
    assert (np.abs(s[:, 3:] - ss[:, 3:]).max(axis=0) <= np.maximum(10 * licence[3:],
                                                                  1e-10 * np.abs(ss[:, 3:]).max())).all()
    pm, ps = np.array(r["momentum"]), np.array(r["serialMomentum"])
    pLicence = np.abs(np.array(r["serialMomentum2Threads"]) - ps).max() if warm else 0.0
    assert np.abs(pm - ps).max() <= max(10 * pLicence, 1e-10 * np.abs(ps).max())


def test_yade_floor_force_under_mpiexec_equals_serial():
    # The measurement: under mpiexec -n 3 every rank stepped the whole
    # QDEM world, and the floor force was 3x the serial one.
    requireMpi()
    import subprocess
    from mpi_launch import ROOT, env
    ser = subprocess.run(["timeout", "300", "yade", "-n", "-x", "tests/mpi/yade_floor.py"], cwd=ROOT, env=env(),
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert ser.returncode == 0, ser.stdout[-3000:]
    s = result(ser.stdout)
    rc, out = mpirun(3, ["yade", "-n", "-x", "tests/mpi/yade_floor.py"], timeout=300)
    assert rc == 0, out[-4000:]
    m = result(out)
    assert s["ranks"] == 1 and m["ranks"] == 3
    assert m["iter"] == s["iter"]
    # At rest: the floor carries the weight, as serially.
    assert s["floor"][2] == pytest.approx(-s["weight"], rel=1e-6)
    # Local damping's sign switch (YADE's rule) turns rounding-level
    # differences of the force sums into ~1e-9 ones at rest: equal to that.
    assert m["floor"][2] == pytest.approx(s["floor"][2], rel=1e-7)
    assert m["floor"][2] == pytest.approx(-s["weight"], rel=1e-6)
    assert m["zmin"] == pytest.approx(s["zmin"], abs=1e-9)
    assert m["energy"] == pytest.approx(s["energy"], rel=1e-7)


@pytest.mark.parametrize("P", [2, 3, 4])
def test_contacts_across_ranks_match_serial(P):
    requireMpi()
    rc, out = mpirun(P, python("tests/mpi/check_contacts.py"))
    assert rc == 0, out[-4000:]
    r = result(out)
    s, ss = np.array(r["series"]), np.array(r["serialSeries"])
    # Every contact computed exactly once: the counts summed over the ranks
    # are the serial ones, every 25 steps; and the scene has all three kinds.
    assert np.array_equal(s[:, :3], ss[:, :3])
    assert (ss[:, :3].sum(axis=0) > 0).all()
    # Trajectories differ by summation order only: as much as 1 vs 2 threads
    # serially (both are rounding noise of ~1e-13, so within a factor of 10),
    # and never more than 1e-10 of the largest displacement.
    d = r["maxDisplacement"]
    assert d > 0.02
    assert r["dx"] <= 1e-10 * d
    assert r["dx"] <= max(10 * r["dxThreads"], 1e-13 * d)
    # The floor reaction summed over the ranks, and the energy, as serial.
    fmax = np.abs(ss[:, 3:6]).max()
    assert np.abs(s[:, 3:6] - ss[:, 3:6]).max() <= 1e-9 * fmax
    assert np.abs(s[:, 6] - ss[:, 6]).max() <= 1e-9 * np.abs(ss[:, 6]).max()
    # The halo is real: ghosts and messages on every rank that has neighbours.
    assert sum(r["ghosts"]) > 0 and all(m > 0 for m in r["stepMessages"])


@pytest.mark.parametrize("broad,P", [("A", 3), ("B", 2), ("C", 4)])
def test_seed_broad_phases_across_ranks_match_serial(broad, P):
    # The seed's cases register tetrahedra (A: all, B/C: surface tets, whose
    # fourth node is interior): the contact halo carries their nodes.
    requireMpi()
    import os
    os.environ["QDEM_MPI_BROADPHASE"] = broad
    try:
        rc, out = mpirun(P, python("tests/mpi/check_contacts.py"))
    finally:
        del os.environ["QDEM_MPI_BROADPHASE"]
    assert rc == 0, out[-4000:]
    r = result(out)
    s, ss = np.array(r["series"]), np.array(r["serialSeries"])
    assert np.array_equal(s[:, :3], ss[:, :3]) and (ss[:, :3].sum(axis=0) > 0).all()
    if broad in ("A", "B"):  # the interior faces tested (the seed's Figure 6 cost) as serially
        assert np.array_equal(s[:, 7:], ss[:, 7:]) and ss[:, 7].sum() > 0
    d = r["maxDisplacement"]
    assert r["dx"] <= 1e-10 * d
    assert r["dx"] <= max(10 * r["dxThreads"], 1e-13 * d)
    fmax = np.abs(ss[:, 3:6]).max()
    assert np.abs(s[:, 3:6] - ss[:, 3:6]).max() <= 1e-9 * fmax


@pytest.mark.parametrize("P", [2, 4])
def test_forced_rebalance_mid_run_keeps_the_trajectory_and_histories(P):
    requireMpi()
    import os
    os.environ["QDEM_MPI_REBALANCE"] = "1"
    try:
        rc, out = mpirun(P, python("tests/mpi/check_contacts.py"))
    finally:
        del os.environ["QDEM_MPI_REBALANCE"]
    assert rc == 0, out[-4000:]
    r = result(out)
    assert r["rebalances"] == [1] * P and r["movedNodes"][0] > 0  # the split moved, mid-contact
    s, ss = np.array(r["series"]), np.array(r["serialSeries"])
    # With the histories lost the counts differ and |dx| is ~1e-4 of the
    # displacement (seen with the surface-node rows left behind).
    assert np.array_equal(s[:, :3], ss[:, :3])
    d = r["maxDisplacement"]
    assert r["dx"] <= 1e-10 * d
    assert r["dx"] <= max(10 * r["dxThreads"], 1e-13 * d)


def test_static_friction_holds_across_a_rank_boundary():
    requireMpi()
    rc, out = mpirun(3, python("tests/mpi/check_friction_hold.py"))
    assert rc == 0, out[-4000:]
    r = result(out)
    assert len(r["slabRanks"]) >= 2  # the slab under the cube is split
    x0, xm, x1 = (np.array(r[k]) for k in ("x0", "xMid", "x1"))
    # Held: the tangential spring's deflection is taken in the first half,
    # then nothing moves (tilt 0.3 < friction 0.5).
    assert np.linalg.norm((x1 - xm)[:2]) < 1e-8
    assert np.linalg.norm((x1 - x0)[:2]) < 1e-3
    assert r["vmax"] < 1e-6
    for a, b in zip((x0, xm, x1), r["serial"]):
        assert np.abs(a - np.array(b)).max() < 1e-12


def test_restart_on_ranks_continues_the_run(tmp_path):
    # qdem.saveState on P ranks gathers every rank's histories, rank 0 writes;
    # loaded on P ranks the run goes on as if never stopped, energies counted once.
    requireMpi()
    import os
    os.environ["QDEM_MPI_TMP"] = str(tmp_path)
    try:
        rc, out = mpirun(3, python("tests/mpi/check_restart.py"))
    finally:
        del os.environ["QDEM_MPI_TMP"]
    assert rc == 0, out[-4000:]
    r = result(out)
    assert r["contVsSerial"] <= 1e-12 * r["disp"]
    assert r["restartVsCont"] <= 1e-13 * r["disp"]
    # ... and loaded by one process: the file is the serial one.
    assert r["serialRestartVsCont"] <= 1e-12 * r["disp"]
    assert r["energySerialRestart"] == pytest.approx(r["energyCont"], rel=1e-10)
    assert r["energyRestart"] == pytest.approx(r["energyCont"], rel=1e-12)
    assert r["energyCont"] == pytest.approx(r["energySerial"], rel=1e-10)


def test_yade_save_and_load_under_mpiexec(tmp_path):
    requireMpi()
    path = str(tmp_path / "scene.yade.gz")
    rc, out = mpirun(3, ["yade", "-n", "-x", "tests/mpi/yade_save_load.py", path], timeout=300)
    assert rc == 0, out[-4000:]
    r = result(out)
    assert r["ranks"] == 3 and r["iter"][0] == r["iter"][1] == 600
    assert r["dx"] <= 1e-15
    assert r["floor"][0] != 0 and r["floor"][1] == pytest.approx(r["floor"][0], rel=1e-12)


@pytest.mark.parametrize("P", [2, 3])
def test_sleeping_pieces_on_ranks_as_serially(P):
    # Every rank takes the same sleep decisions: the ranks' largest node
    # speeds and the whole pieces' boxes are reduced first.
    requireMpi()
    rc, out = mpirun(P, python("tests/mpi/check_sleep.py"))
    assert rc == 0, out[-4000:]
    r = result(out)
    s, ss = np.array(r["series"]), np.array(r["serialSeries"])
    assert np.array_equal(s[:, 0], ss[:, 0])  # pieces asleep, every 100 steps
    assert ss[-1, 0] == len(r["serialAsleep"])  # the scene comes to rest
    assert all(a == r["serialAsleep"] for a in r["asleep"])
    # Sleeping thresholds and the sign of Cundall damping turn rounding into
    # up to ~2e-4 of the displacement: 1 and 2 threads serially part by
    # 4e-7 to 1.6e-6 of 9.8e-3 m from run to run (and once by 7e-9), ranks by
    # 8.8e-7.  A fixed licence, not one run's thread difference, which is
    # itself a sample of that spread; the decisions are checked exactly above.
    assert r["dx"] <= 5e-4 * r["disp"]
    assert np.abs(s[:, 1] - ss[:, 1]).max() <= 1e-4 * np.abs(ss[:, 1]).max()


def test_piece_added_mid_run_on_ranks():
    # Every rank adds it; the world is split again from the gathered state.
    requireMpi()
    rc, out = mpirun(3, python("tests/mpi/check_add_piece.py"))
    assert rc == 0, out[-4000:]
    r = result(out)
    assert r["dx"] <= 1e-12 * r["disp"]
    assert r["energy"][0] == pytest.approx(r["energy"][1], rel=1e-10)


# ---- YADE spheres and clumps (every rank holds the whole YADE scene) --------

_serialSpheres = {}


def _yadeRun(script, scene, P=1, threads=1, tmp=None, **envExtra):
    """Runs `yade -n -x tests/mpi/SCRIPT SCENE` serially (P = 1) or on P ranks,
    QDEM on `threads` threads; the JSON it writes to QDEM_MPI_OUT."""
    import json
    import os
    import subprocess
    import tempfile
    from mpi_launch import ROOT, env
    fd, out = tempfile.mkstemp(suffix=".json", dir=tmp)
    os.close(fd)
    args = ["yade", "-n", "-x", "tests/mpi/" + script, scene]
    extra = dict(envExtra, QDEM_THREADS=str(threads), QDEM_MPI_OUT=out)
    try:
        if P == 1:
            e = env()
            e.update(extra, OMP_NUM_THREADS=str(threads))
            p = subprocess.run(["timeout", "300"] + args, cwd=ROOT, env=e, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
            rc, log = p.returncode, p.stdout
        else:
            saved = dict(os.environ)
            os.environ.update(extra)
            try:
                rc, log = mpirun(P, args, timeout=300)
            finally:
                os.environ.clear()
                os.environ.update(saved)
        assert rc == 0, log[-4000:]
        with open(out) as f:
            return json.load(f)
    finally:
        os.remove(out)


def _yadeSpheres(scene, P=1, threads=1, tmp=None, **envExtra):
    """Runs tests/mpi/yade_spheres.py SCENE serially (P = 1) or on P ranks; its JSON."""
    return _yadeRun("yade_spheres.py", scene, P, threads, tmp, **envExtra)


def _sphereReference(scene):
    """The serial run with 1 and 2 QDEM threads (their difference is the licence)."""
    if scene not in _serialSpheres:
        _serialSpheres[scene] = (_yadeSpheres(scene, threads=1), _yadeSpheres(scene, threads=2))
    return _serialSpheres[scene]


def _sphereDiffs(a, b):
    dx = np.abs(np.array(a["pos"]) - np.array(b["pos"])).max()
    sa, sb = np.array(a["spheres"]), np.array(b["spheres"])
    return dx, np.abs(sa - sb).max() / np.abs(sa).max()


def _assertSpheresAsSerial(r, s, s2, resting=True):
    d = s["disp"]
    dxThreads, dsThreads = _sphereDiffs(s, s2)
    dx, ds = _sphereDiffs(s, r)
    # Every sphere contact computed once: the counts summed over the ranks are
    # the serial ones, every 25 steps; the scene has contacts.
    ser, mine = np.array(s["series"]), np.array(r["series"])
    assert np.array_equal(mine[:, 0], ser[:, 0]) and ser[:, 0].sum() > 10
    # Every rank's copy of YADE got the same forces: its spheres are bit-identical.
    assert r["sphereRankSpread"] == 0.0
    # Summation order is the only licence: as far as 1 vs 2 threads serially.
    assert dx <= 1e-10 * d and dx <= max(10 * dxThreads, 1e-13 * d)
    assert ds <= max(10 * dsThreads, 1e-13)
    # The floor reaction (QDEM's, summed over the ranks, plus YADE's) and the energy as serial.
    fmax = np.abs(ser[:, 1:4]).max()
    assert fmax > 1.0 and np.abs(mine[:, 1:4] - ser[:, 1:4]).max() <= 1e-9 * fmax
    assert np.abs(mine[:, 4] - ser[:, 4]).max() <= 1e-9 * np.abs(ser[:, 4]).max()
    # Momentum of spheres and pieces against the floor's impulse and gravity.
    assert np.abs(r["ledger"]).max() <= 1e-12 * r["momentumScale"]
    # The sphere-piece contact histories: the same on every rank (each pair's
    # owner's, through the reduction), the serial ones to the licence.
    assert r["historySameOnRanks"]
    assert r["historyKeys"] == s["historyKeys"]
    live = np.repeat(np.array(s["historyKeys"]) >= 0, 3)  # springs of slots holding a contact
    sh, sh2, mine = (np.array(x["historyShear"])[live] for x in (s, s2, r))
    if resting:  # spheres resting on the block at the end: contacts with springs
        assert max(r["historyKeys"]) >= 0 and np.abs(sh).max() > 0
    if live.any():
        assert np.abs(mine - sh).max() <= max(10 * np.abs(sh2 - sh).max(), 1e-13 * np.abs(sh).max())


@pytest.mark.parametrize("scene,P", [("drop", 2), ("drop", 3), ("drop", 4), ("clump", 2), ("clump", 3)])
def test_yade_spheres_and_clumps_on_ranks_as_serially(scene, P):
    requireMpi()
    s, s2 = _sphereReference(scene)
    r = _yadeSpheres(scene, P)
    assert r["ranks"] == P
    _assertSpheresAsSerial(r, s, s2, resting=scene == "drop")  # (the clump hops: in the air at the end)
    # The split cuts under the spheres (the clump rolls across a cut): pairs
    # are computed on several ranks.
    assert sum(n > 0 for n in r["sphereContactsPerRank"]) >= 2


def test_yade_spheres_save_load_keeps_their_histories_serially(tmp_path):
    # One process: O.save with spheres resting on the block, O.load, the same
    # steps again: bit for bit (the sphere-piece springs are in the state;
    # without them the spheres end 0.016 apart).
    r = _yadeSpheres("drop", 1, QDEM_MPI_SAVE=str(tmp_path / "s.yade.gz"))
    assert r["reloaded"]["iter"][0] == r["reloaded"]["iter"][1]
    assert r["reloaded"]["dx"] == 0.0 and r["reloaded"]["dSphere"] == 0.0


def test_yade_spheres_rebalance_and_save_load_keep_histories(tmp_path):
    # A rebalance forced mid-contact moves nodes between ranks; O.save at the
    # same step, the run goes on, then O.load and the run goes on again: the
    # sphere-piece contact histories survive both.
    requireMpi()
    s, s2 = _sphereReference("drop")
    r = _yadeSpheres("drop", 3, QDEM_MPI_REBALANCE="1", QDEM_MPI_SAVE=str(tmp_path / "s.yade.gz"))
    assert r["movedNodes"] > 0 and min(r["rebalances"]) >= 1
    _assertSpheresAsSerial(r, s, s2)
    rl = r["reloaded"]
    assert rl["iter"][0] == rl["iter"][1]
    _, dsThreads = _sphereDiffs(s, s2)
    scale = np.abs(np.array(r["spheres"])).max()
    # Loaded, the world is split afresh: rounding apart, the same end.
    assert rl["dx"] <= 1e-12 * r["disp"]
    assert rl["dSphere"] <= max(10 * dsThreads, 1e-13) * scale


def _yadeMpy(scene, P=1, threads=1, **envExtra):
    """Runs tests/mpi/yade_mpy.py SCENE serially (P = 1: mp.mpirun falls back
    to O.run) or on P ranks under yade.mpy; its JSON."""
    return _yadeRun("yade_mpy.py", scene, P, threads, **envExtra)


_serialMpy = {}


@pytest.mark.parametrize("scene,P", [("drop", 3), ("drop", 4), ("clump", 3)])
def test_yade_mpy_spheres_and_clump_as_serially(scene, P):
    # The same script serially and under yade.mpy on P ranks (doc/parallel.md,
    # "Under yade.mpy"): mpy's master keeps the floor, the workers the spheres
    # (placed by qdem.yade.mpy.assignSubdomains), QDEM's nodes go to the
    # workers; obstacles and spheres near pieces are gathered every step.
    requireMpi()
    if scene not in _serialMpy:  # the serial run with 1 and 2 QDEM threads (their difference is the licence)
        _serialMpy[scene] = (_yadeMpy(scene, threads=1), _yadeMpy(scene, threads=2))
    s, s2 = _serialMpy[scene]
    r = _yadeMpy(scene, P=P)
    assert r["ranks"] == P and r["qdemRanks"] == P and s["ranks"] == 1
    # QDEM's split leaves mpy's master empty; every sphere lives on a worker.
    assert r["ownedNodes"][0] == 0 and min(r["ownedNodes"][1:]) > 0
    assert r["owners"][0] == [] and sum(len(o) for o in r["owners"]) == len(s["spheres"])
    # Each sphere contact computed once: the counts summed over the ranks are
    # the serial ones, every 25 steps; the scene has contacts.
    ser, mine = np.array(s["series"]), np.array(r["series"])
    assert np.array_equal(mine[:, 0], ser[:, 0]) and ser[:, 0].sum() >= 5
    # Summation order is the only licence: as far as 1 vs 2 threads serially.
    d = s["disp"]
    dxThreads, dsThreads = _sphereDiffs(s, s2)
    dx, ds = _sphereDiffs(s, r)
    assert dx <= 1e-10 * d and dx <= max(10 * dxThreads, 1e-13 * d)
    assert ds <= max(10 * dsThreads, 1e-13)
    # The floor force (QDEM's reaction, added once on the master) and the energy as serial.
    fmax = np.abs(ser[:, 1:4]).max()
    assert fmax > 1.0 and np.abs(mine[:, 1:4] - ser[:, 1:4]).max() <= 1e-9 * fmax
    assert np.abs(mine[:, 4] - ser[:, 4]).max() <= 1e-9 * np.abs(ser[:, 4]).max()
    if scene == "drop":  # spheres on two workers, pairs computed on every worker
        assert sum(len(o) > 0 for o in r["owners"]) == 2
        assert sum(n > 0 for n in r["sphereContactsPerRank"]) == P - 1
    if scene == "drop" and P == 3:
        # After mp.mergeScene() a step on the master alone is refused, not left waiting.
        merged = _yadeMpy(scene, P=3, QDEM_MPY_MERGE="1", QDEM_MPI_STEPS="50")
        assert "QDEM steps only inside mp.mpirun" in merged["mergedStep"]


def test_yade_mpy_stepping_outside_mpirun_is_refused_on_every_rank():
    # Under yade.mpy, O.run before mp.mpirun would split QDEM as under plain
    # mpiexec, and mpy's scene transfer would then wait on the master alone:
    # refused on every rank at the first step, with the fix, and no hang.
    requireMpi()
    import os
    saved = dict(os.environ)
    os.environ["QDEM_MPY_RUN_FIRST"] = "1"
    try:
        rc, out = mpirun(3, ["yade", "-n", "-x", "tests/mpi/yade_mpy.py", "drop"], timeout=240)
    finally:
        os.environ.clear()
        os.environ.update(saved)
    assert rc != 0 and rc != 124, "mpiexec timed out: a hang\n" + out[-3000:]
    assert out.count("steps QDEM outside mp.mpirun") >= 3, out[-3000:]
    assert "mpiexec -n P yade -n -x script.py" in out
