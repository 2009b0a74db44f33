"""The Python module (issue 12): every bound function called, results equal to the C++ API's
(tests/python/reference.cpp, 17 digits) to 1e-12 relative, numpy dtypes and shapes, errors with the
command line's messages, and the GIL released during long calls."""
import os
import pathlib
import re

import numpy as np
import pytest

import armsim

from conftest import REL_TOL, measure_longest_stall


def test_model_lists_muscles_and_parameters_with_the_files_names(thesis, elbow):
    assert thesis.muscles == ["biceps"] and thesis.primary == "biceps"
    assert len(elbow.muscles) == 7 and elbow.primary in elbow.muscles
    p = thesis.parameters()
    assert p["mass"] == pytest.approx(0.33599, rel=1e-15)
    assert set(p) == {"name", "mass", "optimal_fascicle_length", "optimal_tendon_length", "max_path_length",
                      "slow_fraction", "slow_units", "fast_units"}
    assert "armsim.Model 'elbow', 7 muscles" in repr(elbow)


def test_with_muscle_changes_one_parameter_and_keeps_the_original(thesis):
    heavier = thesis.with_muscle(mass=0.4, optimal_tendon_length=0.25)
    assert heavier.parameters()["mass"] == 0.4
    assert heavier.parameters()["optimal_tendon_length"] == 0.25
    assert thesis.parameters()["mass"] == 0.33599
    # force scales with mass at a fixed normalised state: F0 is proportional to M
    f = armsim.steady_state(thesis, 0.40, 1.0)["force_N"]
    assert armsim.steady_state(thesis.with_muscle(mass=0.67198), 0.40 + 0.0, 1.0)["force_N"] > f


def test_steady_state_equals_the_cpp_api(thesis, reference):
    s = armsim.steady_state(thesis, 0.40, 1.0)
    assert s["force_N"] == pytest.approx(reference["steady_force"], rel=REL_TOL)
    assert s["fascicle_length_m"] == pytest.approx(0.16 * s["normalized_fascicle_length"], rel=1e-14)


def test_muscle_trial_samples_equal_the_cpp_api(thesis, reference):
    t = armsim.muscle_trial(thesis, path_length=0.375, activation=0.8, onset=0.1, rise=0.05, duration=1.0)
    assert t["force_N"].dtype == np.float64 and t["force_N"].shape == (1001,)
    assert all(a.shape == (1001,) for a in t.values())
    np.testing.assert_allclose(t["force_N"][::100], reference["muscle_trial_force"], rtol=REL_TOL, atol=0)
    assert t["time_s"][-1] == pytest.approx(1.0)


def test_geometry_equals_the_cpp_api(elbow, reference):
    g = elbow.geometry([30, 90, 120])
    assert g["moment_arm_m"].shape == (3, 7) and g["path_length_m"].dtype == np.float64
    np.testing.assert_allclose(g["moment_arm_m"].ravel(), reference["moment_arms"], rtol=REL_TOL, atol=0)


def test_arm_trial_equals_the_cpp_api(elbow, reference):
    series, summary = armsim.arm_trial(elbow, angle_deg=100, activation=0.7, antagonist_activation=0.05,
                                       hold=1.0, rate=200)
    n = len(series["time_s"])
    assert n == int(round((0.5 + 1.0) * 200)) + 1
    assert all(a.dtype == np.float64 and a.shape == (n,) for a in series.values())
    assert len(summary["mean_forces_N"]) == 7
    np.testing.assert_allclose(series["muscle_torque_Nm"][::20], reference["arm_trial_torque"], rtol=REL_TOL, atol=0)
    assert summary["mean_muscle_torque_Nm"] == pytest.approx(reference["arm_trial_mean_torque"], rel=REL_TOL)


def test_run_study_writes_the_commands_files(tmp_path):
    (tmp_path / "study.yaml").write_text("kind: study\nname: py\nsubjects: 1\nprotocols: [thesis]\n"
                                         "noise_levels: [0.02]\nmethods:\n  - {method: thesis}\n")
    r = armsim.run_study(str(tmp_path / "study.yaml"), threads=1, out=str(tmp_path / "out"))
    assert (r["total"], r["computed"], r["resumed"]) == (1, 1, 0)
    assert (tmp_path / "out" / "results.csv").exists()
    again = armsim.run_study(str(tmp_path / "study.yaml"), threads=1, out=str(tmp_path / "out"))
    assert (again["computed"], again["resumed"]) == (0, 1)


@pytest.mark.parametrize("call, error, message", [
    (lambda m: armsim.Model.load("/no/such/model.yaml"), FileNotFoundError, "/no/such/model.yaml"),
    (lambda m: armsim.Model.load("no_such_model"), ValueError, "no_such_model"),
    (lambda m: m.with_muscle(mass=-1), ValueError, "field 'mass' = -1: expected in (0, 10] (kg)"),
    (lambda m: m.with_muscle(weight=1), ValueError, "unknown muscle parameter 'weight'"),
    (lambda m: m.parameters("triceps"), ValueError, "triceps"),
    (lambda m: armsim.steady_state(m, 0.40, 2.0), ValueError, "field 'activation' = 2: expected in [0, 1]"),
    (lambda m: armsim.muscle_trial(m, rise=-1), ValueError, "rise"),
    (lambda m: armsim.arm_trial(m, angle_deg=400), ValueError, "400"),
    (lambda m: armsim.arm_trial(m, effort="sideways"), ValueError, "expected flexion, extension, supination or pronation"),
    (lambda m: armsim.run_study("/no/such/study.yaml"), FileNotFoundError, "/no/such/study.yaml"),
    (lambda m: armsim.run_study("/no/such/study.yaml", threads=-3), ValueError, "field 'threads' = -3: expected in [0, 1024]"),
    (lambda m: armsim.run_study("/no/such/study.yaml", threads=5000), ValueError, "field 'threads' = 5000"),
])
def test_bad_arguments_raise_with_the_message(thesis, call, error, message):
    with pytest.raises(error) as e:
        call(thesis)
    assert message in str(e.value)


def test_a_trial_releases_the_gil(elbow):
    """While a trial runs in a thread, this thread keeps running Python: between the call's start and
    end, the longest stretch without an iteration of this loop stays well below the call's duration.
    With the GIL held through the call, no iteration falls inside it (checked by building without the
    release: the stretch is then the whole call)."""
    longest, duration = measure_longest_stall(lambda: armsim.arm_trial(elbow, hold=10.0))
    assert longest < 0.5 * duration, (longest, duration)


def test_docstrings_name_units_and_arguments():
    for f in (armsim.steady_state, armsim.muscle_trial, armsim.arm_trial, armsim.run_study, armsim.Model.load):
        assert f.__doc__ and len(f.__doc__) > 80
    assert "path_length" in armsim.steady_state.__doc__ and "force_N" in armsim.steady_state.__doc__


def test_version_is_the_projects():
    # second source: the CMake project's VERSION
    cmake = (pathlib.Path(__file__).resolve().parents[2] / "CMakeLists.txt").read_text()
    assert re.search(r"project\(armsim VERSION ([0-9.]+)", cmake).group(1) == armsim.__version__


def test_arm_trial_takes_a_forearm_posture_and_a_short_hold(elbow):
    twin = armsim.Model.load("twin")
    kw = dict(angle_deg=90, activation=1.0, hold=0.5, rate=200)   # a 0.5 s hold averages the whole hold
    _, neutral = armsim.arm_trial(twin, rotation_deg=0.0, **kw)
    _, default = armsim.arm_trial(twin, **kw)                      # the twin's posture is neutral
    _, pronated = armsim.arm_trial(twin, rotation_deg=-90.0, **kw)
    assert default["mean_muscle_torque_Nm"] == neutral["mean_muscle_torque_Nm"]
    assert pronated["mean_muscle_torque_Nm"] < 0.99 * neutral["mean_muscle_torque_Nm"]
    with pytest.raises(ValueError, match="forearm_rotation_deg"):
        armsim.arm_trial(elbow, rotation_deg=-90.0, **kw)          # the elbow's forearm does not rotate
    # the second axis: a flexion effort's biceps supinates, a supination effort more, a pronation effort pronates
    series, sup = armsim.arm_trial(twin, effort="supination", rotation_deg=-60.0, **kw)
    _, pro = armsim.arm_trial(twin, effort="pronation", rotation_deg=30.0, **kw)
    assert 0 < neutral["mean_forearm_torque_Nm"] < sup["mean_forearm_torque_Nm"]
    assert pro["mean_forearm_torque_Nm"] < 0
    assert series["forearm_torque_Nm"][-1] > 0
    with pytest.raises(ValueError, match="no forearm rotation"):
        armsim.arm_trial(elbow, effort="supination", **kw)


def test_model_pickles_as_what_made_it_for_process_pools(elbow):
    """A Model pickles as its source (a name or an absolute path) and its with_muscle changes; the
    unpickled model has the same parameters and the same trial, and goes through a process pool."""
    import concurrent.futures
    import pickle
    changed = elbow.with_muscle("BIClong", mass=0.31).with_muscle("BRA", slow_units=40, optimal_tendon_length=0.06)
    back = pickle.loads(pickle.dumps(changed))
    for muscle in ("BIClong", "BRA", "TRIlong"):
        assert back.parameters(muscle) == changed.parameters(muscle)
    assert back.parameters("BIClong")["mass"] == 0.31 and back.parameters("BRA")["slow_units"] == 40
    kw = dict(angle_deg=90.0, hold=0.5, rest=0.2, rate=200.0)
    assert armsim.arm_trial(back, **kw)[1]["mean_muscle_torque_Nm"] == armsim.arm_trial(changed, **kw)[1]["mean_muscle_torque_Nm"]
    path = pathlib.Path(__file__).resolve().parents[2] / "assets" / "models" / "thesis.yaml"
    with concurrent.futures.ProcessPoolExecutor(max_workers=2) as pool:
        masses = list(pool.map(_primary_mass, [changed, armsim.Model.load(path)]))
    assert masses == [changed.parameters()["mass"], armsim.Model.load("thesis").parameters()["mass"]]
    with pytest.raises(ValueError, match="another armsim version"):
        armsim.Model.__new__(armsim.Model).__setstate__((99, "thesis", []))


def _primary_mass(model):
    return model.parameters()["mass"]


def test_model_takes_a_path_copies_and_types_its_overrides(elbow):
    import copy
    twin = armsim.Model.load(pathlib.Path(__file__).resolve().parents[2] / "assets" / "models" / "twin.yaml")
    assert twin.muscles == armsim.Model.load("twin").muscles
    twin_copy = copy.deepcopy(twin)
    assert twin_copy.parameters("BIClong") == twin.parameters("BIClong")
    with pytest.raises(TypeError, match="muscle parameter 'mass' = 'heavy': expected a number"):
        elbow.with_muscle(mass="heavy")
    with pytest.raises(TypeError, match="'slow_units' = 2.5: expected a whole number"):
        elbow.with_muscle(slow_units=2.5)


def test_with_muscle_model_swaps_the_equations_and_keeps_f0(thesis):
    # Issue 29: the same muscle as Thelen 2003 and De Groote-Fregly 2016 (OpenSim's Hill-type models).
    # The same F0 = sigma M / (rho L0) (31.8 N/cm^2, 1.06 g/cm^3): at the path where the fibre is near
    # its optimum (P = L0 + L0T) a fully active Hill muscle gives about F0.
    p = thesis.parameters()
    F0 = 31.8e4 * p["mass"] / (1060 * p["optimal_fascicle_length"])
    P = p["optimal_fascicle_length"] + p["optimal_tendon_length"]
    vm = armsim.steady_state(thesis, P, 1.0)
    for name in ("thelen2003", "degroote2016"):
        hill = thesis.with_muscle_model(name)
        s = armsim.steady_state(hill, P, 1.0)
        assert s["force_N"] == pytest.approx(F0, rel=0.02)
        assert s["normalized_fascicle_length"] == pytest.approx(1.0, abs=0.03)
        assert abs(s["force_N"] - vm["force_N"]) > 1.0  # other equations
        t = armsim.muscle_trial(hill, path_length=P, activation=1.0, duration=1.0, rate=10)
        assert t["force_N"][-1] == pytest.approx(s["force_N"], rel=1e-4)  # integration ends at the steady state
    slow = thesis.with_muscle_model("thelen2003", activation_time_constant=0.05)
    fast = thesis.with_muscle_model("thelen2003")
    rise = lambda m: armsim.muscle_trial(m, path_length=P, activation=1.0, duration=0.02, rate=1000)["force_N"][-1]
    assert rise(slow) < rise(fast)
    # Pickles and copies keep the model and its coefficients.
    import pickle
    again = pickle.loads(pickle.dumps(slow))
    assert rise(again) == rise(slow)
    with pytest.raises(ValueError, match="expected one of virtual_muscle, thelen2003, degroote2016"):
        thesis.with_muscle_model("hill")
    with pytest.raises(ValueError, match="no coefficient 'tau'"):
        thesis.with_muscle_model("thelen2003", tau=0.1)


def test_forward_runs_an_osim_model_as_the_command_does(tmp_path):
    """armsim.forward on arm26 with the OpenSim tutorial's controls (a path, then the same controls as a
    dict of arrays): OpenSim's column names, one row per 1/rate s, the same numbers both ways, and the
    elbow flexing; a control column naming no muscle raises ValueError with the column."""
    data = pathlib.Path(__file__).resolve().parents[1] / "data" / "opensim" / "arm26_forward"
    states = armsim.forward("arm26", data / "arm26_controls.sto", final_time=0.2, rate=100)
    assert list(states)[:5] == ["time", "r_shoulder_elev", "r_elbow_flex", "r_shoulder_elev_u", "r_elbow_flex_u"]
    assert "BIClong.activation" in states and "BIClong.fiber_length" in states
    assert states["time"].dtype == np.float64 and states["time"].shape == (21,)
    assert states["r_elbow_flex"][-1] > states["r_elbow_flex"][0] + 0.1  # flexes (rad)
    lines = (data / "arm26_controls.sto").read_text().splitlines()
    start = lines.index("endheader") + 1
    names = lines[start].split("\t")
    rows = np.array([[float(x) for x in line.split()] for line in lines[start + 1:] if line.strip()])
    as_dict = armsim.forward("arm26", {n: rows[:, k] for k, n in enumerate(names)}, final_time=0.2, rate=100)
    for name in states:
        np.testing.assert_array_equal(as_dict[name], states[name])
    with pytest.raises(ValueError) as e:
        armsim.forward("arm26", {"time": np.array([0.0, 1.0]), "BIC": np.array([0.1, 0.1])}, final_time=0.1)
    assert "column 'BIC' names no muscle" in str(e.value)


def test_isometric_trial_of_an_osim_model(tmp_path):
    """armsim.isometric_trial on arm26 (a name, then a pathlib.Path): the elbow locked at 80 deg, a flexion
    effort then an extension effort. Each muscle's torque column is its moment arm times its force, they
    sum to muscle_torque_Nm, the tare is the first sample's torque, the agonists are the muscles pulling
    the effort's way, and each effort turns the elbow its way; a wrong type raises TypeError, a bad value
    ValueError naming the argument."""
    series, summary = armsim.isometric_trial("arm26", coordinate="r_elbow_flex", angle_deg=80, hold=0.5, rate=200)
    assert summary["coordinate"] == "r_elbow_flex" and series["r_elbow_flex_deg"][0] == 80
    assert series["time_s"].shape == (201,)
    total = sum(series[f"torque_{m}_Nm"] for m in summary["muscles"])
    np.testing.assert_allclose(total, series["muscle_torque_Nm"], rtol=0, atol=1e-9)
    for m, r in zip(summary["muscles"], summary["moment_arms_m"]):
        np.testing.assert_allclose(series[f"torque_{m}_Nm"], r * series[f"force_{m}_N"], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(series["tared_torque_Nm"], series["muscle_torque_Nm"] - summary["rest_torque_Nm"],
                               rtol=0, atol=1e-12)
    assert summary["agonists"] == [r > 1e-4 for r in summary["moment_arms_m"]]
    assert summary["mean_tared_torque_Nm"] > 30
    osim = pathlib.Path(os.environ.get("ARMSIM_ASSETS", pathlib.Path(__file__).resolve().parents[2] / "assets"))
    _, extension = armsim.isometric_trial(osim / "models" / "arm26.osim", coordinate="r_elbow_flex", angle_deg=80,
                                          effort="negative", hold=0.5, rate=200)
    assert extension["mean_tared_torque_Nm"] < -20
    assert extension["agonists"] == [r < -1e-4 for r in extension["moment_arms_m"]]
    with pytest.raises(TypeError, match="model: expected a name or a file path"):
        armsim.isometric_trial(3.0)
    with pytest.raises(ValueError, match=re.escape("'angle_deg' = 150: expected in [0, 130] (deg)")):
        armsim.isometric_trial("arm26", coordinate="r_elbow_flex", angle_deg=150)


def test_free_movement_of_an_osim_model():
    """armsim.free_movement on arm26: the elbow free from 20 deg, the flexors at 0.3 from 0.1 s. The angle
    column is the integral of the speed column (trapezoid rule at 1000 Hz, to 0.05 deg: a second method
    through the two outputs), the elbow flexes, the triceps stay unexcited; effort='negative' extends."""
    s = armsim.free_movement("arm26", coordinate="r_elbow_flex", initial_angle_deg=20, activation=0.3, onset=0.1,
                             duration=0.4, rate=1000)
    assert s["time_s"].shape == (401,) and s["r_elbow_flex_deg"][0] == pytest.approx(20, abs=1e-12)
    integral = 20 + np.concatenate(([0.0], np.cumsum(np.diff(s["time_s"]) * 0.5 *
                                                      (s["r_elbow_flex_speed_degps"][1:] + s["r_elbow_flex_speed_degps"][:-1]))))
    np.testing.assert_allclose(s["r_elbow_flex_deg"], integral, rtol=0, atol=0.05)
    assert s["r_elbow_flex_deg"][-1] > 25
    assert s["activation_BIClong"][-1] > 0.25 and s["activation_TRIlong"][-1] < 0.02
    back = armsim.free_movement("arm26", coordinate="r_elbow_flex", initial_angle_deg=90, effort="negative",
                                activation=0.3, onset=0.1, duration=0.3, rate=100)
    assert back["r_elbow_flex_deg"][-1] < 85
    with pytest.raises(ValueError, match="'initial_angle_deg' = 200"):
        armsim.free_movement("arm26", coordinate="r_elbow_flex", initial_angle_deg=200)
    # The command line's default excitation, 1 (`armsim trial --type free --activation`), not 0.5 as before.
    default = armsim.free_movement("arm26", coordinate="r_elbow_flex", duration=0.3, rate=100)
    assert default["excitation"].max() == 1.0


# The key-naming rule (README, Python): a returned key or column holding a quantity with a unit ends in
# that unit; the dimensionless ones below have none. Model.parameters() and identify's "estimate" keep
# the model files' parameter names (what with_muscle takes); a channel's value carries its unit beside it.
UNIT_SUFFIXES = ("_N", "_Nm", "_m", "_mm", "_m3", "_kg", "_s", "_Hz", "_deg", "_degps", "_mps", "_pct",
                 "_N_per_m2", "_kg_per_m3")
DIMENSIONLESS = {
    "activation", "saturated", "normalized_fascicle_length", "active_fraction", "method", "converged", "message",
    "noise", "noise_level", "noise_degrees_of_freedom", "nuisance", "mass_tendon_correlation", "parameters",
    "iterations", "channel_fits", "channel", "n", "chi_square", "p_value", "consistent_with_noise", "worst",
    "worst_residual_sd", "residual_check", "degrees_of_freedom", "subject", "mass_error", "mass_covered",
    "tendon_covered", "voluntary_activation", "co_contraction", "strength_level", "biceps_short_scale",
    "synergist_scale", "mass_bias", "mass_rmse", "mass_coverage", "tendon_coverage", "mass_interval_width",
    "subjects", "effort", "level", "repetition", "muscle", "value", "sd", "clean_value", "unit",
    "output", "total", "computed", "resumed", "failed", "not_converged",
    "journal_dropped", "journal_summary", "files", "muscle_states", "truth", "stop_reason", "evaluations",
    "tendon_length_covered", "mass_sd", "mass_sd_considered", "prior_mass_sd", "flexor_strength_sd",
    "prior_flexor_strength_sd", "max_force_sd", "prior_max_force_sd", "max_force_sd_considered", "parameter_names",
    "mass_correlation", "posterior_sd", "name", "trials", "draws_used", "criterion", "conditions", "protocol_yaml",
    "predicted", "reference", "steps", "repetitions", "coordinate", "muscles", "agonists", "excitation",
    "tendon_length_error", "mass_bias_se", "mass_rmse_se", "mass_coverage_se", "tendon_coverage_se",
    "mass_coverage_prior_passed", "tendon_coverage_prior_passed", "max_force_bias", "max_force_rmse",
    "max_force_coverage", "max_force_error", "max_force_covered", "noise_level_used", "prior_check_p", "prior_flagged",
}   # mass_sd and max_force_sd: of ln M and ln F0; posterior_sd: per parameter_names entry; *_scale: ratios


def _keys(obj, prefix=""):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield prefix + str(k), str(k)
            yield from _keys(v, prefix + str(k) + ".")
    elif isinstance(obj, (list, tuple)):
        for v in obj:
            yield from _keys(v, prefix)


def test_returned_keys_carry_their_units(thesis, elbow, tmp_path):
    twin = armsim.Model.load("twin")
    sim = armsim.Simulation(twin, excitation=0.1)
    sim.advance_to(0.01)
    results = {
        "steady_state": armsim.steady_state(thesis, 0.37),
        "muscle_trial": armsim.muscle_trial(thesis, duration=0.01),
        "arm_trial": armsim.arm_trial(twin, hold=0.2),
        "geometry": elbow.geometry([90]),
        "Simulation.samples": sim.samples(),
        "Simulation.state": sim.state,
        "identify_torque": armsim.identify_torque("measured/thesis_mvc_torque.csv", activation=0.95),
        "validate_elbow": armsim.validate_elbow(subjects=1, noise=[0.02], jobs=1),
        "validate": armsim.validate(thesis, noise=[0.02], methods=["lm"], jobs=1),
        "design_protocol": armsim.design_protocol(draws=2, trials=3, jobs=1),
        "isometric_trial": armsim.isometric_trial("arm26", coordinate="r_elbow_flex", hold=0.1, rate=100),
        "free_movement": armsim.free_movement("arm26", coordinate="r_elbow_flex", duration=0.3, rate=100),
    }
    bad = []
    for name, result in results.items():
        for path, key in _keys(result):
            if (key.startswith(("state_", "excitation_", "active_fraction_", "activation_")) or key.endswith("_scale")
                    or key in DIMENSIONLESS):
                continue
            if not key.endswith(UNIT_SUFFIXES):
                bad.append(f"{name}: {path}")
    assert not bad, "keys without a unit: " + ", ".join(sorted(set(bad)))


def test_the_bounds_table_holds_in_python_as_on_the_command_line(thesis):
    """basics/bound.h's table, through the module: the same bounds and words as the command line and the files
    (tests/cli/test_bad_input.cpp, BoundsTable)."""
    for kw, bound in ((dict(mass=11.0), "(0, 10] (kg)"), (dict(optimal_tendon_length=3.0), "(0, 2] (m)"),
                      (dict(slow_units=101), "[0, 100]")):
        with pytest.raises(ValueError, match=re.escape(bound)):
            thesis.with_muscle(**kw)
    with pytest.raises(ValueError, match=re.escape("[0, 50] (kg)")):
        armsim.Simulation(thesis, hand_load=60)
