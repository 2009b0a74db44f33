"""Results go straight into pandas (Debian's python3-pandas, optional: skipped without it): every series
and table as pandas.DataFrame(result), every list of estimates or summaries as pandas.DataFrame(list),
with the columns, lengths and values the dicts hold."""
import numpy as np
import pytest

import armsim

pd = pytest.importorskip("pandas")


def check_frame(columns, frame):
    assert list(frame.columns) == list(columns)
    for name, values in columns.items():
        np.testing.assert_array_equal(frame[name].to_numpy(), np.asarray(values), err_msg=name)


def test_series_and_tables_are_frames(thesis):
    twin = armsim.Model.load("twin")
    series, summary = armsim.arm_trial(twin, hold=0.2)
    check_frame(series, pd.DataFrame(series))
    assert pd.Series(summary)["mean_force_N"] == summary["mean_force_N"]
    trial = armsim.muscle_trial(thesis, duration=0.05)
    check_frame(trial, pd.DataFrame(trial))
    sim = armsim.Simulation(twin, excitation=0.1)
    sim.advance_to(0.02)
    check_frame(sim.samples(), pd.DataFrame(sim.samples()))
    data = armsim.read_torque_data("measured/thesis_mvc_torque.csv")
    check_frame(data, pd.DataFrame(data))
    run = armsim.run_protocol("protocols/mvc_force_angle.yaml")
    check_frame(run["trials"], pd.DataFrame(run["trials"]))


def test_estimates_and_validation_rows_are_frames():
    estimates = armsim.identify_torque("measured/thesis_mvc_torque.csv", activation=0.95)
    frame = pd.DataFrame(estimates)
    assert list(frame["method"]) == [e["method"] for e in estimates]
    assert list(frame["mass_kg"]) == [e["mass_kg"] for e in estimates]
    rows, summary = armsim.validate_elbow(subjects=2, noise=[0.02], jobs=1)
    check_frame(rows, pd.DataFrame(rows))
    assert len(pd.DataFrame(summary)) == len(summary)
