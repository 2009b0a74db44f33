"""The module's identification, validation, design, protocol and render functions (issue 12): results
equal the C++ API's (tests/python/reference.cpp) to 1e-12 relative, the report has the command's
keys with numpy arrays, bad arguments raise with the message, files are written where asked."""
import os

import numpy as np
import pytest

import armsim

from conftest import REL_TOL, measure_longest_stall

THESIS_START = {"mass": 0.330, "optimal_tendon_length": 0.22}


@pytest.fixture(scope="module")
def report(thesis, reference):
    data = {"angle_deg": reference["identify_angles_deg"], "force_N": reference["identify_forces"]}
    return armsim.identify(thesis, data, start=THESIS_START)


def test_identify_estimate_intervals_and_correlation_equal_the_cpp_api(report, reference):
    assert report["converged"] and report["stop_reason"] == "converged"
    est = [report["estimate"]["mass"], report["estimate"]["optimal_tendon_length"]]
    np.testing.assert_allclose(est, reference["identify_estimate"], rtol=REL_TOL, atol=0)
    p = report["parameters"]
    intervals = [p[0]["interval"][0], p[0]["interval"][1], p[1]["interval"][0], p[1]["interval"][1]]
    np.testing.assert_allclose(intervals, reference["identify_interval"], rtol=REL_TOL, atol=0)
    corr = report["uncertainty"]["correlation"]
    assert corr.shape == (2, 2) and corr.dtype == np.float64
    assert corr[0, 1] == pytest.approx(reference["identify_correlation"], rel=REL_TOL)
    assert report["model_checks"][1]["rms_residual_N"] == pytest.approx(reference["identify_faithful_check_rms"],
                                                                        rel=REL_TOL)


def test_identify_report_has_the_json_reports_keys_and_arrays(report, reference):
    for key in ("method", "force_model", "stop_reason", "message", "parameters", "uncertainty", "model_checks",
                "iterations", "forward_evaluations", "rms_residual_N", "start_costs_N2"):
        assert key in report
    history = report["history"]
    assert len(history["iteration"]) == reference["identify_history_length"]
    assert {"mass_kg", "optimal_tendon_length_m", "cost_N2"} <= set(history)
    # the history's last row is the estimate; its cost falls from the start
    assert history["mass_kg"][-1] == report["estimate"]["mass"]
    assert history["cost_N2"][-1] < history["cost_N2"][0]
    obs = report["observations"]
    assert obs["residual_N"].shape == (5,)
    np.testing.assert_allclose(obs["model_N"] - obs["measured_N"], obs["residual_N"], rtol=0, atol=1e-9)


def test_identify_reads_a_csv_and_writes_the_commands_report_files(thesis, tmp_path):
    r = armsim.identify(thesis, "measured/thesis_measured.csv", method="ilc-sign-search", out=str(tmp_path))
    assert r["converged"] and r["data_source"].endswith("thesis_measured.csv")
    assert sorted(os.path.basename(f) for f in r["files"]) == ["identification.json", "identification_convergence.png",
                                                               "identification_history.csv"]
    assert all(os.path.getsize(f) > 0 for f in r["files"])
    # the two measured forces are reproduced within the method's 0.1 N tolerance
    assert np.all(np.abs(r["observations"]["residual_N"]) <= 0.1)


def test_identify_torque_runs_every_method_and_equals_the_cpp_api(reference):
    estimates = armsim.identify_torque("measured/thesis_mvc_torque.csv", activation=0.95)
    assert [e["method"] for e in estimates] == ["thesis", "synergist", "synergist-va"]
    np.testing.assert_allclose([e["mass_kg"] for e in estimates], reference["identify_torque_masses"], rtol=REL_TOL)
    for e in estimates:
        lo, hi = e["mass_interval_kg"]
        assert lo <= e["mass_kg"] <= hi
        assert 0 <= e["residual_check"]["p_value"] <= 1
    assert "activation" in " ".join(estimates[1]["nuisance"])


def test_validate_elbow_equals_the_cpp_api(reference):
    rows, summary = armsim.validate_elbow(subjects=2, noise=[0.02])
    np.testing.assert_allclose(rows["mass_kg"], reference["validate_elbow_masses"], rtol=REL_TOL)
    # Out of family: the stronger mismatch population as truth, the default as prior: the same people 1.26x heavier.
    strong, _ = armsim.validate_elbow(subjects=2, noise=[0.02], truth_population="subjects/mismatch/stronger.yaml")
    np.testing.assert_allclose(strong["true_mass_kg"], 1.26 * np.asarray(rows["true_mass_kg"]), rtol=1e-12)
    assert rows["method"][:3] == ["thesis", "synergist", "synergist-va"]
    assert rows["true_mass_kg"].dtype == np.float64 and rows["true_mass_kg"].shape == (6,)
    assert {s["method"] for s in summary} == {"thesis", "synergist", "synergist-va"}


def test_validate_thesis_truth_stays_near_the_truth_without_noise(thesis):
    rows = armsim.validate(thesis, seeds=0, noise=[0.0], methods=["lm"], forward="steady")
    assert rows["method"] == ["lm"] and rows["truth"] == ["thesis"]
    # steady model on the faithful model's tared data: the known bias of a few percent, not zero
    assert abs(rows["mass_error"][0]) < 0.1 and rows["stop_reason"] == ["converged"]


def test_design_protocol_equals_the_cpp_api_and_writes_a_readable_protocol(reference, tmp_path):
    d = armsim.design_protocol(draws=4, trials=6)
    assert d["predicted"]["mass_sd"] == pytest.approx(reference["design_mass_sd"], rel=REL_TOL)
    assert d["reference"]["mass_sd"] == pytest.approx(reference["design_reference_mass_sd"], rel=REL_TOL)
    assert sum(c["repetitions"] for c in d["conditions"]) == 6
    path = tmp_path / "designed.yaml"
    path.write_text(d["protocol_yaml"])
    run = armsim.run_protocol(str(path))
    assert run["kind"] == "torque" and len(run["data"]["torque_Nm"]) == 6


def test_design_across_channels_with_postures_reads_both_axes():
    d = armsim.design_protocol(draws=4, angles=[30, 90, 135], postures=[-60], budget_minutes=60)
    assert "forearm_torque: true" in d["protocol_yaml"]
    assert "volume_scan" in d["protocol_yaml"] or "anthropometry: true" in d["protocol_yaml"]
    p = d["predicted"]
    assert np.isfinite(p["tendon_sd_considered_m"]) and np.isfinite(p["mass_sd_considered"])
    with pytest.raises(ValueError, match="criterion"):
        armsim.design_protocol(draws=4, criterion="best")


def test_run_protocol_torque_equals_the_cpp_api_and_feeds_identify_torque(reference, tmp_path):
    run = armsim.run_protocol("protocols/designed_emg_torque.yaml", out=str(tmp_path / "run"))
    np.testing.assert_allclose(run["data"]["torque_Nm"], reference["torque_protocol_torque"], rtol=REL_TOL)
    assert sorted(os.path.basename(f) for f in run["files"]) == ["protocol.yaml", "torque_angle.png", "torque_data.csv"]
    from_dict = armsim.identify_torque(run["data"])
    from_file = armsim.identify_torque(str(tmp_path / "run" / "torque_data.csv"))
    # the file holds the same numbers to 17 digits: the same estimates
    assert [e["mass_kg"] for e in from_dict] == pytest.approx([e["mass_kg"] for e in from_file], rel=1e-12)


def test_run_protocol_on_an_opensim_model_reads_its_coordinates_torque(tmp_path):
    run = armsim.run_protocol("protocols/arm26_torque.yaml", out=tmp_path / "arm26")
    assert run["subject"] == "OpenSim model arm26, coordinate r_elbow_flex"
    data = run["data"]
    assert len(data["torque_Nm"]) == 14
    # the clean torque is the isometric trial's: flexion MVC at 90 deg through isometric_trial itself
    _, summary = armsim.isometric_trial("arm26", coordinate="r_elbow_flex", angle_deg=90, hold=1.0,
                                        averaging_window=0.5, rate=200)
    at90 = [k for k in range(14) if data["flexion_deg"][k] == 90 and data["effort"][k] == 1 and data["level"][k] == 1]
    assert len(at90) == 2
    for k in at90:
        assert data["clean_torque_Nm"][k] == pytest.approx(summary["mean_tared_torque_Nm"], rel=1e-12)
    assert (tmp_path / "arm26" / "torque_data.csv").exists()


def test_forearm_postures_reach_python_and_feed_identify_torque(tmp_path):
    run = armsim.run_protocol("protocols/forearm_postures.yaml", out=str(tmp_path / "run"))
    rot = np.asarray(run["data"]["rotation_deg"])
    assert len(rot) == 27 and np.isnan(rot).sum() == 15
    assert sorted(set(rot[~np.isnan(rot)])) == [-90.0, 90.0]
    prior = "subjects/default_population.yaml"
    from_dict = armsim.identify_torque(run["data"], population=prior)
    from_file = armsim.identify_torque(str(tmp_path / "run" / "torque_data.csv"), population=prior)
    assert [e["mass_kg"] for e in from_dict] == pytest.approx([e["mass_kg"] for e in from_file], rel=1e-12)
    # dropping the postures changes the synergist fit: the posture is read, not ignored
    neutral = {k: np.asarray(v)[np.isnan(rot)] for k, v in run["data"].items()}
    alone = armsim.identify_torque(neutral, population=prior)
    assert alone[1]["mass_kg"] != pytest.approx(from_dict[1]["mass_kg"], rel=1e-6)


def test_run_protocol_mvc_then_identify_recovers_the_subject(thesis):
    run = armsim.run_protocol("protocols/mvc_force_angle.yaml")
    t = run["trials"]
    assert run["kind"] == "mvc" and len(t["trial"]) == 15 and run["files"] == []
    assert set(run["fits"]) >= {"muscle_force", "force_measured"}
    data = {"angle_deg": t["elbow_angle_deg"], "force_N": t["force_measured_N"], "trial": t["repetition"]}
    r = armsim.identify(thesis, data, forward="corrected")
    truth = thesis.parameters()
    assert r["estimate"]["mass"] == pytest.approx(truth["mass"], rel=0.01)
    assert r["estimate"]["optimal_tendon_length"] == pytest.approx(truth["optimal_tendon_length"], rel=0.01)


def test_render_frame_is_the_cpp_frame_in_rgb(elbow, reference):
    if not reference["frame_rgb_sums"]:
        pytest.skip("built without the renderer")
    series, _ = armsim.arm_trial(elbow, angle_deg=100, activation=0.7, antagonist_activation=0.05, hold=1.0, rate=200)
    frame = armsim.render_frame(elbow, series, 1.0, width=160, height=90)
    assert frame.shape == (90, 160, 3) and frame.dtype == np.uint8
    np.testing.assert_array_equal(frame.reshape(-1, 3).sum(axis=0, dtype=np.int64), reference["frame_rgb_sums"])


def test_render_video_writes_an_mp4_of_the_trials_frames(elbow, reference, tmp_path):
    if not reference["frame_rgb_sums"]:
        pytest.skip("built without the renderer")
    series, _ = armsim.arm_trial(elbow, hold=1.0, rate=200)
    out = tmp_path / "trial.mp4"
    r = armsim.render_video(elbow, series, str(out), fps=10, width=160, height=90)
    duration = series["time_s"][-1] - series["time_s"][0]
    assert r["frames"] == int(np.floor(duration * 10 + 1e-9)) + 1
    assert out.read_bytes()[4:8] == b"ftyp"  # an MP4 container


def test_render_of_an_osim_models_trial(reference, tmp_path):
    """render_frame and render_video with an OpenSim model's name and the series free_movement returns:
    the muscles blue at rest (no red pixels), red once the flexors are fully excited; the video has a
    frame per 1/fps of the trial; the arm scene's colouring by force is refused."""
    if not reference["frame_rgb_sums"]:
        pytest.skip("built without the renderer")
    series = armsim.free_movement("arm26", coordinate="r_elbow_flex", initial_angle_deg=20, activation=1.0, onset=0.1,
                                  duration=0.3, rate=100)
    def red_blue(frame):
        r, b = frame[..., 0].astype(int), frame[..., 2].astype(int)
        return int(np.sum(r > b + 80)), int(np.sum(b > r + 80))
    start = armsim.render_frame("arm26", series, 0.0, width=320, height=240, overlay=False, supersample=1)
    end = armsim.render_frame("arm26", series, 0.3, width=320, height=240, overlay=False, supersample=1)
    assert start.shape == (240, 320, 3) and start.dtype == np.uint8
    assert red_blue(start)[0] == 0 and red_blue(start)[1] > 50
    assert red_blue(end)[0] > 50
    out = tmp_path / "free.mp4"
    r = armsim.render_video("arm26", series, out, fps=20, width=160, height=120)
    assert r["frames"] == 7 and out.read_bytes()[4:8] == b"ftyp"
    with pytest.raises(ValueError, match="coloured by activation"):
        armsim.render_frame("arm26", series, 0.0, color_by="force")


@pytest.mark.parametrize("call, error, message", [
    (lambda m: armsim.identify(m, {"angle_deg": [90.0]}), ValueError, "data: missing column 'force_N'"),
    (lambda m: armsim.identify(m, {"angle_deg": [90.0], "force_N": [1.0], "emg": [0.0]}), ValueError,
     "unknown column 'emg'"),
    (lambda m: armsim.identify(m, {"angle_deg": [90.0, 60.0], "force_N": ["a", "b"]}), ValueError,
     "data: column 'force_N': expected a 1-D sequence of numbers"),
    (lambda m: armsim.identify(m, {"path_cm": [41 + 0j, 37.5], "force_N": [600.0, 458.0]}), ValueError,
     "data: column 'path_cm': expected a 1-D sequence of numbers"),
    (lambda m: armsim.identify(m, "measured/thesis_measured.csv", force_sd=float("nan")), ValueError,
     "force_sd = nan: expected a finite number or None"),
    (lambda m: armsim.identify(m, 3.0), ValueError, "data: expected a CSV path or a dict"),
    (lambda m: armsim.identify_torque("measured/thesis_mvc_torque.csv", population=3), ValueError,
     "population: expected a file path"),
    (lambda m: armsim.validate_elbow(protocol="protocols/designed_emg_torque.yaml", repetitions=7), ValueError,
     "protocol replaces angles and repetitions"),
    (lambda m: armsim.validate_elbow(repetitions=0), ValueError, "field 'repetitions' = 0"),
    (lambda m: armsim.identify(m, {"angle_deg": [90.0, 60.0], "force_N": [1.0]}), ValueError,
     "column 'force_N' has 1 values: expected 2"),
    (lambda m: armsim.identify(m, {"angle_deg": [90.0, 200.0], "force_N": [300.0, 400.0]}), ValueError,
     "data row 2: column 'angle_deg' = 200"),
    (lambda m: armsim.identify(m, "/no/such/data.csv"), FileNotFoundError, "/no/such/data.csv"),
    (lambda m: armsim.identify(m, "measured/thesis_measured.csv", method="newton"), ValueError, "newton"),
    (lambda m: armsim.identify(m, "measured/thesis_measured.csv", bounds={"slow_fraction": (0, 1)}), ValueError,
     "bounds 'slow_fraction': not a free parameter"),
    (lambda m: armsim.identify(m, "measured/thesis_measured.csv", forward="exact"), ValueError,
     "forward model 'exact': expected steady, faithful or corrected"),
    (lambda m: armsim.identify(m, "measured/thesis_measured.csv", forward="faithful", hold=-1), ValueError, "hold"),
    (lambda m: armsim.identify_torque("measured/thesis_mvc_torque.csv", noise_level=2.0), ValueError,
     "field 'noise_level' = 2"),
    (lambda m: armsim.identify_torque({"flexion_deg": [90.0]}), ValueError, "missing column 'torque_Nm'"),
    (lambda m: armsim.identify_torque("measured/thesis_mvc_torque.csv", activation=0.0), ValueError,
     "field 'activation' = 0: expected in (0, 1]"),
    (lambda m: armsim.validate_elbow(subjects=0), ValueError, "field 'subjects' = 0"),
    (lambda m: armsim.validate_elbow(population="/no/such/population.yaml"), FileNotFoundError, "population.yaml"),
    (lambda m: armsim.design_protocol(trials=0), ValueError, "trials"),
    (lambda m: armsim.run_protocol("/no/such/protocol.yaml"), FileNotFoundError, "/no/such/protocol.yaml"),
    (lambda m: armsim.render_frame(m, {"time_s": [0.0]}, 0.0), ValueError, "series"),
    (lambda m: armsim.render_frame(m, armsim.arm_trial(m, hold=0.2, rate=100, averaging_window=0.1)[0], 5.0),
     ValueError, "field 'time' = 5: expected in [0, 0.7] (s, within the trial)"),
])
def test_bad_arguments_raise_with_the_message(thesis, call, error, message):
    with pytest.raises(error) as e:
        call(thesis)
    assert message in str(e.value)


def test_a_bad_codec_is_refused_before_a_file_is_written(thesis, tmp_path):
    series = armsim.arm_trial(thesis, hold=0.2, rate=100, averaging_window=0.1)[0]
    with pytest.raises(ValueError, match="vp9"):
        armsim.render_video(thesis, series, str(tmp_path / "x.mp4"), codec="vp9")
    assert list(tmp_path.iterdir()) == []


def test_any_mapping_of_columns_is_data_and_a_skipped_method_warns(thesis, reference):
    import types
    data = types.MappingProxyType({"angle_deg": reference["identify_angles_deg"], "force_N": reference["identify_forces"]})
    assert armsim.identify(thesis, data, start=THESIS_START)["estimate"]["mass"] == pytest.approx(
        reference["identify_estimate"][0], rel=REL_TOL)
    one_angle = {"flexion_deg": [90.0, 90.0, 90.0], "torque_Nm": [40.0, 41.0, 39.5]}
    with pytest.warns(UserWarning, match="thesis method: skipped"):
        estimates = armsim.identify_torque(one_angle)
    assert [e["method"] for e in estimates] == ["synergist"]


@pytest.mark.parametrize("name, call", [
    ("identify (corrected)", lambda m: armsim.identify(m, "measured/thesis_measured.csv", forward="corrected")),
    ("validate_elbow", lambda m: armsim.validate_elbow(subjects=2, noise=[0.02], jobs=1)),
    ("run_protocol", lambda m: armsim.run_protocol("protocols/mvc_force_angle.yaml", jobs=1)),
])
def test_long_calls_release_the_gil(thesis, name, call):
    """As test_a_trial_releases_the_gil: a Python loop keeps running while the call works in a thread."""
    longest, duration = measure_longest_stall(lambda: call(thesis))
    assert longest < 0.5 * duration, (name, longest, duration)


def test_every_public_function_has_a_useful_docstring():
    for name in armsim.__all__:
        doc = getattr(armsim, name).__doc__
        assert doc and len(doc) > 150, name
    assert "mass_interval" in armsim.identify_torque.__doc__ and "forward" in armsim.identify.__doc__


def _stub_functions():
    import ast
    package = os.path.dirname(armsim.__file__)
    funcs = {}
    for stub in ("_armsim.pyi", "__init__.pyi"):
        with open(os.path.join(package, stub)) as f:
            for node in ast.parse(f.read()).body:
                if isinstance(node, ast.FunctionDef):
                    funcs[node.name] = [a.arg for a in node.args.args]
                elif isinstance(node, ast.ClassDef):   # Class.member: its methods and properties
                    for member in node.body:
                        if isinstance(member, ast.FunctionDef):
                            funcs[node.name + "." + member.name] = [a.arg for a in member.args.args + member.args.kwonlyargs]
    return funcs


def test_type_stubs_name_every_public_member_of_the_classes():
    """Every public method and property of Model and Simulation is in the stubs (with the method's
    argument names as pybind11 reports them)."""
    import re
    stubs = _stub_functions()
    for cls in (armsim.Model, armsim.Simulation):
        for name, member in vars(cls).items():
            if name.startswith("_"):
                continue
            key = cls.__name__ + "." + name
            assert key in stubs, key
            doc = getattr(member, "__doc__", "") or ""
            if callable(member) and doc.startswith(name + "("):
                signature = doc.splitlines()[0]
                names = re.findall(r"(\w+): ", signature[signature.index("(") + 1:signature.rindex(")")])
                assert stubs[key] == names, (key, stubs[key], names)


def test_type_stubs_name_every_public_function_with_its_arguments():
    """The stubs editors complete from (_armsim.pyi, __init__.pyi) list every public function with the
    argument names the functions take (pybind11's signature line, or the Python signature)."""
    import inspect
    import re
    stubs = _stub_functions()
    for name in armsim.__all__:
        if name in ("Model", "Simulation", "__version__"):   # classes and a string, not functions
            continue
        f = getattr(armsim, name)
        assert name in stubs, name
        if inspect.isfunction(f):
            names = list(inspect.signature(f).parameters)
        else:
            signature = f.__doc__.splitlines()[0]
            names = re.findall(r"(\w+): ", signature[signature.index("(") + 1:signature.rindex(")")])
        assert stubs[name] == names, (name, stubs[name], names)


def _run_cli(*args):
    import subprocess
    if "ARMSIM_EXE" not in os.environ:
        pytest.skip("ARMSIM_EXE (the armsim command) not set: run through ctest")
    return subprocess.run([os.environ["ARMSIM_EXE"], *args], check=True, capture_output=True, text=True)


def test_identify_and_a_torque_protocol_give_the_commands_numbers(thesis, tmp_path):
    """The same inputs through the command and through the module: the same estimate (the JSON report
    holds 17 digits) and the same torque data (the CSV holds 17 significant digits)."""
    import json
    _run_cli("identify", "measured/thesis_measured.csv", "--method", "lm", "--out", str(tmp_path / "id"))
    with open(tmp_path / "id" / "identification.json") as f:
        cli = json.load(f)
    py = armsim.identify(thesis, "measured/thesis_measured.csv")
    assert [p["value"] for p in cli["parameters"]] == [p["value"] for p in py["parameters"]]
    assert cli["model_checks"][1]["rms_residual_N"] == py["model_checks"][1]["rms_residual_N"]

    _run_cli("protocol", "protocols/designed_emg_torque.yaml", "--out", str(tmp_path / "tp"))
    cli_data = armsim.read_torque_data(str(tmp_path / "tp" / "torque_data.csv"))
    py_data = armsim.run_protocol("protocols/designed_emg_torque.yaml")["data"]
    np.testing.assert_allclose(cli_data["torque_Nm"], py_data["torque_Nm"], rtol=1e-15, atol=0)


def test_recommended_protocol_channels_feed_identify_torque(tmp_path):
    run = armsim.run_protocol("protocols/recommended.yaml", out=str(tmp_path / "run"))
    names = sorted(os.path.basename(f) for f in run["files"])
    assert "channel_data.csv" in names and "fascicle_length.png" in names
    assert set(run["channels"]["channel"]) == {"fascicle_length", "emg", "volume", "upper_arm_length"}
    estimates = armsim.identify_torque(str(tmp_path / "run" / "torque_data.csv"),
                                       channels=str(tmp_path / "run" / "channel_data.csv"), activation=0.93)
    fit = [e for e in estimates if e["method"] == "channels"]
    assert len(fit) == 1 and fit[0]["converged"]
    lo, hi = fit[0]["max_force_interval_N"]
    assert lo < fit[0]["max_force_N"] < hi
    assert [f["channel"] for f in fit[0]["channel_fits"]][:2] == ["torque", "fascicle_length"]
    # the channels narrow the mass interval of the same torques
    width = {e["method"]: e["mass_interval_kg"][1] - e["mass_interval_kg"][0] for e in estimates}
    assert width["channels"] < 0.8 * width["synergist-va"]
