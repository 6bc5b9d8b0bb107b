"""The Python module against the CLI: the same inputs give the same files, hostile input is a
cablecal.InputError with the CLI's message, long calls release the GIL and honour Ctrl-C.

Run by ctest (tests/CMakeLists.txt) with PYTHONPATH=build/python, CABLECAL_CLI=build/cablecal
and CABLECAL_SOURCE_DIR set. Robots: the asymmetric file, the 3- and 4-cable files, and a robot
built here as a dict (exit points at different heights, centre of mass off the bar) - never
only the built-in one.
"""
import os
import json
import signal
import subprocess
import threading
import time
import warnings

import cablecal  # before numpy: cablecal's reference BLAS is then the one numpy shares (README)
import numpy as np
import pytest

SOURCE = os.environ.get("CABLECAL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
CLI = os.environ.get("CABLECAL_CLI", os.path.join(SOURCE, "build", "cablecal"))
ROBOTS = os.path.join(SOURCE, "robots")


def robot_file(name):
    return os.path.join(ROBOTS, name + ".yaml")


def cli(*args):
    """Runs the CLI; returns its stdout, failing the test on a non-zero exit."""
    done = subprocess.run([CLI, *args], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


def data_lines(path):
    """A CLI file without its provenance comment lines (version, commit, command line)."""
    with open(path) as f:
        return "".join(line for line in f if not line.startswith("#"))


def yaml_without_provenance(text):
    """A result YAML's lines but its `cablecal:` (version, commit), `command:` and wall-time lines."""
    return [l for l in text.splitlines() if not l.startswith(("cablecal:", "command:", "#", "wall_time_s:"))]


def handmade_robot_dict():
    """An asymmetric 2-cable robot written here: exits at different heights, offset mass."""
    d = cablecal.Robot.builtin().to_dict()
    d["name"] = "handmade"
    d["cables"][0]["exit"] = [0.0, 2.4]
    d["cables"][1]["exit"] = [d["frame"]["width"], 2.1]
    d["platform"]["com"] = [0.04, -0.03]
    return d


# ---- Robots -------------------------------------------------------------------------------------


def test_builtin_and_files_load():
    assert cablecal.Robot.builtin().name == "wang2022"
    for name, cables in [("asymmetric", 2), ("planar3_suspended", 3), ("planar4_fully_constrained", 4)]:
        r = cablecal.Robot.load(robot_file(name))
        assert r.num_cables == cables
        assert r.geometry.shape == (3 * cables,)
        assert len(r.geometry_names) == 3 * cables


@pytest.mark.parametrize("name", ["asymmetric", "planar3_suspended", "planar4_fully_constrained"])
def test_dict_round_trip_keeps_the_robot(name):
    r = cablecal.Robot.load(robot_file(name))
    back = cablecal.Robot.from_dict(r.to_dict())
    assert back.to_yaml() == r.to_yaml()
    np.testing.assert_array_equal(back.geometry, r.geometry)


def test_handmade_dict_robot_carries_the_dicts_values():
    # The values handmade_robot_dict sets, written out here: the robot must carry them, not the
    # built-in robot's it was copied from (2.8 m exits, a centred mass).
    d = handmade_robot_dict()
    r = cablecal.Robot.from_dict(d)
    assert r.name == "handmade"
    g = dict(zip(r.geometry_names, r.geometry))
    assert (g["a1x"], g["a1z"], g["a2x"], g["a2z"]) == (0.0, 2.4, 5.209, 2.1)
    assert r.to_dict()["platform"]["com"] == [0.04, -0.03]
    # Everything else as in the dict: the loader's own reading of it, back as a dict.
    assert r.to_dict() == d


def test_misspelt_key_is_the_loaders_message():
    d = handmade_robot_dict()
    d["platform"]["mas"] = d["platform"].pop("mass")
    with pytest.raises(cablecal.InputError) as e:
        cablecal.Robot.from_dict(d)
    assert "mas" in str(e.value)
    assert isinstance(e.value, ValueError)


@pytest.mark.parametrize(
    "bad",
    [
        "not a dict",
        {"name": "x"},  # missing keys
        {**handmade_robot_dict(), "gravity": float("nan")},
        {**handmade_robot_dict(), "gravity": "9.81 m/s^2"},
        {**handmade_robot_dict(), "cables": [object()]},
        {**handmade_robot_dict(), 3: "int key"},
    ],
)
def test_bad_robot_dicts_raise_input_error(bad):
    with pytest.raises(cablecal.InputError):
        cablecal.Robot.from_dict(bad)


def test_missing_file_and_unknown_builtin():
    with pytest.raises(cablecal.InputError, match="no_such.yaml"):
        cablecal.Robot.load("/nonexistent/no_such.yaml")
    with pytest.raises(cablecal.InputError, match="no built-in robot"):
        cablecal.Robot.builtin("nope")


# ---- The CLI's files from the same inputs ------------------------------------------------------


@pytest.mark.parametrize("name", ["asymmetric", "planar3_suspended"])
def test_sample_equals_cli(tmp_path, name):
    robot = cablecal.Robot.load(robot_file(name))
    plan = cablecal.sample(robot, 9, seed=5)
    assert plan.poses.shape == (9, 3)
    assert plan.tensions.shape == (9, robot.num_cables)
    out = tmp_path / "plan.csv"
    cli("sample", "--robot", robot_file(name), "--poses", "9", "--seed", "5", "--out", str(out))
    assert plan.to_csv() == data_lines(out)


def test_workspace_equals_cli(tmp_path):
    robot = cablecal.Robot.load(robot_file("asymmetric"))
    ws = cablecal.workspace(robot, step=0.1)
    out = tmp_path / "ws.csv"
    cli("workspace", "--robot", robot_file("asymmetric"), "--step", "0.1", "--out", str(out))
    assert ws["csv"] == data_lines(out)
    assert ws["feasible"].dtype == bool and ws["feasible"].any()
    assert ws["tensions"].shape == (len(ws["x"]), 2)
    assert np.isclose(ws["area_m2"], ws["feasible"].sum() * 0.01)


def test_design_simulate_identify_equal_cli(tmp_path):
    path = robot_file("asymmetric")
    robot = cablecal.Robot.load(path)
    design = cablecal.design(robot, 7, starts=2, random_sets=5, seed=3)
    plan_csv, summary = tmp_path / "plan.csv", tmp_path / "summary.yaml"
    cli("design", "--robot", path, "--poses", "7", "--starts", "2", "--random-sets", "5", "--seed", "3",
        "--out", str(plan_csv), "--summary", str(summary))
    assert design.plan.to_csv() == data_lines(plan_csv)
    assert yaml_without_provenance(design.to_yaml()) == yaml_without_provenance(open(summary).read())
    assert design.best_start >= 0 and design.converged_starts >= 1

    experiment = cablecal.simulate(robot, design.plan, geometry_sigma=0.01, seed=4)
    meas_csv, truth_yaml = tmp_path / "meas.csv", tmp_path / "truth.yaml"
    cli("simulate", "--robot", path, "--plan", str(plan_csv), "--geometry-sigma", "0.01", "--seed", "4",
        "--out", str(meas_csv), "--truth-out", str(truth_yaml))
    assert experiment.measurements.to_csv() == data_lines(meas_csv)

    result = cablecal.identify(robot, experiment.measurements)
    result_yaml = tmp_path / "result.yaml"
    cli("identify", "--robot", path, "--measurements", str(meas_csv), "--out", str(result_yaml))
    assert yaml_without_provenance(result.to_yaml()) == yaml_without_provenance(open(result_yaml).read())
    assert result.status == "converged"
    # The estimate is within 4 predicted sigma of the truth on every identified parameter.
    truth = experiment.truth.geometry
    held = result.std == 0
    assert held.sum() == 1  # a1x, the gauge
    z = np.abs(result.geometry - truth)[~held] / result.std[~held]
    assert z.max() < 4.0, z
    cov = result.covariance
    assert cov.shape == (6, 6)
    np.testing.assert_allclose(np.sqrt(np.diag(cov)), result.std, rtol=1e-12)


def test_design_warns_where_the_cli_does(tmp_path):
    """A 3-cable robot whose robust poses lose to random ones (found by a new user): the CLI's
    warning on stderr is the module's UserWarning, with the option spelt the Python way."""
    d = {
        "name": "lab3", "gravity": 9.81, "frame": {"width": 2.5, "height": 1.8},
        "platform": {"mass": 2.0, "com": [0.03, -0.05], "anchors": [[-0.3, 0.0], [0.05, 0.2], [0.3, -0.02]]},
        "cables": [{"exit": [0.0, 1.7], "pulley_radius": 0.02, "side": "left"},
                   {"exit": [0.8, 1.8], "pulley_radius": 0.025, "side": "left"},
                   {"exit": [2.5, 1.6], "pulley_radius": 0.02, "side": "right"}],
        "tension": {"min": 1.0, "max": 90.0},
        "limits": {"theta_max_deg": 40, "laser_range": 2.0, "margin": 0.05},
        "home": [1.25, 0.9], "home_theta_deg": 10,
        "sensors": {"laser": {"accuracy": 0.006, "repeatability": 0.0015},
                    "inclinometer": {"accuracy_deg": 0.1, "repeatability_deg": 0.05},
                    "encoder": {"sigma": 0.00005}},
    }
    robot = cablecal.Robot.from_dict(d)
    with pytest.warns(UserWarning, match="no better than the median random set.*smaller geometry_sigma"):
        design = cablecal.design(robot, 12, starts=4)
    assert design.criteria["a_trace_covariance_m2"] >= design.random_median["a_trace_covariance_m2"]
    path = tmp_path / "lab3.yaml"
    path.write_text(robot.to_yaml())
    done = subprocess.run([CLI, "design", "--robot", str(path), "--poses", "12", "--starts", "4",
                           "--out", str(tmp_path / "p.csv")], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "warning: the designed set is no better" in done.stderr
    assert "smaller --geometry-sigma" in done.stderr


def test_design_with_a_prior_equals_cli(tmp_path):
    path = robot_file("planar3_suspended")
    robot = cablecal.Robot.load(path)
    exp = cablecal.simulate(robot, cablecal.sample(robot, 8, seed=3), geometry_sigma=0.005, seed=5)
    result_yaml = tmp_path / "result.yaml"
    result_yaml.write_text(cablecal.identify(robot, exp.measurements).to_yaml())
    design = cablecal.design(robot, 5, starts=2, random_sets=3, prior=result_yaml)
    plan_csv = tmp_path / "plan.csv"
    cli("design", "--robot", path, "--poses", "5", "--starts", "2", "--random-sets", "3", "--prior", str(result_yaml),
        "--out", str(plan_csv))
    assert design.plan.to_csv() == data_lines(plan_csv)
    with pytest.raises(cablecal.InputError):
        cablecal.design(robot, 5, prior=tmp_path / "missing.yaml")


def test_measurements_from_arrays_equal_the_file(tmp_path):
    path = robot_file("planar3_suspended")
    robot = cablecal.Robot.load(path)
    plan = cablecal.sample(robot, 8, seed=2)
    exp = cablecal.simulate(robot, plan, seed=9)
    m = exp.measurements
    again = cablecal.Measurements(robot, m.dl, m.z, m.theta, pose_ids=m.pose_ids)
    assert again.to_csv() == m.to_csv()
    r1 = cablecal.identify(robot, m)
    r2 = cablecal.identify(robot, again)
    np.testing.assert_array_equal(r1.geometry, r2.geometry)
    calibrated = cablecal.calibrated_robot(robot, r1)
    np.testing.assert_array_equal(calibrated.geometry, r1.geometry)


def test_a_labs_log_is_read_by_column_name(tmp_path):
    robot = cablecal.Robot.load(robot_file("asymmetric"))
    m = cablecal.simulate(robot, cablecal.sample(robot, 9, seed=1), seed=2).measurements
    lines = [l for l in m.to_csv().splitlines() if l]
    rows = [l.split(",") for l in lines]
    log = tmp_path / "log.csv"
    log.write_text("\n".join(";".join([("time" if k == 0 else str(k)), r[0], r[4], r[3], r[1], r[2]])
                             for k, r in enumerate(rows)) + "\n")
    with pytest.warns(UserWarning, match="ignoring columns 'time'"):
        again = cablecal.Measurements.load(robot, log, delimiter=";")
    assert again.to_csv() == m.to_csv()
    with pytest.raises(cablecal.InputError, match="another separator"):
        cablecal.Measurements.load(robot, log)


def test_a_labs_log_gets_the_likely_cause_of_its_mistakes(tmp_path):
    robot = cablecal.Robot.load(robot_file("asymmetric"))
    m = cablecal.simulate(robot, cablecal.sample(robot, 9, seed=1), seed=2).measurements
    header, *rows = [l for l in m.to_csv().splitlines() if l]
    log = tmp_path / "log.csv"
    log.write_text("\n".join([header.replace("pose", "Pose")] + rows) + "\n")
    with pytest.raises(cablecal.InputError, match="did you mean 'pose' for 'Pose'"):
        cablecal.Measurements.load(robot, log)
    log.write_text("\n".join([header.replace("theta", "theta_deg")] + rows) + "\n")
    with pytest.warns(UserWarning, match="column 'theta_deg' ignored: theta is read from a column 'theta' in rad"):
        cablecal.Measurements.load(robot, log)
    log.write_text("\n".join([header] + rows + [rows[0]]) + "\n")
    with pytest.warns(UserWarning, match=r"log.csv:11: pose 1 read again after other poses \(first at .*log.csv:2\)"):
        assert len(cablecal.Measurements.load(robot, log)) == 10


def test_validate_equals_cli_and_the_calibration_wins(tmp_path):
    """Identified on one experiment, validated on another of the same true robot: the module's
    CSV and summary are the CLI's, and the calibrated robot predicts z better than the nominal."""
    path = robot_file("asymmetric")
    robot = cablecal.Robot.load(path)
    first = cablecal.simulate(robot, cablecal.sample(robot, 14, seed=2), geometry_sigma=0.015, seed=5)
    truth = first.truth
    holdout = cablecal.simulate(robot, cablecal.sample(robot, 12, seed=3), truth=truth, seed=6).measurements
    calibrated = cablecal.calibrated_robot(robot, cablecal.identify(robot, first.measurements))
    v = cablecal.validate(calibrated, holdout, nominal=robot)
    assert set(v.robots) == {"calibrated", "nominal"}
    cal, nom = v.robots["calibrated"], v.robots["nominal"]
    assert cal["poses"].shape == (12, 3)
    np.testing.assert_array_equal(cal["z_error"], cal["poses"][:, 1] - v.z_measured)
    np.testing.assert_array_equal(nom["theta_error"], nom["poses"][:, 2] - v.theta_measured)
    assert v.pose_ids == holdout.pose_ids
    assert np.isclose(cal["z_rms"], np.sqrt(np.mean(cal["z_error"] ** 2)), rtol=1e-12)
    assert v.ratio["z_rms"] == nom["z_rms"] / cal["z_rms"]
    assert v.ratio["z_rms"] >= 3.0, v.ratio

    # The CLI on the same files.
    cal_yaml, meas_csv = tmp_path / "cal.yaml", tmp_path / "holdout.csv"
    cal_yaml.write_text(calibrated.to_yaml())
    meas_csv.write_text(holdout.to_csv())
    out, summary = tmp_path / "v.csv", tmp_path / "v.yaml"
    cli("validate", "--robot", str(cal_yaml), "--nominal", path, "--measurements", str(meas_csv),
        "--out", str(out), "--summary", str(summary))
    assert v.to_csv() == data_lines(out)
    # The robot files' names differ: the module's calibrated robot was not loaded from cal.yaml.
    ours = [l for l in yaml_without_provenance(v.to_yaml()) if "file:" not in l]
    theirs = [l for l in yaml_without_provenance(summary.read_text()) if "file:" not in l]
    assert ours == theirs

    alone = cablecal.validate(truth, holdout)
    assert alone.ratio is None and set(alone.robots) == {"calibrated"}


def test_validate_without_an_inclinometer_equals_cli(tmp_path):
    path = robot_file("planar3_suspended")
    robot = cablecal.Robot.load(path)
    m = cablecal.simulate(robot, cablecal.sample(robot, 8, seed=3), seed=4).measurements
    no_theta = cablecal.Measurements(robot, m.dl, m.z, None, pose_ids=m.pose_ids)
    v = cablecal.validate(robot, no_theta, nominal=robot)
    assert v.theta_measured is None and v.not_compared == "no 'theta' column (inclinometer)"
    cal = v.robots["calibrated"]
    assert cal["theta_error"] is None and cal["theta_rms"] is None and cal["theta_max_abs"] is None
    assert cal["z_rms"] < 0.02 and cal["poses"].shape == (8, 3)
    assert v.ratio == {"z_rms": 1.0, "theta_rms": None}  # the same robot twice
    csv, out = tmp_path / "m.csv", tmp_path / "v.csv"
    csv.write_text(no_theta.to_csv())
    cli("validate", "--robot", path, "--nominal", path, "--measurements", str(csv), "--out", str(out))
    assert v.to_csv() == data_lines(out)
    assert "theta_measured_rad" not in v.to_csv()
    with pytest.raises(cablecal.InputError, match="nothing to compare the predictions with"):
        cablecal.validate(robot, cablecal.Measurements(robot, m.dl, None, None))


def test_validate_corrects_for_systematic_errors_as_the_cli(tmp_path):
    d = cablecal.Robot.load(robot_file("asymmetric")).to_dict()
    d["sensors"]["laser"]["offset"] = 0.03
    robot = cablecal.Robot.from_dict(d)
    m = cablecal.simulate(robot, cablecal.sample(robot, 10, seed=6), seed=7, systematic_errors=True).measurements
    v = cablecal.validate(robot, m)
    assert v.robots["calibrated"]["z_rms"] < 0.005  # the laser's noise: the 30 mm offset corrected
    path, csv, summary = tmp_path / "robot.yaml", tmp_path / "m.csv", tmp_path / "v.yaml"
    path.write_text(robot.to_yaml())
    csv.write_text(m.to_csv())
    cli("validate", "--robot", str(path), "--measurements", str(csv), "--summary", str(summary), "--out",
        str(tmp_path / "v.csv"))
    ours = [l for l in yaml_without_provenance(v.to_yaml()) if "file:" not in l]
    assert ours == [l for l in yaml_without_provenance(summary.read_text()) if "file:" not in l]
    assert any(l.startswith("sensor_correction:") for l in ours)


def test_validate_refuses_what_it_cannot_compare():
    r2 = cablecal.Robot.load(robot_file("asymmetric"))
    r3 = cablecal.Robot.load(robot_file("planar3_suspended"))
    m2 = cablecal.simulate(r2, cablecal.sample(r2, 4, seed=1), seed=2).measurements
    m3 = cablecal.simulate(r3, cablecal.sample(r3, 4, seed=1), seed=2).measurements
    slack = cablecal.Measurements(r2, np.vstack([m2.dl, [3.0, 0.0]]), np.append(m2.z, 1.2), np.append(m2.theta, 0.0))
    for call, message in [
        (lambda: cablecal.validate(r2, slack), "measurements: pose 5: the calibrated robot .* cannot hold"),
        (lambda: cablecal.validate(r2, m3), "another number of cables"),
        (lambda: cablecal.validate(r2, m2, nominal=r3), "the nominal robot has 3 cables"),
        (lambda: cablecal.validate(r2, m2, nominal=robot_file("asymmetric")), "expected a cablecal.Robot"),
        (lambda: cablecal.validate(r2.to_dict(), m2), "expected a cablecal.Robot"),
        (lambda: cablecal.validate(r2, m2.dl), "expected a cablecal.Measurements"),
    ]:
        with pytest.raises(cablecal.InputError, match=message):
            call()


def test_validate_skip_infeasible_leaves_out_what_a_robot_cannot_hold():
    r2 = cablecal.Robot.load(robot_file("asymmetric"))
    m2 = cablecal.simulate(r2, cablecal.sample(r2, 4, seed=1), seed=2).measurements
    slack = cablecal.Measurements(r2, np.vstack([m2.dl, [3.0, 0.0]]), np.append(m2.z, 1.2), np.append(m2.theta, 0.0))
    with pytest.warns(UserWarning, match="skipped 1 of 5 readings a robot cannot hold"):
        v = cablecal.validate(r2, slack, skip_infeasible=True)
    assert [pose for pose, _ in v.skipped] == [5]
    assert "the calibrated robot" in v.skipped[0][1] and "cannot hold" in v.skipped[0][1]
    assert v.to_csv() == cablecal.validate(r2, m2).to_csv()
    assert "skipped: 1" in v.to_yaml()
    assert cablecal.validate(r2, m2).skipped == []
    only = cablecal.Measurements(r2, np.array([[3.0, 0.0]]), np.array([1.2]), np.array([0.0]))
    with pytest.raises(cablecal.InputError, match="no reading is left to validate on"):
        cablecal.validate(r2, only, skip_infeasible=True)
    with pytest.raises(cablecal.InputError, match="skip_infeasible: expected True or False"):
        cablecal.validate(r2, m2, skip_infeasible="yes")


def test_simulate_skip_infeasible_equals_the_cli(tmp_path):
    # The CLI test's case: seed 8 draws a true robot that settles outside its workspace at some
    # of these poses.
    robot = cablecal.Robot.builtin("wang2022")
    plan = cablecal.sample(robot, 10, seed=8)
    with pytest.raises(cablecal.InputError, match="settles outside its workspace"):
        cablecal.simulate(robot, plan, geometry_sigma=0.005, seed=8)
    with pytest.warns(UserWarning, match="poses the true robot cannot hold"):
        exp = cablecal.simulate(robot, plan, geometry_sigma=0.005, seed=8, skip_infeasible=True)
    assert exp.skipped and all("settles outside its workspace" in why for _, why in exp.skipped)
    assert len(exp.measurements) + len(exp.skipped) == 10
    assert not set(exp.measurements.pose_ids) & {pose for pose, _ in exp.skipped}
    plan_csv, meas = tmp_path / "plan.csv", tmp_path / "m.csv"
    plan_csv.write_text(plan.to_csv())
    cli("simulate", "--plan", str(plan_csv), "--geometry-sigma", "0.005", "--seed", "8", "--skip-infeasible",
        "--out", str(meas), "-q")
    assert exp.measurements.to_csv() == data_lines(meas)


def test_repeated_readings_and_a_missing_inclinometer(tmp_path):
    robot = cablecal.Robot.load(robot_file("planar4_fully_constrained"))
    plan = cablecal.sample(robot, 12, seed=4)
    m = cablecal.simulate(robot, plan, geometry_sigma=0.01, seed=5).measurements
    twice = cablecal.Measurements(robot, np.vstack([m.dl, m.dl]), np.concatenate([m.z, m.z]), None,
                                  pose_ids=list(m.pose_ids) * 2)
    assert twice.theta is None and len(twice) == 24
    r = cablecal.identify(robot, twice)
    assert r.missing_sensors == ["inclinometer"]
    assert r.pose_ids == list(range(1, 13)) and r.poses.shape == (12, 3)
    assert len(r.readings) == 24 and r.readings[0]["inclinometer_sigmas"] is None
    csv = tmp_path / "m.csv"
    csv.write_text(twice.to_csv())
    assert twice.to_csv().splitlines()[0] == "pose,dl1,dl2,dl3,dl4,z"
    result = tmp_path / "r.yaml"
    cli("identify", "--robot", robot_file("planar4_fully_constrained"), "--measurements", str(csv), "--out", str(result))
    assert yaml_without_provenance(r.to_yaml()) == yaml_without_provenance(open(result).read())


def test_a_gross_laser_reading_is_named_and_rejected_by_cauchy():
    robot = cablecal.Robot.load(robot_file("asymmetric"))
    for seed in range(21, 60):  # a random plan the true robot can run (some hold a pose it cannot)
        try:
            exp = cablecal.simulate(robot, cablecal.sample(robot, 20, seed=seed), geometry_sigma=0.01, seed=seed)
            break
        except cablecal.InputError:
            continue
    m = exp.measurements
    z = m.z.copy()
    z[6] += 0.3
    bad = cablecal.Measurements(robot, m.dl, z, m.theta)
    with pytest.raises(cablecal.InputError, match="pose 7"):
        cablecal.identify(robot, bad)
    r = cablecal.identify(robot, bad, loss="cauchy")
    assert r.loss == "cauchy:10" and r.down_weighted[0].startswith("pose 7: ")
    held = r.std == 0
    assert (np.abs(r.geometry - exp.truth.geometry)[~held] / r.std[~held]).max() < 3.0
    with pytest.raises(cablecal.InputError, match="--loss: must be none, huber or cauchy"):
        cablecal.identify(robot, m, loss="tukey")


def report_section(text, heading):
    """One `## heading` section of a report.md, up to the next section."""
    return text.split("## " + heading + "\n", 1)[1].split("\n## ", 1)[0]


def is_png(path):
    data = path.read_bytes()
    return data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR" and data[-8:-4] == b"IEND"


def test_report_equals_the_clis(tmp_path):
    path = robot_file("planar3_suspended")
    robot = cablecal.Robot.load(path)
    exp = cablecal.simulate(robot, cablecal.sample(robot, 10, seed=3), seed=2)
    meas_csv = tmp_path / "meas.csv"
    meas_csv.write_text(exp.measurements.to_csv())
    result = cablecal.identify(robot, exp.measurements, loss="huber")
    written = cablecal.report(robot, result, tmp_path / "py")
    assert written == str(tmp_path / "py" / "report.md")
    cli("identify", "--robot", path, "--measurements", str(meas_csv), "--loss", "huber", "--out",
        str(tmp_path / "r.yaml"), "--report", str(tmp_path / "cli"))
    for name in ("parameters.csv", "correlation.csv", "singular_values.csv", "residuals.csv"):
        assert data_lines(tmp_path / "py" / name) == data_lines(tmp_path / "cli" / name), name
    assert len(data_lines(tmp_path / "py" / "residuals.csv").splitlines()) == 1 + 10 * 5  # header, 3 encoders + 2
    py_md, cli_md = (tmp_path / "py" / "report.md").read_text(), (tmp_path / "cli" / "report.md").read_text()
    for heading in ("Estimates", "Correlations", "Residuals per pose", "Robust loss", "Identifiability", "Warnings"):
        assert report_section(py_md, heading) == report_section(cli_md, heading), heading
    assert "| command | `python: cablecal.report` |" in py_md
    for figure in ("estimates.png", "correlation.png", "residuals.png", "singular_values.png"):
        assert is_png(tmp_path / "py" / figure), figure
        assert f"]({figure})" in py_md
    # The table's values are the result's, m to 1 um.
    rows = [line.split("|") for line in report_section(py_md, "Estimates").splitlines() if line.startswith("| a")
            or line.startswith("| l")]
    assert [r[1].strip() for r in rows] == result.geometry_names
    np.testing.assert_allclose([float(r[3]) for r in rows], result.geometry, atol=5.000001e-7)


def test_report_with_holdout_equals_the_clis(tmp_path):
    path = robot_file("asymmetric")
    robot = cablecal.Robot.load(path)
    calibration = cablecal.simulate(robot, cablecal.sample(robot, 14, seed=6), geometry_sigma=0.003, seed=2)
    meas_csv, holdout_csv = tmp_path / "meas.csv", tmp_path / "holdout.csv"
    meas_csv.write_text(calibration.measurements.to_csv())
    holdout_csv.write_text(cablecal.simulate(robot, cablecal.sample(robot, 6, seed=7), truth=calibration.truth,
                                             seed=3).measurements.to_csv())
    result = cablecal.identify(robot, calibration.measurements)
    holdout = cablecal.Measurements.load(robot, holdout_csv)
    cablecal.report(robot, result, tmp_path / "py", holdout=holdout)
    cli("identify", "--robot", path, "--measurements", str(meas_csv), "--out", str(tmp_path / "r.yaml"),
        "--report", str(tmp_path / "cli"), "--holdout", str(holdout_csv))
    assert data_lines(tmp_path / "py" / "validation.csv") == data_lines(tmp_path / "cli" / "validation.csv")
    assert len(data_lines(tmp_path / "py" / "validation.csv").splitlines()) == 1 + 6
    py_md, cli_md = (tmp_path / "py" / "report.md").read_text(), (tmp_path / "cli" / "report.md").read_text()
    section = report_section(py_md, "Validation on held-out poses")
    assert section == report_section(cli_md, "Validation on held-out poses")
    assert f"The readings of `{holdout_csv}` (6 poses)" in section and "| calibrated | " in section
    assert "| nominal | " in section and "Nominal / calibrated RMS error: z " in section
    assert is_png(tmp_path / "py" / "validation.png") and "](validation.png)" in section
    assert f"| held-out readings | `{holdout_csv}` |" in py_md
    # The same numbers as validate() of the calibrated robot.
    v = cablecal.validate(cablecal.calibrated_robot(robot, result), holdout, nominal=robot)
    assert f"| calibrated | {1e3 * v.robots['calibrated']['z_rms']:.3g} | " in section
    with pytest.raises(cablecal.InputError, match="holdout: expected a cablecal.Measurements"):
        cablecal.report(robot, result, tmp_path / "bad", holdout=str(holdout_csv))
    assert not (tmp_path / "bad").exists()


def test_report_refuses_a_file_and_keeps_the_data_without_figures(tmp_path, monkeypatch):
    robot = cablecal.Robot.load(robot_file("asymmetric"))
    result = cablecal.identify(robot, cablecal.simulate(robot, cablecal.sample(robot, 8, seed=5), seed=1).measurements)
    (tmp_path / "file").write_text("not a folder")
    with pytest.raises(cablecal.InputError, match="exists and is not a folder"):
        cablecal.report(robot, result, tmp_path / "file")
    with pytest.raises(cablecal.InputError, match="does not exist"):
        cablecal.report(robot, result, tmp_path / "nowhere" / "report")
    with pytest.raises(cablecal.InputError, match="robot 'asymmetric' with 2 cables, but .* is robot "
                                                  "'planar3_suspended' with 3 cables: a result of another robot"):
        cablecal.report(cablecal.Robot.load(robot_file("planar3_suspended")), result, tmp_path / "other")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]
    # No plotting script: the report and its data are written, then FigureError.
    monkeypatch.setenv("CABLECAL_SCRIPTS_DIR", str(tmp_path / "no-scripts"))
    with pytest.raises(cablecal.FigureError, match="the plotting script failed .*report.md, without figures"):
        cablecal.report(robot, result, tmp_path / "report")
    assert "**The figures could not be made:**" in (tmp_path / "report" / "report.md").read_text()
    assert not list((tmp_path / "report").glob("*.png"))
    assert (tmp_path / "report" / "residuals.csv").exists()


def test_montecarlo_with_outliers_and_a_loss():
    robot = cablecal.Robot.builtin()
    clean = cablecal.montecarlo(robot, 12, 4, designs="random", seed=3, threads=1)
    rough = cablecal.montecarlo(robot, 12, 4, designs="random", seed=3, threads=1, outliers="0.05:100")
    robust = cablecal.montecarlo(robot, 12, 4, designs="random", seed=3, threads=1, outliers="0.05:100", loss="cauchy")
    assert clean.summary_csv() != rough.summary_csv()
    assert robust.summary_csv() != rough.summary_csv()
    with pytest.raises(cablecal.InputError, match="--outliers"):
        cablecal.montecarlo(robot, 12, 4, outliers="2")
# ---- Sensor error models -------------------------------------------------------------------------


def bench_arrays(seed=1):
    """Bench readings of a known model: inclinometer offset 0.05 deg, k -0.3 deg; laser offset 20 mm;
    the paper's accuracy and repeatability (3-sigma ranges), accuracy drawn per reference."""
    rng = np.random.default_rng(seed)
    d = np.pi / 180
    ref = np.repeat(np.arange(-60, 61, 5) * d, 6)
    acc = np.repeat(rng.normal(0, 0.1 * d / 3, 25), 6)
    incl = np.column_stack([ref, ref + 0.05 * d - 0.3 * d * (1 / np.cos(ref) - 1) + acc + rng.normal(0, 0.05 * d / 3, ref.size)])
    lref = np.repeat(np.arange(2, 30) * 0.1, 5)
    lacc = np.repeat(rng.normal(0, 0.006 / 3, 28), 5)
    laser = np.column_stack([lref, lref + 0.02 + lacc + rng.normal(0, 0.0015 / 3, lref.size)])
    return incl, laser


def write_bench(path, header, rows):
    with open(path, "w") as f:
        f.write(header + "\n")
        for r in rows:
            f.write("%r,%r\n" % (float(r[0]), float(r[1])))


def test_fit_sensors_from_arrays_equals_the_files_and_the_cli(tmp_path):
    path = robot_file("asymmetric")
    robot = cablecal.Robot.load(path)
    incl, laser = bench_arrays()
    incl_csv, laser_csv, out = str(tmp_path / "incl.csv"), str(tmp_path / "laser.csv"), str(tmp_path / "sensors.yaml")
    write_bench(incl_csv, "reference_rad,reading_rad", incl)
    write_bench(laser_csv, "reference_m,reading_m", laser)
    from_arrays = cablecal.fit_sensors(inclinometer=incl, laser=laser, robot=robot)
    import pathlib
    from_files = cablecal.fit_sensors(inclinometer=pathlib.Path(incl_csv), laser=laser_csv, robot=robot)
    assert from_arrays.inclinometer == from_files.inclinometer
    assert from_arrays.laser == from_files.laser
    cli("sensors", "fit", "--robot", path, "--inclinometer", incl_csv, "--laser", laser_csv, "--out", out)
    cli_text = open(out).read()
    assert from_files.to_yaml().splitlines()[2:] == cli_text.splitlines()[2:]  # all but version and command
    assert from_files.to_yaml().splitlines()[1] == "# command: python: cablecal.fit_sensors"
    i, l = from_arrays.inclinometer, from_arrays.laser
    d = np.pi / 180
    assert abs(i["offset_rad"] - 0.05 * d) < 3 * i["offset_se_rad"]
    assert abs(i["sec_coefficient_rad"] + 0.3 * d) < 3 * i["sec_coefficient_se_rad"]
    assert abs(l["offset_m"] - 0.02) < 3 * l["offset_se_m"]
    assert (i["readings"], i["references"], l["readings"], l["references"]) == (150, 25, 140, 28)
    assert 0.03 * d < i["repeatability_rad"] < 0.07 * d and 0.001 < l["repeatability_m"] < 0.002
    # The fitted robot holds the block; what was not fitted is the robot's own.
    sensors = from_arrays.robot.to_dict()["sensors"]
    assert sensors["laser"]["offset"] == l["offset_m"]
    assert sensors["encoder"] == robot.to_dict()["sensors"]["encoder"]
    laser_only = cablecal.fit_sensors(laser=laser, robot=robot)
    assert laser_only.inclinometer is None
    assert laser_only.robot.to_dict()["sensors"]["inclinometer"] == robot.to_dict()["sensors"]["inclinometer"]


def test_systematic_errors_simulated_and_corrected_as_the_cli(tmp_path):
    path = robot_file("asymmetric")
    incl, laser = bench_arrays(2)
    robot_yaml = tmp_path / "fitted.yaml"
    robot_yaml.write_text(cablecal.fit_sensors(inclinometer=incl, laser=laser, robot=cablecal.Robot.load(path)).robot.to_yaml())
    robot = cablecal.Robot.load(robot_yaml)  # the file's degrees have 12 digits: the CLI's robot, bit for bit
    plan = cablecal.sample(robot, 25, seed=4)
    plan_csv = tmp_path / "plan.csv"
    plan_csv.write_text(plan.to_csv())
    experiment = cablecal.simulate(robot, plan, geometry_sigma=0.003, seed=2, systematic_errors=True)
    meas_csv, result_yaml = tmp_path / "m.csv", tmp_path / "result.yaml"
    cli("simulate", "--robot", str(robot_yaml), "--plan", str(plan_csv), "--geometry-sigma", "0.003", "--seed", "2",
        "--systematic-errors", "--out", str(meas_csv))
    assert experiment.measurements.to_csv() == data_lines(meas_csv)
    corrected = cablecal.identify(robot, experiment.measurements)
    cli("identify", "--robot", str(robot_yaml), "--measurements", str(meas_csv), "--out", str(result_yaml))
    assert yaml_without_provenance(corrected.to_yaml()) == yaml_without_provenance(open(result_yaml).read())
    assert corrected.sensor_correction["laser_offset_m"] == robot.to_dict()["sensors"]["laser"]["offset"]
    # As read (a robot file without the terms) the exit heights carry the laser's offset.
    raw = cablecal.identify(cablecal.Robot.load(path), experiment.measurements)
    assert raw.sensor_correction is None
    truth = dict(zip(robot.geometry_names, experiment.truth.geometry))
    for name in ("a1z", "a2z"):
        k = corrected.geometry_names.index(name)
        assert abs(corrected.geometry[k] - truth[name]) < 3 * corrected.std[k], name
        assert abs(raw.geometry[k] - corrected.geometry[k] - corrected.sensor_correction["laser_offset_m"]) < 0.002, name


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(), "give inclinometer, laser or both"),
        (dict(inclinometer=[[0.0, 0.0], [1.6, 1.6]]), "inclinometer: row 1: column 'reference_rad': 1.6 rad is at or beyond"),
        (dict(inclinometer=[[0.0, 0.0], [0.1, float("nan")]]), "row 1, column 1 is not finite"),
        (dict(inclinometer=[[0.1, 0.1]]), "1 reading of 1 reference value"),
        (dict(inclinometer=np.zeros((4, 3))), "expected shape \\(n, 2\\)"),
        (dict(inclinometer="abc"), "abc: cannot open the file"),
        (dict(laser=[[1.0, 1.0], [-1.0, -1.0]]), "laser: row 1: column 'reference_m': -1 m is negative"),
        (dict(laser=[[1.0, 1.0], [1.0, 1.001], [2.0, 2.0]], delimiter="|"), "--delimiter"),
        (dict(laser=[[1.0, 1.0], [1.0, 1.001], [2.0, 2.0]], robot="wang2022"), "expected a cablecal.Robot"),
    ],
)
def test_fit_sensors_hostile_input_raises_input_error(kwargs, message):
    with pytest.raises(cablecal.InputError, match=message):
        cablecal.fit_sensors(**kwargs)


def test_systematic_errors_need_a_robot_that_has_them():
    robot = cablecal.Robot.load(robot_file("asymmetric"))
    plan = cablecal.sample(robot, 4)
    with pytest.raises(cablecal.InputError, match="no systematic sensor errors to add"):
        cablecal.simulate(robot, plan, systematic_errors=True)
    with pytest.raises(cablecal.InputError, match="expected True or False"):
        cablecal.simulate(robot, plan, systematic_errors="yes")


def test_a_bench_short_of_the_range_warns():
    narrow = [[r, r + e] for r in (-0.4, 0.0, 0.4) for e in (0.0001, -0.0001)]
    with pytest.warns(UserWarning, match="the sec term is extrapolated"):
        cablecal.fit_sensors(inclinometer=narrow, robot=cablecal.Robot.load(robot_file("asymmetric")))


def test_montecarlo_equals_cli(tmp_path):
    path = robot_file("asymmetric")
    robot = cablecal.Robot.load(path)
    result = cablecal.montecarlo(robot, "6:8:2", 15, designs="random", seed=7)
    cli("montecarlo", "--robot", path, "--poses", "6:8:2", "--trials", "15", "--designs", "random", "--seed", "7",
        "--no-plot", "--out", str(tmp_path))
    assert result.summary_csv() == data_lines(tmp_path / "summary.csv")
    rows = result.summary
    assert {r["n"] for r in rows} == {6, 8}
    one_thread = cablecal.montecarlo(robot, "6:8:2", 15, designs="random", seed=7, threads=1)
    assert one_thread.summary_csv() == result.summary_csv()
    assert all(r["design"] == "random" for r in rows)


# ---- Hostile input ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "call",
    [
        lambda r: cablecal.sample(r, "10"),
        lambda r: cablecal.sample(r, True),
        lambda r: cablecal.sample(r, 0),
        lambda r: cablecal.sample(r, 5, seed=-1),
        lambda r: cablecal.sample(r, 5, seed=1.5),
        lambda r: cablecal.workspace(r, step=-0.1),
        lambda r: cablecal.workspace(r, step=float("nan")),
        lambda r: cablecal.workspace(r, step="0.1"),
        lambda r: cablecal.design(r, 7, criterion="f"),
        lambda r: cablecal.design(r, 2),
        lambda r: cablecal.montecarlo(r, "6:x", 5),
        lambda r: cablecal.montecarlo(r, [6], 0),
        lambda r: cablecal.montecarlo(r, [6], 5, designs="random,nonsense"),
        lambda r: cablecal.Measurements(r, np.full((3, 2), np.nan), np.zeros(3), np.zeros(3)),
        lambda r: cablecal.Measurements(r, np.zeros((3, 3)), np.zeros(3), np.zeros(3)),
        lambda r: cablecal.Measurements(r, np.zeros((3, 2)), np.zeros(4), np.zeros(3)),
        lambda r: cablecal.Measurements(r, "abc", np.zeros(3), np.zeros(3)),
        lambda r: cablecal.Measurements(r, np.zeros((3, 2)), np.zeros(3), np.zeros(3), pose_ids=[1, 1.5, 2]),
        lambda r: cablecal.identify(r, cablecal.Measurements(r, np.zeros((3, 2)), np.ones(3), np.zeros(3))),
        lambda r: cablecal.identify(r, cablecal.simulate(r, cablecal.sample(r, 8)).measurements, estimator="best"),
        lambda r: cablecal.simulate(r, cablecal.sample(r, 4), sensors="all"),
        lambda r: cablecal.simulate(r, cablecal.sample(r, 4), geometry_sigma=-1.0),
        lambda r: cablecal.simulate(r, cablecal.sample(r, 4), truth=r, geometry_sigma=0.01),
        lambda r: cablecal.simulate(r, cablecal.sample(cablecal.Robot.load(robot_file("planar3_suspended")), 4)),
        lambda r: cablecal.Plan.load(r, os.path.join(ROBOTS, "asymmetric.yaml")),
    ],
)
def test_hostile_input_raises_input_error(call):
    robot = cablecal.Robot.load(robot_file("asymmetric"))
    with pytest.raises(cablecal.InputError):
        call(robot)


@pytest.mark.parametrize("seed", [2**64, -1, 2**70])
def test_seeds_beyond_sixty_four_bits_are_refused_by_every_call(seed):
    robot = cablecal.Robot.load(robot_file("asymmetric"))
    plan = cablecal.sample(robot, 6, seed=1)
    for call in [
        lambda: cablecal.sample(robot, 3, seed=seed),
        lambda: cablecal.simulate(robot, plan, seed=seed),
        lambda: cablecal.design(robot, 6, starts=1, random_sets=0, seed=seed),
        lambda: cablecal.montecarlo(robot, 6, 2, designs="random", seed=seed),
    ]:
        with pytest.raises(cablecal.InputError, match=r"seed: must be a whole number from 0 to "
                                                      r"18446744073709551615 \(got " + str(seed) + r"\)"):
            call()
    assert len(cablecal.sample(robot, 2, seed=2**64 - 1)) == 2  # the largest is a seed


def test_objects_of_the_wrong_kind_and_other_robots_raise_input_error(tmp_path):
    r2 = cablecal.Robot.load(robot_file("asymmetric"))
    r3 = cablecal.Robot.load(robot_file("planar3_suspended"))
    plan3 = cablecal.sample(r3, 6, seed=1)
    for call in [
        lambda: cablecal.workspace(None),
        lambda: cablecal.workspace(robot_file("asymmetric")),
        lambda: cablecal.montecarlo(r2.to_dict(), 8, 3),
        lambda: cablecal.identify(r3, plan3),
        lambda: cablecal.simulate(r3, None),
        lambda: cablecal.simulate(r3, plan3, truth="lab.yaml"),
        lambda: cablecal.simulate(r3, plan3, truth=r2),  # another cable count
    ]:
        with pytest.raises(cablecal.InputError):
            call()
    result3 = cablecal.identify(r3, cablecal.simulate(r3, plan3, seed=2).measurements)
    with pytest.raises(cablecal.InputError, match="cables"):
        cablecal.calibrated_robot(r2, result3)


def test_a_result_is_refused_beside_another_robot_of_the_same_cable_count(tmp_path):
    # The asymmetric robot's result beside the built-in robot (2 cables each) would report the
    # difference between the two robots as the calibration's changes.
    asymmetric = cablecal.Robot.load(robot_file("asymmetric"))
    result = cablecal.identify(asymmetric, cablecal.simulate(asymmetric, cablecal.sample(asymmetric, 8, seed=5),
                                                             seed=1).measurements)
    assert "robot: {name: \"asymmetric\", cables: 2}" in result.to_yaml()
    assert result.held == ["a1x"] and result.std[0] == 0.0
    other = cablecal.Robot.builtin()
    message = "result: identified for robot 'asymmetric', but <built-in wang2022> is robot 'wang2022' with 2 cables"
    with pytest.raises(ValueError, match=message):
        cablecal.calibrated_robot(other, result)
    with pytest.raises(ValueError, match=message):
        cablecal.report(other, result, tmp_path / "report")
    assert not (tmp_path / "report").exists()
    # A robot of the same name (the calibrated file, a copy) is the same robot.
    assert cablecal.calibrated_robot(cablecal.Robot.from_dict(asymmetric.to_dict()), result).name == "asymmetric"


def test_paths_numpy_integers_and_dict_messages():
    import pathlib
    r = cablecal.Robot.load(pathlib.Path(robot_file("asymmetric")))
    assert r.name == "asymmetric"
    assert len(cablecal.montecarlo(r, np.int64(6), np.int32(4), designs="random").summary) > 0
    d = handmade_robot_dict()
    d["gravty"] = d.pop("gravity")
    with pytest.raises(cablecal.InputError) as e:
        cablecal.Robot.from_dict(d)
    assert str(e.value).startswith("robot dict: gravty"), str(e.value)


def test_input_error_carries_the_clis_message(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(cablecal.Robot.builtin().to_yaml().replace("mass:", "mas:"))
    with pytest.raises(cablecal.InputError) as e:
        cablecal.Robot.load(str(bad))
    done = subprocess.run([CLI, "sample", "--robot", str(bad), "--poses", "3", "--out", str(tmp_path / "p.csv")],
                          capture_output=True, text=True)
    assert done.returncode == 2
    assert str(e.value) in done.stderr
    assert "mas" in str(e.value)
    assert not (tmp_path / "p.csv").exists()


def test_solver_error_is_a_runtime_error():
    assert issubclass(cablecal.SolverError, RuntimeError)
    assert issubclass(cablecal.InputError, ValueError)


# ---- Long calls -------------------------------------------------------------------------------


def test_montecarlo_releases_the_gil():
    robot = cablecal.Robot.load(robot_file("asymmetric"))
    done = threading.Event()

    def run():
        cablecal.montecarlo(robot, [6, 10, 20], 1000, designs="random", seed=1)  # about 1 s
        done.set()

    worker = threading.Thread(target=run)
    worker.start()
    ticks = 0
    while not done.is_set():
        ticks += 1
        time.sleep(0.005)
    worker.join()
    # With the GIL held for the whole study this thread could not run until it ended.
    assert ticks > 20


def test_ctrl_c_interrupts_a_montecarlo():
    robot = cablecal.Robot.load(robot_file("asymmetric"))
    seen = []
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        cablecal.montecarlo(robot, [6, 10], 20000, designs="random", seed=1,
                            progress=lambda done, total: seen.append((done, total)))
    timer.join()
    # Stopped part-way: a study that ran to its end would have reported (total, total).
    assert seen, "progress was reported"
    done, total = seen[-1]
    assert total == 40000 and done < total


def test_progress_reaches_the_total_and_an_exception_in_it_stops_the_study():
    robot = cablecal.Robot.load(robot_file("asymmetric"))
    seen = []
    cablecal.montecarlo(robot, [6], 300, designs="random", seed=1, progress=lambda d, t: seen.append((d, t)))
    assert seen[-1] == (300, 300)
    assert all(a[0] <= b[0] for a, b in zip(seen, seen[1:]))

    class Stop(Exception):
        pass

    def stop(done, total):
        raise Stop()

    with pytest.raises(Stop):
        cablecal.montecarlo(robot, [6, 10], 20000, designs="random", seed=1, progress=stop)
    with pytest.raises(cablecal.InputError):
        cablecal.montecarlo(robot, [6], 10, progress="not callable")


# ---- Spatial robots -----------------------------------------------------------------------------

SPATIAL = ["cogiro", "ipanema1", "irma4u"]


@pytest.mark.parametrize("name", SPATIAL)
def test_spatial_robots_load_from_files_and_built_in(name):
    r = cablecal.Robot.load(robot_file(name))
    assert isinstance(r, cablecal.SpatialRobot)
    assert r.kind == "spatial" and cablecal.Robot.builtin().kind == "planar"
    assert r.num_cables == (4 if name == "irma4u" else 8)
    assert repr(r) == f"<cablecal.SpatialRobot '{r.name}', {r.num_cables} cables>"
    b = cablecal.SpatialRobot.builtin(name)
    assert b.to_yaml() == r.to_yaml()
    assert r.to_dict()["kind"] == "spatial"
    assert r.home.shape == (6,)
    assert name in cablecal.SpatialRobot.builtin_names()
    with pytest.raises(cablecal.InputError, match="no built-in spatial robot"):
        cablecal.SpatialRobot.builtin("nope")


# The geometry error each true robot is drawn with: what its tension limits allow. Stiff cables
# turn an exit error into tension, and ipanema1's plan has cables on tension.min, which any
# error takes below it; irma4u's inextensible 4-cable home slackens a cable at 0.1 mm.
SPATIAL_SIGMA = {"cogiro": "0.002", "ipanema1": "0", "irma4u": "0.000001"}


@pytest.mark.parametrize("name", SPATIAL)
def test_spatial_sample_workspace_simulate_equal_cli(tmp_path, name):
    path = robot_file(name)
    robot = cablecal.Robot.load(path)
    plan = cablecal.sample(robot, 5, seed=3, yaw_range_deg=20)
    assert plan.poses.shape == (5, 6)
    assert plan.tensions.shape == (5, robot.num_cables)
    out = tmp_path / "plan.csv"
    cli("sample", "--robot", path, "--poses", "5", "--seed", "3", "--yaw-range-deg", "20", "--out", str(out))
    assert plan.to_csv() == data_lines(out)
    assert cablecal.SpatialPlan.load(robot, str(out)).to_csv() == plan.to_csv()

    ws = cablecal.workspace(robot, rpy_deg=[0, 0, 0.2])  # irma4u holds its yaw within about 1 degree
    ws_out = tmp_path / "ws.csv"
    cli("workspace", "--robot", path, "--rpy-deg", "0,0,0.2", "--out", str(ws_out))
    assert ws["csv"] == data_lines(ws_out)
    assert ws["xyz"].shape[1] == 3 and ws["feasible"].any()
    assert np.isfinite(ws["tensions"][ws["feasible"]]).all()
    assert np.isclose(ws["volume_m3"], ws["feasible"].sum() * np.diff(np.unique(ws["xyz"][:, 0]))[0] ** 3)

    sigma = SPATIAL_SIGMA[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the poses skipped, as the CLI's stderr lines
        run = cablecal.simulate(robot, plan, geometry_sigma=float(sigma), seed=7, skip_infeasible=True)
    m_out, t_out = tmp_path / "m.csv", tmp_path / "t.yaml"
    cli("simulate", "--robot", path, "--plan", str(out), "--geometry-sigma", sigma, "--seed", "7", "--skip-infeasible",
        "--out", str(m_out), "--truth-out", str(t_out))
    assert run.measurements.to_csv() == data_lines(m_out)
    assert run.truth_yaml == data_lines(t_out)
    held = 5 - len(run.skipped)
    assert held >= 1 and run.true_poses.shape == (held, 6)
    assert run.measurements.dl.shape == (held, robot.num_cables)
    back = cablecal.SpatialMeasurements.load(robot, str(m_out))
    np.testing.assert_array_equal(back.dl, run.measurements.dl)
    assert set(back.sensors) == set(run.measurements.sensors)
    # A file in millimetres is refused on loading, naming the pose and column, as the CLI reads it.
    lines = m_out.read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("pose,"))
    cells = lines[header + 1].split(",")
    cells[1] = str(float(cells[1]) * 1000.0 + 100.0)
    lines[header + 1] = ",".join(cells)
    mm = tmp_path / "mm.csv"
    mm.write_text("\n".join(lines) + "\n")
    with pytest.raises(cablecal.InputError, match=r"column 'dl1'.*millimetres\?"):
        cablecal.SpatialMeasurements.load(robot, str(mm))
    # The first pose read again after the others: a repeated reading of it, warned about as the
    # CLI does.
    if held >= 2:
        lines = m_out.read_text().splitlines()
        again = tmp_path / "again.csv"
        again.write_text("\n".join(lines + [lines[header + 1]]) + "\n")
        with pytest.warns(UserWarning, match=r"again.csv:%d: pose %s read again after other poses \(first at "
                          r".*again.csv:%d\)" % (len(lines) + 1, cells[0], header + 2)):
            cablecal.SpatialMeasurements.load(robot, str(again))


def test_montecarlo_whose_every_trial_fails_raises(tmp_path):
    # As the CLI's exit 3: no statistics (they were zeros, read as a perfect calibration).
    robot = cablecal.SpatialRobot.builtin("irma4u")
    with pytest.raises(cablecal.SolverError, match=r"every one of the 2 trials failed \(simulation 2\)"):
        cablecal.montecarlo(robot, "4", 2, designs="random", geometry_sigma=0.2)


def test_spatial_montecarlo_equals_cli(tmp_path):
    path = robot_file("cogiro")
    robot = cablecal.Robot.load(path)
    # The nominal robot as the truth, its platform too: cogiro's stiff cables take any exit
    # error under their tension bound at some of 27 poses (README, "Monte Carlo" of spatial
    # robots), and a platform drawn from the file's priors (5 mm) moves its tensions as much.
    result = cablecal.montecarlo(robot, 27, 3, designs="random,grid:3x3x3", geometry_sigma=0, seed=5,
                                 exact_platform=True)
    cli("montecarlo", "--robot", path, "--poses", "27", "--trials", "3", "--designs", "random,grid:3x3x3",
        "--geometry-sigma", "0", "--exact-platform", "--seed", "5", "--no-plot", "--out", str(tmp_path))
    assert result.summary_csv() == data_lines(tmp_path / "summary.csv")
    assert {r["design"] for r in result.summary} == {"random", "grid:3x3x3"}
    assert all(r["failures"] == 0 for r in result.summary)
    assert "a1y" in {r["parameter"] for r in result.summary}
    with pytest.raises(cablecal.InputError, match="exact_platform: expected True or False"):
        cablecal.montecarlo(robot, 27, 3, exact_platform="yes")
    with pytest.raises(cablecal.InputError, match="exact_platform: serves spatial robots only"):
        cablecal.montecarlo(cablecal.Robot.builtin(), 10, 3, exact_platform=True)
    with pytest.raises(cablecal.InputError, match="--gauge"):
        cablecal.montecarlo(robot, 8, 3, gauge="a1z")
    with pytest.raises(cablecal.InputError, match="--poses 27"):
        cablecal.montecarlo(robot, 8, 3, designs="grid:3x3x3")
    with pytest.raises(cablecal.InputError, match="cannot identify the geometry"):
        cablecal.montecarlo(robot, 8, 3, designs="random")


def test_spatial_montecarlo_margins_and_pool_equal_cli(tmp_path):
    # The spatial study's planning margins, pool and skipped poses, as the CLI's flags.
    path = robot_file("cogiro")
    robot = cablecal.Robot.load(path)
    result = cablecal.montecarlo(robot, 27, 2, designs="random", geometry_sigma=0.001, seed=5,
                                 skip_infeasible=True, tension_margin=50.0, frame_margin=0.02,
                                 tilt_margin_deg=1.0, random_pool=40)
    cli("montecarlo", "--robot", path, "--poses", "27", "--trials", "2", "--designs", "random",
        "--geometry-sigma", "0.001", "--seed", "5", "--skip-infeasible", "--tension-margin", "50",
        "--frame-margin", "0.02", "--tilt-margin-deg", "1", "--random-pool", "40", "--no-plot",
        "--out", str(tmp_path))
    assert result.summary_csv() == data_lines(tmp_path / "summary.csv")
    # Not the defaults' study: the margins change the plans.
    plain = cablecal.montecarlo(robot, 27, 2, designs="random", geometry_sigma=0.001, seed=5,
                                skip_infeasible=True)
    assert plain.summary_csv() != result.summary_csv()
    with pytest.raises(cablecal.InputError, match="--random-pool.*cannot give 27"):
        cablecal.montecarlo(robot, 27, 2, designs="random", random_pool=20)
    with pytest.raises(cablecal.InputError, match="--tension-margin"):
        cablecal.montecarlo(robot, 27, 2, designs="random", tension_margin=-1.0)
    planar = cablecal.Robot.builtin()
    for name, value in [("skip_infeasible", True), ("tension_margin", 5.0), ("frame_margin", 0.01),
                        ("tilt_margin_deg", 1.0), ("random_pool", 100)]:
        with pytest.raises(cablecal.InputError, match=name + ": serves spatial robots only"):
            cablecal.montecarlo(planar, 10, 3, **{name: value})
    with pytest.raises(cablecal.InputError, match="skip_infeasible: expected True or False"):
        cablecal.montecarlo(robot, 27, 2, skip_infeasible="yes")


def test_spatial_arguments_are_checked():
    robot = cablecal.SpatialRobot.builtin("irma4u")
    planar = cablecal.Robot.builtin()
    with pytest.raises(cablecal.InputError, match="yaw_range_deg"):
        cablecal.sample(planar, 3, yaw_range_deg=10)
    with pytest.raises(cablecal.InputError, match="rpy_deg"):
        cablecal.workspace(planar, rpy_deg=[0, 0, 0])
    for rpy, what in (([0, 0, 720], "yaw must be within"), ([95, 0, 0], "roll and pitch must be within"),
                      ([0, -90, 0], "roll and pitch must be within")):  # the CLI's --rpy-deg check
        with pytest.raises(cablecal.InputError, match=r"rpy_deg: " + what):
            cablecal.workspace(robot, rpy_deg=rpy)
    plan = cablecal.sample(robot, 2)
    with pytest.raises(cablecal.InputError, match="SpatialPlan"):
        cablecal.simulate(robot, cablecal.sample(planar, 2))
    with pytest.raises(cablecal.InputError, match="truth"):
        cablecal.simulate(robot, plan, truth=robot, geometry_sigma=0.001)
    run = cablecal.simulate(robot, plan, sensors="none", encoder_noise=False)
    np.testing.assert_array_equal(run.measurements.dl, plan.length_changes)


def simulated_spatial(tmp_path, path):
    """The robot file at path, 16 poses sampled and simulated with a 2 mm geometry error, and
    the measurement CSV written to tmp_path: (robot, run, csv)."""
    robot = cablecal.Robot.load(path)
    plan = cablecal.sample(robot, 16, seed=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = cablecal.simulate(robot, plan, geometry_sigma=0.002, seed=2, skip_infeasible=True)
    csv = tmp_path / "m.csv"
    csv.write_text(run.measurements.to_csv())
    return robot, run, csv


def test_spatial_identify_equals_cli_and_takes_arrays(tmp_path):
    path = robot_file("cogiro")
    robot, run, csv = simulated_spatial(tmp_path, path)
    result = cablecal.identify(robot, run.measurements)
    assert isinstance(result, cablecal.SpatialIdentifyResult) and result.status == "converged"
    out = tmp_path / "r.yaml"
    stdout = cli("identify", "--robot", path, "--measurements", str(csv), "--out", str(out))
    assert "(ml, gauge auto, statics)" in stdout
    doc = json.loads(cli("identify", "--robot", path, "--measurements", str(csv), "--json"))
    assert list(doc["parameters"]) == result.names
    # The same solve; the last bits may differ with the heap's alignment (Eigen's summation order).
    np.testing.assert_allclose([doc["parameters"][n]["value"] for n in result.names], result.values, rtol=1e-12)
    np.testing.assert_allclose([doc["parameters"][n]["std"] for n in result.names], result.sigma, rtol=1e-6)
    assert result.covariance.shape == (36, 36) and result.poses.shape == (len(result.pose_ids), 6)
    assert result.tensions.shape == (len(result.pose_ids), 8)
    assert result.held == doc["held"] == [] and result.null_directions == []
    assert result.worst_reading["pose_id"] == doc["worst_reading"]["pose"]
    mine = json.loads(result.to_json())
    assert set(mine) == set(doc) and mine["command"].startswith("python: cablecal.identify")
    assert result.to_yaml().startswith("# cablecal identification result") and "\nheld: []\n" in result.to_yaml()
    # From arrays: the same readings, the same estimate.
    again = cablecal.SpatialMeasurements(robot, run.measurements.dl, run.measurements.sensors,
                                         run.measurements.pose_ids)
    np.testing.assert_allclose(cablecal.identify(robot, again).values, result.values, rtol=1e-12)
    # The calibrated robot: a SpatialRobot with the identified exits and initial lengths.
    calibrated = cablecal.calibrated_robot(robot, result)
    cables = calibrated.to_dict()["cables"]
    np.testing.assert_array_equal([c["exit"] for c in cables], result.values[:24].reshape(8, 3))
    np.testing.assert_array_equal([c["initial_length"] for c in cables], result.values[24:32])
    # validate: on the calibration's own readings the calibrated robot beats the nominal one.
    v = cablecal.validate(calibrated, run.measurements, nominal=robot)
    assert isinstance(v, cablecal.SpatialValidation) and v.compared == ["position"]
    assert v.robots["calibrated"]["position"]["rms"] < v.robots["nominal"]["position"]["rms"] / 3
    assert v.robots["calibrated"]["position"]["errors"].shape == (len(v.pose_ids), 3)
    # The spatial report, drawn with this interpreter, validating on the same readings.
    path_md = cablecal.report(robot, result, str(tmp_path / "report"), holdout=run.measurements)
    assert path_md.endswith("report.md")
    for name in ("result.yaml", "parameters.csv", "exits.csv", "residuals.csv", "validation.yaml", "exits.png",
                 "residuals.png"):
        assert (tmp_path / "report" / name).exists(), name
    assert "## Validation on held-out poses" in (tmp_path / "report" / "report.md").read_text()


def test_spatial_identify_from_the_plan_equals_cli(tmp_path):
    # identify --plan: each pose starts from its commanded pose; the same estimate as the
    # command's, and within a twentieth of a sigma of the starts from home.
    path = robot_file("cogiro")
    robot, run, csv = simulated_spatial(tmp_path, path)
    plan = cablecal.sample(robot, 16, seed=2)  # simulated_spatial's
    plan_csv = tmp_path / "plan.csv"
    plan_csv.write_text(plan.to_csv())
    home = cablecal.identify(robot, run.measurements)
    planned = cablecal.identify(robot, run.measurements, plan=plan)
    free = home.sigma > 0
    assert np.all(np.abs(planned.values - home.values)[free] < 0.05 * home.sigma[free])
    doc = json.loads(cli("identify", "--robot", path, "--measurements", str(csv), "--plan", str(plan_csv), "--json"))
    np.testing.assert_allclose([doc["parameters"][n]["value"] for n in planned.names], planned.values, rtol=1e-12)
    loaded = cablecal.SpatialPlan.load(robot, str(plan_csv))
    np.testing.assert_allclose(cablecal.identify(robot, run.measurements, plan=loaded).values, planned.values,
                               rtol=1e-12)
    with pytest.raises(cablecal.InputError, match="plan: serves spatial robots only"):
        cablecal.identify(cablecal.Robot.load(robot_file("wang2022")), run.measurements, plan=plan)
    with pytest.raises(cablecal.InputError, match="plan.*SpatialPlan"):
        cablecal.identify(robot, run.measurements, plan="plan.csv")
    with pytest.raises(cablecal.InputError, match="is a folder, not a CSV file"):
        cablecal.SpatialPlan.load(robot, str(tmp_path))


def test_spatial_identify_anchors_equals_cli(tmp_path):
    # cogiro with an inclinometer beside its tracker (the anchors seen) and load cells (its
    # stretching cables' tensions read).
    text = open(robot_file("cogiro")).read().replace("  encoder: {sigma: 0.00005}", "  encoder: {sigma: 0.00005}\n"
                                                     "  inclinometer: {accuracy_deg: 0.1, repeatability_deg: 0.05}\n"
                                                     "  load_cell: {accuracy: 3.0, repeatability: 1.0}")
    path = str(tmp_path / "cogiro_sensors.yaml")
    open(path, "w").write(text)
    robot, run, csv = simulated_spatial(tmp_path, path)
    result = cablecal.identify(robot, run.measurements, identify="anchors")
    doc = json.loads(cli("identify", "--robot", path, "--measurements", str(csv), "--identify", "anchors", "--json"))
    assert doc["identify"] == "anchors" and json.loads(result.to_json())["identify"] == "anchors"
    assert result.names[32:56] == ["b%d%s" % (i, a) for i in range(1, 9) for a in "xyz"]
    assert list(doc["parameters"]) == result.names and result.held == doc["held"]
    np.testing.assert_allclose([doc["parameters"][n]["value"] for n in result.names], result.values, rtol=1e-12)
    np.testing.assert_allclose([doc["parameters"][n]["std"] for n in result.names], result.sigma, rtol=1e-6)
    anchors = cablecal.calibrated_robot(robot, result).to_dict()["platform"]["anchors"]
    np.testing.assert_array_equal(anchors, result.values[32:56].reshape(8, 3))
    with pytest.raises(cablecal.InputError, match="--identify: foo: expected exits"):
        cablecal.identify(robot, run.measurements, identify="foo")
    planar = cablecal.Robot.builtin()
    with pytest.raises(cablecal.InputError, match="serves spatial robots only"):
        cablecal.identify(planar, cablecal.Measurements(planar, np.zeros((6, 2))), identify="anchors")


def test_a_tilted_swivel_axis_turn_is_held_by_identify_and_design(tmp_path):
    # cogiro with encoders, inclinometer and laser, its third swivel axis tilted 8.5 degrees: the
    # turn about z is barely seen, and identification and design hold it (README, "Barely seen turns").
    text = open(robot_file("cogiro")).read()
    text = text[:text.index("sensors:")] + ("sensors:\n  encoder: {sigma: 0.00005}\n"
                                            "  inclinometer: {accuracy_deg: 0.1, repeatability_deg: 0.05}\n"
                                            "  laser: {accuracy: 0.006, repeatability: 0.0015}\n")
    axes = text.split("swivel_axis: [0, 0, 1]")
    assert len(axes) == 9
    text = "swivel_axis: [0, 0, 1]".join(axes[:3]) + "swivel_axis: [0.147809, 0, 0.989016]" + \
        "swivel_axis: [0, 0, 1]".join(axes[3:])
    path = str(tmp_path / "tilted.yaml")
    open(path, "w").write(text)
    robot = cablecal.Robot.load(path)
    run = cablecal.simulate(robot, cablecal.sample(robot, 30, seed=3), seed=4)
    result = cablecal.identify(robot, run.measurements)
    # 35 iterations with the equilibrium rows at 1e-4 of the weight (README, "Statics as information").
    assert result.status == "converged" and result.iterations < 50
    assert len(result.null_directions) == 2 and len(result.held) == 3
    assert [d["nearly_rigid"] for d in result.weak_directions] == [True]
    assert result.weak_directions[0]["description"].startswith("nearly a rotation about z of the frame")
    design = cablecal.design(robot, 13, starts=1, random_sets=0, geometry_sigma=0)
    assert len(design.held) == 3 and len(design.weakly_seen_held) == 1
    assert design.weakly_seen_held[0].startswith("nearly a rotation about z of the frame")
    assert "weakly_seen_held:" in design.to_yaml()


def test_spatial_identify_refuses_what_it_cannot_do():
    robot = cablecal.SpatialRobot.builtin("cogiro")
    run = cablecal.simulate(robot, cablecal.sample(robot, 12, seed=1), seed=1, skip_infeasible=True)
    with pytest.raises(cablecal.InputError, match="planar robots only"):
        cablecal.identify(robot, run.measurements, estimator="paper")
    with pytest.raises(cablecal.InputError, match="planar robots only"):
        cablecal.identify(robot, run.measurements, geometry_prior=0.001)
    with pytest.raises(cablecal.InputError, match="'a9x' is not an exit coordinate"):
        cablecal.identify(robot, run.measurements, gauge="hold:a9x")
    with pytest.raises(cablecal.InputError, match="SpatialMeasurements"):
        cablecal.identify(robot, cablecal.Measurements(cablecal.Robot.builtin(), np.zeros((3, 2))))
    with pytest.raises(cablecal.InputError, match="no spatial sensor"):
        cablecal.SpatialMeasurements(robot, run.measurements.dl, {"compass": np.zeros((len(run.measurements), 1))})


def test_spatial_design_equals_cli_and_refuses_what_it_does_not_serve(tmp_path):
    path = robot_file("irma4u")
    robot = cablecal.Robot.load(path)
    # A surveyed robot (sigma 0.1 mm, 1 sigma): its plan holds as asked, without the search for
    # the largest robustness that the default below needs (which takes most of this test's time).
    design = cablecal.design(robot, 2, starts=2, random_sets=3, seed=5, geometry_sigma=0.0001, robust_sigmas=1)
    assert isinstance(design, cablecal.SpatialDesignResult)
    plan_csv, summary = tmp_path / "plan.csv", tmp_path / "summary.yaml"
    cli("design", "--robot", path, "--poses", "2", "--starts", "2", "--random-sets", "3", "--seed", "5",
        "--geometry-sigma", "0.0001", "--robust-sigmas", "1", "--out", str(plan_csv), "--summary", str(summary))
    assert design.plan.to_csv() == data_lines(plan_csv)
    assert yaml_without_provenance(design.to_yaml()) == yaml_without_provenance(open(summary).read())
    assert design.plan.poses.shape == (2, 6)
    assert design.held == ["a1x", "a1y", "a1z"] and "a2x" in design.free
    assert design.best_start >= 0 and 1 <= design.converged_starts <= 2
    assert design.criteria["a_trace_covariance_m2"] < design.random_median["a_trace_covariance_m2"]
    assert design.comparison.endswith("better than the median of 3 random sets")
    # The plan is the robot's: simulate takes it as the CLI's simulate takes the file.
    run = cablecal.simulate(robot, design.plan, sensors="none", encoder_noise=False)
    np.testing.assert_array_equal(run.measurements.dl, design.plan.length_changes)
    with pytest.raises(cablecal.InputError, match="summary.yaml: not an identification result"):
        cablecal.design(robot, 2, prior=str(summary))
    assert design.geometry_sigma_m == 0.0001 and design.robustness_requested_k == 1 and design.robustness_note is None
    assert design.robustness_achieved_k == 1 and design.robustness.startswith("each pose holds on ")
    # irma4u has no tracker survey: the default 0.01 m, at which no plan holds (a cable goes
    # slack), so the robustness is lowered, warned and said.
    with pytest.warns(UserWarning, match="robustness lowered"):
        lowered = cablecal.design(robot, 2, starts=1, random_sets=0, seed=5)
    assert lowered.geometry_sigma_m == 0.01 and lowered.robustness_requested_k == 3
    assert lowered.robustness_achieved_k < 3 and "not the requested 3 x 0.01 m" in lowered.robustness_note
    assert lowered.robustness.startswith("each pose holds on ")
    with pytest.raises(cablecal.InputError, match="robust_sigmas.*between 0 and 10"):
        cablecal.design(robot, 2, robust_sigmas=11)
    with pytest.raises(cablecal.InputError, match="at least 2 poses"):
        cablecal.design(robot, 1)
    # Named by design()'s argument, not by the CLI's flag.
    with pytest.raises(cablecal.InputError, match=r"^n: at least 2 poses"):
        cablecal.design(robot, 1)


def test_study_figures_show_a_spatial_robots_every_free_coordinate():
    # plot_montecarlo.py chose its panels by the planar names (x and z): a spatial study's y
    # coordinates were left out and its legend said a1x was held whatever the gauge held.
    import importlib.util
    path = os.path.join(os.environ["CABLECAL_SOURCE_DIR"], "scripts", "plot_montecarlo.py")
    spec = importlib.util.spec_from_file_location("plot_montecarlo", path)
    plot = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(plot)
    names = ["x4", "l20", "a2z", "a1y", "a2x", "a1x", "l10", "a1z", "a2y", "b1x"]
    assert plot.geometry_names(names) == ["a1x", "a1y", "a1z", "a2x", "a2y", "a2z", "l10", "l20"]
    summary = [{"parameter": p, "max_abs": v} for p, v in
               [("a1x", "0"), ("a1y", "0"), ("a1z", "0.002"), ("a2y", "0"), ("a2y", ""), ("a2y", "0.001"),
                ("l10", "nan"), ("l10", "0")]]
    assert plot.held_names(summary) == {"a1x", "a1y", "l10"}
    assert plot.held_label(["a1x"]) == "geometric parameters (under the default gauge a1x is held: error 0)"
    assert plot.held_label(["a1x", "a2y"]) == "geometric parameters (held by the gauge, error 0: a1x, a2y)"
    assert plot.held_label([]) == "geometric parameters"


def test_spatial_robot_round_trips_through_its_dict():
    # A new user's to_dict() could not be loaded back: Robot.from_dict read planar robots only and
    # SpatialRobot had no from_dict.
    robot = cablecal.SpatialRobot.builtin("irma4u")
    d = robot.to_dict()
    for back in (cablecal.SpatialRobot.from_dict(d), cablecal.Robot.from_dict(d)):
        assert isinstance(back, cablecal.SpatialRobot)
        assert back.to_yaml() == robot.to_yaml()
    assert isinstance(cablecal.Robot.from_dict(cablecal.Robot.builtin().to_dict()), cablecal.Robot)
    d["gravity"] = -1.0
    with pytest.raises(cablecal.InputError, match=r"^robot dict: gravity: must be > 0"):
        cablecal.SpatialRobot.from_dict(d)
    with pytest.raises(cablecal.InputError, match="reads spatial robots only"):
        cablecal.SpatialRobot.from_dict(cablecal.Robot.builtin().to_dict())
    with pytest.raises(cablecal.InputError, match="expected a dict"):
        cablecal.SpatialRobot.from_dict([1, 2])
