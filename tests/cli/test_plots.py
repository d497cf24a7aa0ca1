"""``--plot FILE`` on every command that has something to look at (issue 28, item 3): the file is written (PNG, SVG
or PDF by its suffix, atomically, never over a file without --force) and the figure the library drew has the axes,
the labels with their units and the lines the issue asks for. The Figure is read, not its pixels: each test
catches the one ``save_plot`` was given.

References: the record, log or result the same command wrote or printed (a figure must show what was computed,
not something else), and closed forms for the design figure (G = 1/(s+1), K = 2: L(jw) = 2/(1+jw), T = 2/(s+3)).
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from flexdigit.cli import main

#: What a file of each format starts with.
MAGIC = {".png": b"\x89PNG", ".pdf": b"%PDF", ".svg": b"<?xml"}
#: A figure's data are the computation's own floats, copied: equal but for float formatting in JSON and text.
SAME_RTOL = 1e-12


def _lines(ax) -> dict:
    return {line.get_label(): line for line in ax.get_lines()}


def _written(path) -> bool:
    return path.read_bytes().startswith(MAGIC[path.suffix])


def _plotted(argv, plot, capsys) -> dict:
    """Run a command with ``--plot PLOT --json``: what it printed, the plot written where it says."""
    assert main([*argv, "--plot", str(plot), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["plot"] == str(plot)
    assert _written(plot)
    return result


def test_simulate_plots_its_record_and_identify_its_fit(tmp_path, drawn, capsys):
    record, plot = tmp_path / "step.csv", tmp_path / "step.png"
    assert main(["simulate", "step", "--duration", "0.6", "--out", str(record), "--plot", str(plot)]) == 0
    assert _written(plot)
    (fig,) = drawn
    command_ax, volts_ax = fig.axes
    assert volts_ax.get_xlabel() == "time (s)"
    assert volts_ax.get_ylabel() == "voltage (V)"
    assert {"potentiometer", "gauge 1", "gauge 2", "gauge 3"} <= set(_lines(volts_ax))
    assert set(np.unique(_lines(command_ax)["command"].get_ydata())) == {0, 51}  # the default step 0 -> 51
    capsys.readouterr()

    fit_plot = tmp_path / "fit.svg"
    assert main(["identify", "step", str(record), "--channel", "pot", "--plot", str(fit_plot), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert _written(fit_plot)
    top, bottom = drawn[1].axes
    lines = _lines(top)
    assert {"record", "model", "step instant"} <= set(lines)
    assert top.get_ylabel().endswith("(V)")
    assert bottom.get_ylabel() == "residual (V)"
    # the model line starts at the instant identify reported, and the residual is record minus model
    assert lines["model"].get_xdata()[0] >= summary["t0_s"]
    record_y = lines["record"].get_ydata()[-1]
    np.testing.assert_allclose(
        _lines(bottom)["residual"].get_ydata()[-1], record_y - lines["model"].get_ydata()[-1], rtol=SAME_RTOL
    )


def test_design_plots_step_and_bode(tmp_path, drawn):
    plot = tmp_path / "hinf.pdf"
    assert main(["design", "hinf", "--filter-hz", "39", "--plot", str(plot)]) == 0
    assert _written(plot)
    labels = [(ax.get_xlabel(), ax.get_ylabel()) for ax in drawn[0].axes]
    assert labels == [
        ("", "y per unit step (m/m)"),
        ("", "magnitude (dB)"),
        ("time (s)", "u per unit step (commands/m)"),
        ("frequency (rad/s)", "phase of L (deg)"),
    ]
    assert {"L = G K", "S (T_zw)", "T (T_yw)"} <= set(_lines(drawn[0].axes[1]))


def test_design_figure_against_closed_forms():
    import control as ct

    from flexdigit.control import design_figure

    fig = design_figure(ct.tf([1.0], [1.0, 1.0]), ct.tf([2.0], [1.0]), output_unit="rad", t_final_s=4.0)
    step_y, bode_mag, step_u, bode_phase = fig.axes
    y = _lines(step_y)["output y (T_yw)"]
    t = y.get_xdata()
    np.testing.assert_allclose(y.get_ydata(), 2 / 3 * (1 - np.exp(-3 * t)), atol=1e-6)  # T = 2/(s+3)
    np.testing.assert_allclose(_lines(step_u)["command u (T_uw)"].get_ydata()[0], 2.0, rtol=1e-9)  # u(0+) = K
    loop = _lines(bode_mag)["L = G K"]
    w = loop.get_xdata()
    np.testing.assert_allclose(loop.get_ydata(), 20 * np.log10(2 / np.sqrt(1 + w**2)), rtol=1e-9)
    np.testing.assert_allclose(bode_phase.get_lines()[0].get_ydata(), -np.degrees(np.arctan(w)), atol=1e-9)


def test_run_plots_setpoint_estimate_truth_and_command_and_logs_the_truth(tmp_path, drawn):
    log, plot = tmp_path / "run.jsonl", tmp_path / "run.png"
    argv = ["run", "--duration", "0.4", "--setpoint-deg", "20", "--log", str(log), "--plot", str(plot), "--json"]
    assert main(argv) == 0
    assert _written(plot)
    rotation_ax, command_ax = drawn[0].axes
    lines = _lines(rotation_ax)
    assert {"setpoint", "estimate (gauges)", "true rotation (twin)"} <= set(lines)
    assert rotation_ax.get_ylabel() == "beam rotation (deg)"
    assert command_ax.get_xlabel() == "time (s)"
    samples = [json.loads(line) for line in log.read_text().splitlines() if '"k"' in line]
    assert len(samples) == 20  # 0.4 s of 20 ms
    # the log keeps the twin's true rotation, the one the figure shows
    logged = [s["true_rotation_deg"] for s in samples]
    np.testing.assert_allclose(lines["true rotation (twin)"].get_ydata(), logged, rtol=SAME_RTOL)
    np.testing.assert_allclose(lines["estimate (gauges)"].get_ydata(), [s["y"] for s in samples], rtol=SAME_RTOL)
    assert logged[-1] > 5.0  # the digit moved towards 20 deg


def test_train_and_predict_plot_predicted_against_actual(tmp_path, drawn, capsys, make_rig):
    from flexdigit.tactile.protocols import Protocol
    from flexdigit.tactile.runner import collect

    data = tmp_path / "d.parquet"
    small = Protocol("s", (0.0125, 0.025), (0.0, 0.05, 0.10), repetitions=6, no_load_repetitions=3)
    collect(small, make_rig(seed=0), data)
    model, plot = tmp_path / "m.json", tmp_path / "train.png"
    argv = ["train", str(data), "--hidden", "3", "--tol", "1e-4", "--model", str(model), "--plot", str(plot)]
    assert main(argv) == 0
    assert _written(plot)
    ax = drawn[0].axes[0]
    assert ax.get_xlabel() == "actual load position from the tip (mm)"
    assert ax.get_ylabel() == "predicted load position from the tip (mm)"
    assert set(np.unique(_lines(ax)["readings"].get_xdata())) <= {0.0, 50.0, 100.0}  # the protocol's positions
    capsys.readouterr()

    plot = tmp_path / "predict.svg"
    assert main(["predict", str(model), str(data), "--plot", str(plot)]) == 0
    assert _written(plot)
    text = capsys.readouterr().out
    rmse_mm = float(re.search(r"RMSE ([\d.e+-]+) mm", text).group(1))  # predict's RMSE carries its unit
    readings = _lines(drawn[1].axes[0])["readings"]
    shown = np.sqrt(np.mean((readings.get_ydata() - readings.get_xdata()) ** 2))
    np.testing.assert_allclose(shown, rmse_mm, rtol=1e-3)  # printed to 4 digits
    # each printed prediction carries its unit, the one the plot shows (they were bare metres)
    printed = np.array(re.findall(r"predicted ([-\d.e+]+) mm, actual ([-\d.e+]+) mm", text), float)
    assert len(printed) == min(10, len(readings.get_xdata()))  # predict's --limit default
    np.testing.assert_allclose(printed[:, 0], readings.get_ydata()[: len(printed)], rtol=1e-4, atol=1e-3)
    np.testing.assert_allclose(printed[:, 1], readings.get_xdata()[: len(printed)], rtol=1e-4, atol=1e-3)


# long enough to touch the block and hold (a hold that never reaches its force now exits 2: palpate)
HOLD = "[force]\nsetpoint_n = 0.1\nduration_s = 8\n"


def test_palpate_hold_plots_force_with_the_truth(tmp_path, drawn):
    protocol, plot = tmp_path / "hold.toml", tmp_path / "hold.png"
    protocol.write_text(HOLD)
    assert main(["palpate", "--tissue", "soft-block", "--protocol", str(protocol), "--plot", str(plot)]) == 0
    assert _written(plot)
    force_ax, command_ax = drawn[0].axes
    assert {"setpoint", "estimated force", "true force (twin)"} <= set(_lines(force_ax))
    assert force_ax.get_ylabel() == "contact force (N)"
    assert command_ax.get_ylabel() == "servo command"


QUICK_SWEEP = "[sweep]\ncommands = { from = 8, to = 26, step = 3 }\nsettle_s = 2.5\nreadings = 10\n"


@pytest.mark.slow
def test_palpate_sweep_plots_force_against_indentation_with_the_truth(tmp_path, drawn, capsys):
    protocol, plot = tmp_path / "sweep.toml", tmp_path / "sweep.png"
    protocol.write_text(QUICK_SWEEP)
    argv = ["palpate", "--tissue", "soft-block", "--protocol", str(protocol), "--plot", str(plot), "--json"]
    assert main(argv) == 0
    result = json.loads(capsys.readouterr().out)
    assert _written(plot)
    ax = drawn[0].axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("indentation (mm)", "contact force (N)")
    true_line = _lines(ax)["true contact force (twin)"]
    np.testing.assert_allclose(np.sort(true_line.get_ydata()), np.sort(result["curve"]["true_force_n"]))
    assert f"true {result['truth']['modulus_n_m2']:.4g} N/m^2" in ax.get_title()


def test_calibrate_plots_a_residual_per_target(tmp_path, drawn, capsys):
    sweep, out, plot = tmp_path / "sweep.csv", tmp_path / "cal.toml", tmp_path / "cal.png"
    argv = ["simulate", "sweep", "--commands", "8,22,36,43", "--samples", "3", "--settle", "1", "--out", str(sweep)]
    assert main(argv) == 0
    capsys.readouterr()
    assert main(["calibrate", "--sweep", str(sweep), "--out", str(out), "--plot", str(plot), "--json"]) == 0
    residuals = json.loads(capsys.readouterr().out)["residuals"]
    assert _written(plot)
    ax = drawn[0].axes[0]
    names = [t.get_text() for t in ax.get_yticklabels()]
    assert len(names) == len(residuals) == 6  # slope and offset of each gauge's line (E 3.20-3.22)
    assert all(r["target"] in name for r, name in zip(residuals, names, strict=True))
    notes = [t.get_text() for t in ax.texts]
    assert all(note.endswith(r["unit"]) for r, note in zip(residuals, notes, strict=True))  # each with its unit


def test_shape_plots_the_centre_line(tmp_path, drawn, capsys):
    plot = tmp_path / "shape.png"
    # a reading of the twin's actuation sweep at command 22 (vertical, cable on)
    argv = ["shape", "--gauges-v", "0.0085,0.765,0.151", "--command", "22", "--plot", str(plot), "--json"]
    assert main(argv) == 0
    row = json.loads(capsys.readouterr().out)
    assert _written(plot)
    ax = drawn[0].axes[0]
    assert ax.get_xlabel() == "along the digit from the clamp (mm)"
    assert ax.get_ylabel() == "towards the cable (mm)"
    tip = _lines(ax)["tip"]
    np.testing.assert_allclose([tip.get_xdata()[0], tip.get_ydata()[0]], 1e3 * np.asarray(row["tip_m"]), rtol=1e-9)


def test_a_negative_comma_list_needs_no_equals_sign(capsys):
    # `--gauges-v -0.19,0.1,0.2` was taken for an option; the readings are the rig's, not this rig's: exit 1
    assert main(["shape", "--gauges-v", "-0.19,0.1,0.2", "--command", "20", "--json"]) in (0, 1)
    assert "tip_m" in json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("name", ["fig.jpg", "fig"])
def test_an_unknown_plot_format_is_refused_in_one_line_before_the_work(tmp_path, capsys, name, work_must_not_start):
    import flexdigit.twin.records

    work_must_not_start(flexdigit.twin.records, "servo_step_test")
    argv = ["simulate", "step", "--out", str(tmp_path / "s.csv"), "--plot", str(tmp_path / name)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "'--plot' parameter of flexdigit simulate must be a file ending in .png, .svg or .pdf" in err
    assert "\n" not in err


def test_an_existing_plot_is_kept_without_force_and_replaced_with_it(tmp_path, capsys, work_must_not_start):
    plot = tmp_path / "fig.png"
    plot.write_bytes(b"precious")
    argv = ["design", "hinf", "--filter-hz", "39", "--plot", str(plot)]
    import flexdigit.control.thesis_designs

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(flexdigit.control.thesis_designs, "thesis_design", _refuse)
        assert main(argv) == 2  # refused before the design
    assert "pass --force" in capsys.readouterr().err
    assert plot.read_bytes() == b"precious"
    assert main([*argv, "--force"]) == 0
    assert _written(plot)


def _refuse(*args, **kwargs):
    raise RuntimeError("the work started")


SMALL_SCAN = (
    "[sweep]\ncommands = { from = 8, to = 26, step = 3 }\nsettle_s = 2.0\nreadings = 10\n"
    "[scan]\noffsets_mm = [-20, 0, 20]\ninclusion_width_mm = 10.0\n"
)


@pytest.mark.slow
def test_palpate_scan_plots_the_stiffness_map_with_the_true_inclusion(tmp_path, drawn, capsys):
    protocol, plot = tmp_path / "scan.toml", tmp_path / "scan.png"
    protocol.write_text(SMALL_SCAN)
    argv = ["palpate", "--tissue", "nodule-phantom", "--protocol", str(protocol), "--plot", str(plot), "--json"]
    assert main(argv) == 0
    data = json.loads(capsys.readouterr().out)
    assert _written(plot)
    ax = drawn[0].axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("position in the tissue (mm)", "modulus (N/m^2)")
    lines = _lines(ax)
    inclusion = data["inclusion"]
    np.testing.assert_allclose(lines["inclusion (fitted)"].get_xdata()[0], inclusion["centre_in_tissue_mm"])
    np.testing.assert_allclose(lines["inclusion (true, twin)"].get_xdata()[0], inclusion["true_centre_in_tissue_mm"])


# ------------------------------------------------------------------------------------ a tendon robot (issue 26)
ROBOT_STEP = ["simulate", "step", "--robot", "rao2021", "--tension-n", "2,0,0,0,0,0", "--duration", "0.05"]


def test_simulate_robot_plots_the_tip_path_of_its_table(tmp_path, drawn, capsys):
    import pandas as pd

    table, plot = tmp_path / "rstep.csv", tmp_path / "rstep.png"
    assert main([*ROBOT_STEP, "--out", str(table), "--plot", str(plot)]) == 0
    assert f"plot -> {plot}" in capsys.readouterr().out
    assert _written(plot)
    rows = pd.read_csv(table, comment="#")
    axes = drawn[0].axes
    assert [ax.get_ylabel() for ax in axes] == ["tip x (mm)", "tip y (mm)", "tip z (mm)"]
    assert axes[-1].get_xlabel() == "time (s)"
    for ax, column in zip(axes, ("tip_x_m", "tip_y_m", "tip_z_m"), strict=True):
        line = ax.get_lines()[0]
        np.testing.assert_allclose(line.get_xdata(), rows["t_s"], rtol=1e-9)
        np.testing.assert_allclose(line.get_ydata(), 1e3 * rows[column], rtol=1e-9, atol=1e-9)
    # 2 N on the tendon at 90 deg pulls the tip towards +y and shortens its height (the robot is 400 mm long)
    assert rows["tip_y_m"].iloc[-1] > 1e-3
    assert rows["tip_z_m"].iloc[-1] < 0.4
    # a still coordinate (x: the pull has no x component) is drawn on a 1 mm span, not blown up to round-off
    low, high = axes[0].get_ylim()
    assert high - low >= 1.0


def test_simulate_robot_refuses_a_bad_plot_before_the_simulation(tmp_path, capsys, work_must_not_start):
    import flexdigit.tdcr.experiments

    work_must_not_start(flexdigit.tdcr.experiments, "step_test")
    assert main([*ROBOT_STEP, "--out", str(tmp_path / "r.csv"), "--plot", str(tmp_path / "r.jpg")]) == 2
    assert "must be a file ending in .png, .svg or .pdf" in capsys.readouterr().err


def test_tdcr_shape_plots_the_estimate_beside_the_twin(tmp_path, drawn, capsys):
    plot = tmp_path / "shape.svg"
    argv = ["tdcr", "shape", "rao2021", "--tension-n", "2,0,0,1,0,0", "--plot", str(plot), "--json"]
    assert main(argv) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["plot"] == str(plot)
    assert _written(plot)
    side, front, error = drawn[0].axes
    assert [(ax.get_xlabel(), ax.get_ylabel()) for ax in (side, front)] == [("x (mm)", "z (mm)"), ("y (mm)", "z (mm)")]
    assert (error.get_xlabel(), error.get_ylabel()) == (
        "arc length from the base (mm)",
        "distance to the twin's backbone (mm)",
    )
    lines = _lines(front)
    assert {"estimate (gauges)", "twin", "gauge stations"} <= set(lines)
    # the lines are the backbones the command printed: the estimate's tip and the twin's, in mm
    estimate, twin = lines["estimate (gauges)"], lines["twin"]
    np.testing.assert_allclose(
        [estimate.get_xdata()[-1], estimate.get_ydata()[-1]], 1e3 * np.asarray(result["tip_position_m"])[1:], rtol=1e-9
    )
    np.testing.assert_allclose(
        [twin.get_xdata()[-1], twin.get_ydata()[-1]], 1e3 * np.asarray(result["twin"]["tip_position_m"])[1:], rtol=1e-9
    )
    # the distance panel ends at the tip error the command reported (the twin's last node is the tip)
    np.testing.assert_allclose(error.get_lines()[0].get_ydata()[-1], 1e3 * result["tip_error_m"], rtol=1e-9)
    assert len(_lines(side)["gauge stations"].get_xdata()) == 2 * 3  # 3 stations in each of 2 segments


def test_design_hinf_plots_the_design_on_a_digits_own_plant(tmp_path, drawn, capsys):
    """`design hinf --params --plot` was refused ("the thesis rig's design only"): a user's digit is drawn too."""
    from digits import write_digit

    digit, plot = write_digit("short", tmp_path), tmp_path / "hinf.png"
    argv = ["design", "hinf", "--filter-hz", "5", "--params", str(digit), "--plot", str(plot), "--json"]
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["plot"] == str(plot)
    assert _written(plot)
    step_y, bode_mag, _, _ = drawn[0].axes
    assert step_y.get_ylabel() == "y per unit step (m/m)"
    # the step drawn settles (2 %) when the design's own analysis said it does
    y = _lines(step_y)["output y (T_yw)"]
    t, out = y.get_xdata(), y.get_ydata()
    outside = np.flatnonzero(np.abs(out - out[-1]) > 0.02 * abs(out[-1]))
    assert abs(t[outside[-1] + 1] - summary["tyw_settling_s"]) <= 2 * (t[1] - t[0]) + 0.01 * summary["tyw_settling_s"]
    # and the loop's gain at the lowest frequency drawn is the plant's DC gain times the controller's
    k0 = summary["controller_num"][-1] / summary["controller_den"][-1]
    loop_db = 20 * np.log10(abs(summary["plant_dc_gain_m_per_command"] * k0))
    assert abs(_lines(bode_mag)["L = G K"].get_ydata()[0] - loop_db) < 0.1  # 0.1 rad/s: far below the digit's mode


def test_the_readmes_own_digit_commands_end_in_plots(tmp_path, monkeypatch, capsys):
    """Issue 28: from the README to a plotted step of one's own digit. The README's commands, as written, run
    (the template is the user's file before they edit it) and leave the plots they promise."""
    import shlex
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    block = readme.split("## Your own digit, plotted", 1)[1].split("\n\n")[1]
    commands = [shlex.split(line, comments=True) for line in block.splitlines() if line.strip()]
    expected = [["flexdigit", "list"], ["flexdigit", "params"], ["flexdigit", "params"], ["flexdigit", "simulate"]]
    assert [c[:2] for c in commands] == [*expected, ["flexdigit", "run"]]
    monkeypatch.chdir(tmp_path)
    for argv in commands:
        assert main(argv[1:]) == 0, (argv, capsys.readouterr().err)
    for plot in ("step.png", "run.png"):
        assert _written(tmp_path / plot), plot
    assert "plot -> run.png" in capsys.readouterr().out


def test_tdcr_contact_plots_the_estimate_and_where_the_twin_was_pressed(tmp_path, drawn, capsys):
    plot = tmp_path / "contact.pdf"
    argv = ["tdcr", "contact", "rao2021", "--tension-n", "2,0,0,0,0,0", "--contact-s-m", "0.3"]
    argv += ["--contact-force-n", "0,0.05,0", "--plot", str(plot), "--json"]
    assert main(argv) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["plot"] == str(plot)
    assert _written(plot)
    side, front = drawn[0].axes
    assert [(ax.get_xlabel(), ax.get_ylabel()) for ax in (side, front)] == [("x (mm)", "z (mm)"), ("y (mm)", "z (mm)")]
    lines = _lines(front)
    assert {"backbone (without the contact)", "estimated contact", "pressed here (twin)"} <= set(lines)
    # the estimated contact is drawn where the command reported it, in mm
    estimated = lines["estimated contact"]
    shown = [estimated.get_xdata()[0], estimated.get_ydata()[0]]
    np.testing.assert_allclose(shown, 1e3 * np.asarray(result["position_m"])[1:], rtol=1e-9)
    # and the twin was pressed on its backbone, 300 mm along it: the mark lies on the drawn line
    pressed = lines["pressed here (twin)"]
    backbone = lines["backbone (without the contact)"]
    y_at = np.interp(pressed.get_ydata()[0], backbone.get_ydata(), backbone.get_xdata())
    assert abs(pressed.get_xdata()[0] - y_at) < 0.5  # mm: between two of the backbone's drawn nodes


def test_a_negative_vector_needs_no_equals_sign(capsys):
    # tdcr's help told users to write --tip-force-n=-1,0,0; the parser takes the plain form
    assert (
        main(["tdcr", "statics", "rao2021", "--tension-n", "0,0,0,0,0,0", "--tip-force-n", "-0.01,0,0", "--json"]) == 0
    )
    tip = json.loads(capsys.readouterr().out)["tip_position_m"]
    assert tip[0] < -1e-3  # 10 mN pushes the straight 400 mm rod's tip towards -x


@pytest.mark.slow  # the design's robustness checks (Monte Carlo, small-gain boxes): ~10 s
def test_design_mixsyn_plots_a_step_that_ends_on_the_setpoint(tmp_path, drawn, capsys):
    plot = tmp_path / "mixsyn.svg"
    assert main(["design", "mixsyn", "--plot", str(plot), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert _written(plot)
    step_y, bode_mag, _, _ = drawn[0].axes
    assert step_y.get_ylabel() == "y per unit step (rad/rad)"  # the beam rotation, the plant this design is for
    # integral action (|S(0)| reported ~0): the drawn step ends on the setpoint, and |S| at the lowest frequency
    # drawn is far below 0 dB
    assert summary["requirements"]["sensitivity_dc"] < 1e-6
    y = _lines(step_y)["output y (T_yw)"].get_ydata()
    assert abs(y[-1] - 1.0) < 0.01
    assert _lines(bode_mag)["S (T_zw)"].get_ydata()[0] < -20.0


def test_tdcr_contact_that_finds_nothing_exits_non_zero_and_writes_nothing(tmp_path, capsys):
    """A contact nearer the base than the second gauge station (out of sight) has no place or force the command can
    stand behind: exit 1, the reason in one line (also under --json), no --out and no --plot written."""
    out, plot = tmp_path / "contact.json", tmp_path / "contact.png"
    argv = ["tdcr", "contact", "rao2021", "--tension-n", "2,0,0,0,1,0", "--contact-s-m", "0.05"]
    argv += ["--contact-force-n", "0,0.05,0", "--out", str(out), "--plot", str(plot)]
    assert main(argv) == 1
    text = capsys.readouterr().out
    refused = [line for line in text.splitlines() if line.startswith("out of sight:")]
    assert len(refused) == 1
    assert "place and force not determined" in refused[0]
    assert not out.exists()
    assert not plot.exists()
    assert main([*argv, "--json"]) == 1
    data = json.loads(capsys.readouterr().out)
    assert data["refused"] == refused[0]
    assert data["out_of_sight"] is True
    assert data["s_m"] is None


def test_tdcr_statics_plots_the_backbone_it_solved(tmp_path, drawn, capsys):
    result = _plotted(["tdcr", "statics", "rao2021", "--tension-n", "2,0,0,1,0,0"], tmp_path / "statics.png", capsys)
    side, front, top = drawn[0].axes
    assert [(ax.get_xlabel(), ax.get_ylabel()) for ax in drawn[0].axes] == [
        ("x (mm)", "z (mm)"),
        ("y (mm)", "z (mm)"),
        ("x (mm)", "y (mm)"),
    ]
    assert "rao2021" in drawn[0].get_suptitle()
    backbone_mm = 1e3 * np.asarray(result["backbone_m"])
    for ax, (i, j) in zip((side, front, top), ((0, 2), (1, 2), (0, 1)), strict=True):
        line = _lines(ax)["backbone"]
        np.testing.assert_allclose(line.get_xdata(), backbone_mm[:, i], rtol=SAME_RTOL, atol=1e-12)
        np.testing.assert_allclose(line.get_ydata(), backbone_mm[:, j], rtol=SAME_RTOL, atol=1e-12)
        tip = _lines(ax)["tip"]
        np.testing.assert_allclose(
            [tip.get_xdata()[0], tip.get_ydata()[0]], 1e3 * np.asarray(result["tip_position_m"])[[i, j]]
        )
    # 2 N on the tendon at 90 deg bends the rod towards +y (the tip well off the base's axis), 1 N opposite less so
    assert result["tip_position_m"][1] > 0.05
    assert len(_lines(front)["disks"].get_xdata()) == 20  # rao2021's 20 disks (10 a segment)


def test_tdcr_dynamics_plots_the_tip_path_it_printed(tmp_path, drawn, capsys):
    plot = tmp_path / "dynamics.svg"
    argv = ["tdcr", "dynamics", "rao2021", "--tension-n", "2,0,0,0,0,0", "--duration-s", "0.02"]
    result = _plotted(argv, plot, capsys)
    axes = drawn[0].axes
    assert [ax.get_ylabel() for ax in axes] == ["tip x (mm)", "tip y (mm)", "tip z (mm)"]
    assert axes[-1].get_xlabel() == "time (s)"
    assert "rao2021" in axes[0].get_title()
    tip_mm = 1e3 * np.asarray(result["tip_position_m"])
    for k, ax in enumerate(axes):
        line = ax.get_lines()[0]
        np.testing.assert_allclose(line.get_xdata(), result["t_s"], rtol=SAME_RTOL)
        np.testing.assert_allclose(line.get_ydata(), tip_mm[:, k], rtol=SAME_RTOL, atol=1e-12)
    assert tip_mm[-1, 1] > tip_mm[0, 1]  # the pull at 90 deg moves the tip towards +y
    capsys.readouterr()
    plot.write_bytes(b"precious")  # an existing plot is kept without --force, refused before the simulation
    assert main([*argv, "--plot", str(plot)]) == 2
    assert "pass --force" in capsys.readouterr().err
    assert plot.read_bytes() == b"precious"


#: The 20 ms figure's step is the loop the command scored, redrawn from its weights: the same settling time but
#: for the rebuilt design's round-off (BLAS orderings in the LQR and Kalman solves), far below a 20 ms sample.
REDRAWN_RTOL = 1e-6


def _step_drawn(ax, label):
    from flexdigit.control.analysis import step_figures

    line = _lines(ax)[label]
    return step_figures(line.get_xdata(), line.get_ydata(), target=30.0)


def test_design_20ms_plots_the_step_it_scored_and_the_loops_frequency_response(tmp_path, drawn, capsys):
    data = _plotted(["design", "20ms"], tmp_path / "d20.png", capsys)
    step_ax, bode_mag, command_ax, bode_phase = drawn[0].axes
    assert [(ax.get_xlabel(), ax.get_ylabel()) for ax in drawn[0].axes] == [
        ("", "tip rotation (deg)"),
        ("", "magnitude (dB)"),
        ("time (s)", "command change (servo commands)"),
        ("frequency (rad/s)", "phase of L (deg)"),
    ]
    assert "thesis rig" in drawn[0].get_suptitle()
    shown = _step_drawn(step_ax, "tip rotation")
    scored = data["linear_step_30deg"]
    assert shown.settling_time_s == pytest.approx(scored["settling_time_s"], rel=REDRAWN_RTOL)
    assert shown.overshoot_percent == pytest.approx(scored["overshoot_percent"], rel=REDRAWN_RTOL, abs=1e-9)
    # the command the loop ends on turns the digit 30 deg at the rotation per command the command printed
    command = command_ax.get_lines()[0].get_ydata()
    assert command[-1] * data["deg_per_command"] == pytest.approx(30.0, rel=1e-3)
    # integral action: the tip follows a slow setpoint (|T| ~ 0 dB) and |S| is small where |L| is large
    mag = _lines(bode_mag)
    w = mag["L (loop gain)"].get_xdata()
    assert w[-1] <= np.pi / data["period_s"]  # up to Nyquist, not beyond
    assert abs(mag["T (setpoint to tip)"].get_ydata()[0]) < 0.1
    np.testing.assert_allclose(
        mag["S = 1/(1 + L)"].get_ydata()[0], -mag["L (loop gain)"].get_ydata()[0], atol=0.1
    )  # |S| = 1/|1 + L| ~ 1/|L| where |L| >> 1 (30 dB at 0.1 rad/s: within 0.1 dB)


@pytest.mark.slow  # a described digit's design and run
def test_design_20ms_plots_a_described_digits_design_without_searching_again(tmp_path, drawn, capsys):
    from digits import write_digit

    digit, plot = write_digit("short", tmp_path), tmp_path / "d20.svg"
    assert main(["design", "20ms", "--params", str(digit), "--plot", str(plot), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert _written(plot)
    assert "short" in drawn[0].get_suptitle()
    shown = _step_drawn(drawn[0].axes[0], "tip rotation")
    assert shown.settling_time_s == pytest.approx(data["linear_step_30deg"]["settling_time_s"], rel=REDRAWN_RTOL)


def test_design_sweep_plots_the_swept_tolerance_beside_the_thesis(tmp_path, drawn, capsys):
    plot = tmp_path / "sweep.pdf"
    assert main(["design", "sweep", "--filters", "5,39", "--plot", str(plot), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert _written(plot)
    top, bottom = drawn[0].axes
    assert "thesis rig's printed plant" in top.get_title()
    assert (top.get_ylabel(), bottom.get_xlabel(), bottom.get_ylabel()) == (
        "||T_pq|| (dB)",
        "error filter cut-off (Hz)",
        "additive tolerance (%)",
    )
    np.testing.assert_allclose(top.get_lines()[0].get_xdata(), [5.0, 39.0])
    np.testing.assert_allclose(top.get_lines()[0].get_ydata(), [r["tpq_peak_db"] for r in rows], rtol=SAME_RTOL)
    lines = _lines(bottom)
    ours = lines["1/||T_pq||, % of |G(0)| (flexdigit)"].get_ydata()
    np.testing.assert_allclose(ours, [r["additive_tolerance_relative_percent"] for r in rows], rtol=SAME_RTOL)
    # the thesis's printed percentages (reference/thesis.toml hinf.additive_tolerance_percent) drawn as printed
    np.testing.assert_allclose(lines["thesis (as printed)"].get_ydata(), [0.85, 22.48])


SMALL_PROTOCOL = """name = "small"
orientation = "horizontal"
loads_g = [20.0]
positions_from_tip_cm = [0, 5, 10]
repetitions = 2
no_load_repetitions = 2
settle_s = 0.5
"""


def test_collect_plots_the_datasets_gauges_against_place_and_time(tmp_path, drawn, capsys):
    from flexdigit.tactile.dataset import load_dataset

    protocol, out, plot = tmp_path / "small.toml", tmp_path / "d.parquet", tmp_path / "d.png"
    protocol.write_text(SMALL_PROTOCOL)
    assert main(["collect", str(protocol), "--out", str(out), "--plot", str(plot), "--no-progress", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["plot"] == str(plot)
    assert _written(plot)
    by_place, by_time = drawn[0].axes
    assert (by_place.get_xlabel(), by_place.get_ylabel()) == ("load position from the tip (mm)", "gauge voltage (V)")
    assert (by_time.get_xlabel(), by_time.get_ylabel()) == ("time (s)", "gauge voltage (V)")
    assert "small" in drawn[0].get_suptitle()
    dataset = load_dataset(out)
    loaded = dataset["load_kg"] > 0
    assert loaded.sum() == 6  # 3 positions x 2 repetitions of 20 g
    assert len(dataset) == 12  # and as many readings with no load hung
    for k, name in enumerate(dataset.gauge_columns):
        shown = _lines(by_place)[f"gauge {k + 1}"]
        np.testing.assert_allclose(shown.get_xdata(), 1e3 * dataset["position_from_tip_m"][loaded], rtol=SAME_RTOL)
        np.testing.assert_allclose(shown.get_ydata(), dataset[name][loaded], rtol=SAME_RTOL)
        over_time = _lines(by_time)[f"gauge {k + 1}"]
        np.testing.assert_allclose(over_time.get_xdata(), dataset["time_s"], rtol=SAME_RTOL)
    assert set(np.unique(_lines(by_place)["gauge 1"].get_xdata())) == {0.0, 50.0, 100.0}  # the protocol's places


ROBOT_STUDY = """[study]
robot = "rao2021"
tensions_n = [1, 0, 0, 0, 0, 0]
metrics = {metrics}
[parameters.loads.tensions_n.0]
distribution = "uniform"
relative = 0.1
[parameters.backbone.youngs_modulus_pa]
distribution = "uniform"
relative = 0.1
[sensitivity]
morris_trajectories = 2
"""


def _robot_study(tmp_path, capsys, drawn, metrics: str) -> tuple[dict, object]:
    spec = tmp_path / "spec.toml"
    spec.write_text(ROBOT_STUDY.format(metrics=metrics))
    argv = ["study", "sensitivity", str(spec), "--out", str(tmp_path / "out"), "--workers", "0", "--n", "8"]
    summary = _plotted([*argv, "--no-progress"], tmp_path / "study.png", capsys)
    assert drawn[0].get_suptitle() == "study spec on robot rao2021"
    return summary, drawn[0]


def test_study_sensitivity_plots_the_total_indices_of_every_metric(tmp_path, capsys, drawn):
    summary, fig = _robot_study(tmp_path, capsys, drawn, '["tip_angle_deg", "tip_z_m"]')
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["loads.tensions_n[0]", "backbone.youngs_modulus_pa"]
    # each metric a row, "(NOT converged)" after it at this small N
    assert [t.get_text().split(" (")[0] for t in ax.get_yticklabels()] == ["tip_angle_deg", "tip_z_m"]
    assert fig.axes[1].get_ylabel() == "total Sobol index ST"  # the colour bar
    shown = np.asarray(ax.get_images()[0].get_array())
    for i, metric in enumerate(("tip_angle_deg", "tip_z_m")):
        sobol = summary["metrics"][metric]["sobol"]
        st = [sobol[name]["ST"] for name in ("loads.tensions_n[0]", "backbone.youngs_modulus_pa")]
        np.testing.assert_allclose(shown[i], np.clip(st, 0, 1), rtol=SAME_RTOL)
    # the tip angle T d L / EI: the tension and the modulus both matter, each near half (uniform +-10 % spreads)
    assert np.all(shown[0] > 0.3)
    # a finished study is read for --plot, not run again (nor refused): the same indices drawn
    argv = ["study", "sensitivity", str(tmp_path / "spec.toml"), "--out", str(tmp_path / "out"), "--n", "8"]
    journal = (tmp_path / "out" / "journal.jsonl").read_bytes()
    again = _plotted([*argv, "--workers", "0", "--no-progress"], tmp_path / "again.png", capsys)
    assert (tmp_path / "out" / "journal.jsonl").read_bytes() == journal
    np.testing.assert_allclose(np.asarray(drawn[1].axes[0].get_images()[0].get_array()), shown, rtol=SAME_RTOL)
    assert again["metrics"] == summary["metrics"]


def test_study_sensitivity_of_one_metric_plots_its_indices_with_intervals(tmp_path, capsys, drawn):
    summary, fig = _robot_study(tmp_path, capsys, drawn, '["tip_angle_deg"]')
    ax = fig.axes[0]
    assert ax.get_ylabel() == "Sobol index"
    sobol = summary["metrics"]["tip_angle_deg"]["sobol"]
    from matplotlib.container import BarContainer

    s1_bars, st_bars = (c for c in ax.containers if isinstance(c, BarContainer))
    names = ("loads.tensions_n[0]", "backbone.youngs_modulus_pa")
    np.testing.assert_allclose([b.get_height() for b in s1_bars], [sobol[n]["S1"] for n in names], rtol=SAME_RTOL)
    np.testing.assert_allclose([b.get_height() for b in st_bars], [sobol[n]["ST"] for n in names], rtol=SAME_RTOL)
    assert "N = 16" in ax.get_title()  # the 2N the indices are from


def test_study_design_plots_its_pareto_front(tmp_path, capsys, drawn):
    plot = tmp_path / "front.svg"
    argv = ["study", "design", "thesis-design", "--samples", "3", "--out", str(tmp_path / "out"), "--workers", "0"]
    assert main([*argv, "--no-progress", "--plot", str(plot), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert _written(plot)
    assert drawn[0].get_suptitle() == "study thesis-design on the thesis rig"
    ax = drawn[0].axes[0]
    x_name, y_name = summary["objectives"]
    assert ax.get_xlabel().startswith(x_name)
    assert ax.get_ylabel().startswith(y_name)
    front = _lines(ax)["Pareto front"]
    printed = sorted((row[x_name], row[y_name]) for row in summary["pareto_front"])
    np.testing.assert_allclose(sorted(zip(front.get_xdata(), front.get_ydata(), strict=True)), printed, rtol=SAME_RTOL)
    assert len(ax.collections[0].get_offsets()) == summary["candidates"]  # every candidate drawn
