"""armsim.Simulation: each excitation form against another that must give the same numbers, the locked
arm against the isometric trial, the state written back, and bad input named."""
import copy
import os

import numpy as np
import pytest

import armsim

FLEXORS = ("BIClong", "BICshort", "BRA", "BRD")


@pytest.fixture(scope="module")
def twin():
    return armsim.Model.load("twin")


def same_samples(a, b):
    assert list(a) == list(b)
    for k in a:
        np.testing.assert_array_equal(a[k], b[k], err_msg=k)


def test_arrays_a_controls_file_and_a_csv_give_the_same_movement(twin, tmp_path):
    t = np.array([0.0, 0.05, 0.05, 0.3])
    u = np.array([0.0, 0.0, 0.6, 0.2])
    arrays = armsim.Simulation(twin, angle_deg=120, excitation={"time_s": t, "BRA": u, "BIClong": u})
    arrays.advance_to(0.3)
    sto = tmp_path / "controls.sto"   # OpenSim's storage format, muscles as /forceset/<muscle>
    with open(sto, "w") as f:
        f.write("controls\nversion=1\nnRows=4\nnColumns=3\ninDegrees=no\nendheader\n")
        f.write("time\t/forceset/BRA\tBIClong\n")
        for row in zip(t, u, u):
            f.write("\t".join(repr(float(x)) for x in row) + "\n")
    from_sto = armsim.Simulation(twin, angle_deg=120, excitation=sto)   # a pathlib.Path
    from_sto.advance_to(0.3)
    same_samples(arrays.samples(), from_sto.samples())
    csv = tmp_path / "controls.csv"
    with open(csv, "w") as f:
        f.write("time_s,BRA,BIClong\n" + "".join(f"{a!r},{b!r},{b!r}\n" for a, b in zip(t, u)))
    from_csv = armsim.Simulation(twin, angle_deg=120, excitation=str(csv))
    from_csv.advance_to(0.3)
    same_samples(arrays.samples(), from_csv.samples())
    s = arrays.samples()
    assert s["excitation_BRA"][[0, 60, 300]].tolist() == pytest.approx([0.0, 0.6 - 0.4 * 0.01 / 0.25, 0.2])
    assert s["elbow_angle_deg"][-1] < 115   # the flexors moved the forearm


def test_a_callable_a_number_and_per_muscle_values_agree(twin):
    runs = [armsim.Simulation(twin, angle_deg=100, excitation=e)
            for e in (0.2, lambda t: 0.2, [0.2] * len(twin.muscles), {m: 0.2 for m in twin.muscles})]
    for r in runs:
        r.advance_to(0.2)
    for r in runs[1:]:
        same_samples(runs[0].samples(), r.samples())
    ramp = armsim.Simulation(twin, angle_deg=100, excitation=lambda t: {"BRA": min(1.0, 2 * t)})
    ramp.advance_to(0.4)
    np.testing.assert_allclose(ramp.samples()["excitation_BRA"][::100], [0.0, 0.2, 0.4, 0.6, 0.8], atol=1e-12)


def test_locked_arm_holds_the_isometric_trials_torque(twin):
    # The trial integrates the locked arm's muscle ODE directly; the simulation the whole Simbody System:
    # issue 30's agreement between the two paths, 1e-6 of the largest value (measured: 2e-7).
    series, _ = armsim.arm_trial(twin, angle_deg=90, rest=0.2, hold=0.3, averaging_window=0.1)
    agonists = [m for m in twin.muscles if series["activation_" + m][-1] > 0]   # the effort's, in this pose
    assert set(FLEXORS) <= set(agonists)
    on = {m: [0.0, 0.0, 1.0, 1.0] for m in agonists}
    sim = armsim.Simulation(twin, locked=True, angle_deg=90, excitation={"time_s": [0, 0.2, 0.2, 0.5], **on})
    sim.advance_to(0.5)
    s = sim.samples()
    for column in ("holding_torque_Nm", "force_BRA_N", "force_BIClong_N"):
        largest = np.max(np.abs(series[column]))
        worst = np.max(np.abs(s[column] - series[column]))
        print(f"{column}: largest difference {worst / largest:.2g} of the largest value")
        assert worst < 1e-6 * largest, column
    np.testing.assert_allclose(s["elbow_angle_deg"], 90.0, rtol=0, atol=1e-12)


def test_state_written_back_continues_the_same_way(twin):
    a = armsim.Simulation(twin, angle_deg=130, excitation={"BRA": 0.5})
    b = armsim.Simulation(twin, angle_deg=70, excitation={"TRIlat": 0.1})
    a.advance_to(0.15)
    b.advance_to(0.15)
    b.set_state(copy.deepcopy(a.state))
    b.set_excitation({"BRA": 0.5})
    assert b.muscle_forces_N.tolist() == a.muscle_forces_N.tolist()
    a.advance_to(0.3)
    b.advance_to(0.3)
    for k in ("elbow_angle_deg", "force_BRA_N", "state_BRA_L"):
        np.testing.assert_array_equal(a.samples()[k][151:], b.samples()[k][151:], err_msg=k)
    assert a.state["elbow_angle_deg"] == b.state["elbow_angle_deg"]
    assert len(a.state["muscle_states"]) == len(a.state_names)


def test_bad_input_is_named_and_changes_nothing(twin):
    sim = armsim.Simulation(twin, locked=True)
    with pytest.raises(ValueError, match="'XX' is not a muscle of model 'twin'"):
        armsim.Simulation(twin, excitation={"XX": 1.0})
    with pytest.raises(ValueError, match="2 values for a model with 10 muscles"):
        armsim.Simulation(twin, excitation=[0.1, 0.2])
    with pytest.raises(ValueError, match="1.5: expected in \\[0, 1\\]"):
        armsim.Simulation(twin, excitation=1.5)
    with pytest.raises(TypeError, match="expected a number"):
        armsim.Simulation(twin, excitation={"BRA": "high"})
    with pytest.raises(FileNotFoundError, match="nothing.sto"):
        armsim.Simulation(twin, excitation="nothing.sto")
    with pytest.raises(ValueError, match="angle_deg = 300"):
        armsim.Simulation(twin, angle_deg=300)
    sim.advance_to(0.01)
    with pytest.raises(ValueError, match="time_s' = 0.005 s"):
        sim.advance_to(0.005)
    before = sim.state
    with pytest.raises(ValueError, match="on a locked elbow"):
        sim.set_state(elbow_angle_deg=60, elbow_velocity_degps=5)
    assert sim.state["elbow_angle_deg"] == before["elbow_angle_deg"]   # the angle was not kept
    with pytest.raises(ValueError, match="muscle states: 3 values"):
        sim.set_state(muscle_states=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="time moves with advance_to"):
        sim.set_state({**before, "time_s": 0.0})


def test_samples_go_straight_into_pandas(twin):
    pd = pytest.importorskip("pandas")
    sim = armsim.Simulation(twin, excitation=0.1)
    sim.advance_to(0.05)
    frame = pd.DataFrame(sim.samples())
    assert frame.shape == (51, len(sim.samples()))
    assert frame["time_s"].iloc[-1] == pytest.approx(0.05)


def test_result_columns_numpy_arrays_and_a_refused_excitation(twin):
    # A result dict's columns are strided views: read as values, not as raw memory.
    series, _ = armsim.arm_trial(twin, angle_deg=90, rest=0.1, hold=0.1)
    t, u = series["time_s"], series["activation_BRA"]
    assert not t.flags["C_CONTIGUOUS"]
    views = armsim.Simulation(twin, locked=True, excitation={"time_s": t, "BRA": u})
    copies = armsim.Simulation(twin, locked=True, excitation={"time_s": np.array(t), "BRA": np.array(u)})
    views.advance_to(0.2)
    copies.advance_to(0.2)
    same_samples(views.samples(), copies.samples())
    # numpy per-muscle values, of any length, as lists are
    a = armsim.Simulation(twin, excitation=np.full(len(twin.muscles), 0.2))
    b = armsim.Simulation(twin, excitation=[0.2] * len(twin.muscles))
    a.advance_to(0.05)
    b.advance_to(0.05)
    same_samples(a.samples(), b.samples())
    # a refused excitation keeps the callable it would have replaced
    ramp = lambda time: {"BRA": min(1.0, time)}
    kept = armsim.Simulation(twin, excitation=ramp)
    plain = armsim.Simulation(twin, excitation=ramp)
    kept.advance_to(0.1)
    plain.advance_to(0.1)
    with pytest.raises(ValueError, match="'XX' is not a muscle"):
        kept.set_excitation({"XX": 1.0})
    kept.advance_to(0.2)
    plain.advance_to(0.2)
    same_samples(kept.samples(), plain.samples())


def test_one_simulation_is_stepped_by_one_thread_at_a_time(twin):
    import threading
    sim = armsim.Simulation(twin, rate=10, excitation={"time_s": np.linspace(0, 60, 6001),
                                                      "BRA": 0.3 + 0.2 * np.sin(np.linspace(0, 600, 6001))})
    worker = threading.Thread(target=sim.advance_to, args=(60.0,))
    worker.start()
    refused = False
    while worker.is_alive() and not refused:
        try:
            sim.state
        except RuntimeError as e:
            refused = "advance_to is running in another thread" in str(e)
    worker.join()
    if not refused:
        pytest.skip("the advance ended before another call could be tried")
    assert sim.time_s == pytest.approx(60.0)
