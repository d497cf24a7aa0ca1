"""What a newcomer tripped on (issue 28's "Tried by someone who has never seen flexdigit"): each a behaviour, each
with the command line they typed."""

import json
from pathlib import Path

import pytest

from flexdigit.cli import main
from flexdigit.tactile.protocols import Protocol
from flexdigit.tactile.runner import collect

SMALL = Protocol("small", loads_kg=(0.025,), positions_from_tip_m=(0.0, 0.04, 0.08), repetitions=6)


@pytest.fixture
def dataset_file(tmp_path, make_rig):
    path = tmp_path / "lab.parquet"
    collect(SMALL, make_rig(seed=0), path)
    return path


def test_train_writes_its_model_with_out_as_the_other_commands(dataset_file, tmp_path, capsys):
    model = tmp_path / "m.json"
    argv = ["train", str(dataset_file), "--target", "contact", "--hidden", "3", "--tol", "1e-4", "--json"]
    assert main([*argv, "--out", str(model)]) == 0
    assert json.loads(capsys.readouterr().out)["model"] == str(model)
    assert model.is_file()
    assert main([*argv, "--out", str(model)]) == 2  # never over it without --force
    assert "--force" in capsys.readouterr().err
    assert main([*argv, "--model", str(tmp_path / "n.json")]) == 0  # the old name still works
    assert (tmp_path / "n.json").is_file()


def _readings(tmp_path):
    path = tmp_path / "lab.csv"
    path.write_text("A,B,C,L,X\n0.1,0.2,0.3,0,\n0.2,0.3,0.4,0.01,0.02\n0.2,0.3,0.5,0.02,0.04\n")
    return path


def test_a_column_map_takes_the_gauges_as_the_flag_does(tmp_path, capsys):
    columns = tmp_path / "columns.toml"
    columns.write_text('gauges = "A,B,C"\nload = "L"\nposition = "X"\n')
    out = tmp_path / "lab.parquet"
    assert main(["dataset", "import", str(_readings(tmp_path)), "--map", str(columns), "--out", str(out)]) == 0
    assert "3 readings (2 loaded, 1 no load" in capsys.readouterr().out


@pytest.mark.parametrize("gauges", ["3", '["A", 3]', "[]"])
def test_a_bad_gauges_key_names_the_file_the_key_and_a_toml_list(tmp_path, capsys, gauges):
    columns = tmp_path / "columns.toml"
    columns.write_text(f'gauges = {gauges}\nload = "L"\nposition = "X"\n')
    code = main(
        ["dataset", "import", str(_readings(tmp_path)), "--map", str(columns), "--out", str(tmp_path / "o.csv")]
    )
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1
    assert f"{columns}: key 'gauges' must be 1 to 8 column names (a TOML list" in err
    assert "ColumnMap" not in err


def _template_edited(tmp_path, name="mine", *, keep: dict[str, str] | None = None):
    """The newcomer's digit from the template: 2 x 0.10 m sections of a 0.3 x 12 mm strip, 4 gauges, edited in place
    (``keep`` uncomments or sets more keys)."""
    template = tmp_path / "template.toml"
    if not template.exists():
        assert main(["params", "--template", str(template)]) == 0
    edits = {
        "section_count": "2",
        "section_length_m": "0.10",
        "strip_thickness_m": "0.0003",
        "strip_width_m": "0.012",
        "gauge_positions_m": "[0.03, 0.07, 0.13, 0.17]",
        "adc_channels": "[0, 1, 2, 3]",
        **(keep or {}),
    }
    lines, skip = [], False
    for line in template.read_text().splitlines():
        key = line.lstrip("# ").split(" = ")[0] if " = " in line else None
        if skip:
            skip = not line.startswith("]")
            continue
        if key in edits:
            lines.append(f"{key} = {edits[key]}")
            skip = line.rstrip().endswith("[")  # a list tomli_w wrote over several lines
            continue
        lines.append(line)
    path = tmp_path / f"{name}.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_the_template_derives_the_lengths_of_an_edited_digit(tmp_path, capsys):
    # the template leaves strip_length_m and digit_length_m out: its sections give them (10 mm supports)
    path = _template_edited(tmp_path)
    capsys.readouterr()
    assert main(["params", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["params"]["geometry"]["strip_length_m"] == pytest.approx(0.20, abs=1e-12)
    assert out["params"]["geometry"]["digit_length_m"] == pytest.approx(0.22, abs=1e-12)
    assert out["notes"] == []
    assert main(["params", str(path)]) == 0
    text = capsys.readouterr().out
    assert "  digit_length_m = 0.22\n" in text  # not 0.22000000000000003


def test_a_leftover_digit_length_is_noted_with_the_supports_it_makes(tmp_path, capsys):
    # the thesis's 0.27 m kept for a 0.20 m strip: (0.27 - 0.20) / 2 = 35 mm supports, and gauge 3 on one
    path = _template_edited(tmp_path, keep={"digit_length_m": "0.27"})
    capsys.readouterr()
    assert main(["params", str(path)]) == 2
    err = capsys.readouterr().err.splitlines()  # one refusal line: its problems, then the note saying why
    assert len(err) == 1
    assert err[0].startswith(
        f"flexdigit params: error: {path}: [geometry] gauge_positions_m[2] = 0.13 m is on the support at 0.135 m"
    )
    assert "note: [geometry] digit_length_m = 0.27 (the thesis rig's) makes 2 supports of 35 mm" in err[0]
    assert "leave digit_length_m out (0.22 m, 10 mm supports)" in err[0]
    # gauges clear of the long supports: consistent, and noted
    moved = _template_edited(
        tmp_path, "moved", keep={"digit_length_m": "0.27", "gauge_positions_m": "[0.03, 0.07, 0.17, 0.2]"}
    )
    capsys.readouterr()
    assert main(["params", str(moved)]) == 0
    assert "note: [geometry] digit_length_m = 0.27 (the thesis rig's) makes 2 supports of 35 mm" in (
        capsys.readouterr().out
    )


def test_a_changed_dynamics_table_is_noted_as_read_by_no_twin(tmp_path, capsys):
    path = _template_edited(tmp_path, keep={"wn_housing_rad_s": "20.0"})
    capsys.readouterr()
    assert main(["params", str(path), "--json"]) == 0
    notes = json.loads(capsys.readouterr().out)["notes"]
    assert len(notes) == 1
    assert notes[0].startswith("[dynamics] wn_housing_rad_s differs from the thesis rig's")


def _own_digit_section() -> str:
    page = (Path(__file__).resolve().parents[2] / "docs" / "getting-started.md").read_text()
    return page.split("## Your own digit, plotted")[1].split("\n## ")[0]


@pytest.mark.slow
def test_the_getting_started_own_digit_steps_run_as_written(tmp_path, monkeypatch, capsys):
    # the page's commands, in order, then its Python: a 30 deg closed-loop step of the newcomer's digit, plotted
    import matplotlib.pyplot as plt

    section = _own_digit_section()
    commands = [line.split("  #")[0].split()[1:] for line in section.splitlines() if line.startswith("    flexdigit ")]
    assert [c[0] for c in commands] == ["params", "params", "run"]
    assert "--setpoint-deg" in commands[2]
    assert "--params" in commands[2]
    monkeypatch.chdir(tmp_path)
    assert main(commands[0]) == 0
    edited = _template_edited(tmp_path, "edited")
    (tmp_path / "mine.toml").write_text(edited.read_text())  # what "edit the sections, ..." stands for
    drawn = _drawn_figures(monkeypatch)
    for argv in commands[1:]:
        assert main(argv) == 0, capsys.readouterr()
    assert Path("step.png").stat().st_size > 0
    assert drawn[0].axes[0].get_title() == "digit mine: digital20 on sim, step to 30 deg"  # whose digit
    assert "digital20 on sim, digit mine (mine.toml): completed" in capsys.readouterr().out
    shown = []
    monkeypatch.setattr(plt, "show", lambda: shown.append(plt.gcf()))
    blocks = section.split("```python\n")[1:]
    assert len(blocks) == 1
    exec(blocks[0].split("```")[0], {})  # noqa: S102 (the page's own code)
    (axes,) = shown[0].axes
    labels = [line.get_label() for line in axes.get_lines()]
    assert labels == ["setpoint", "y", "true_rotation_deg"]
    true_deg = axes.get_lines()[2].get_ydata()
    assert true_deg[-1] == pytest.approx(30.0, abs=0.6)  # the loop holds 30 deg within 2 % (issue 24)
    plt.close("all")


def _drawn_figures(monkeypatch) -> list:
    """The figures the commands save with ``--plot`` (still saved), to read their titles."""
    import flexdigit._plot

    drawn, save = [], flexdigit._plot.save_plot
    monkeypatch.setattr(flexdigit._plot, "save_plot", lambda fig, *a, **k: (drawn.append(fig), save(fig, *a, **k))[1])
    return drawn


def test_a_simulated_record_of_a_described_digit_is_titled_with_its_name(tmp_path, monkeypatch, capsys):
    path = _template_edited(tmp_path)
    capsys.readouterr()
    drawn = _drawn_figures(monkeypatch)
    out, plot = tmp_path / "s.csv", tmp_path / "s.png"
    argv = ["simulate", "step", "--params", str(path), "--cable", "--to", "30", "--out", str(out), "--plot", str(plot)]
    assert main(argv) == 0
    assert capsys.readouterr().out.startswith(f"servo_step_test of digit mine ({path}): 1501 rows")
    assert drawn[0].axes[0].get_title() == "servo step on the twin of digit mine (as thesis 3.2.4)"
    assert plot.stat().st_size > 0
    # the thesis rig's record keeps its title
    assert (
        main(["simulate", "step", "--to", "30", "--out", str(tmp_path / "t.csv"), "--plot", str(tmp_path / "t.png")])
        == 0
    )
    assert drawn[1].axes[0].get_title() == "servo step on the twin (thesis 3.2.4, figure 3.11)"


def test_list_digits_names_example_digits_every_command_takes(tmp_path, monkeypatch, capsys):
    from flexdigit.params import RigParams, builtin_digits, description_notes, digit_inconsistencies, load_params

    assert main(["list", "digits", "--json"]) == 0
    (listed,) = json.loads(capsys.readouterr().out).values()
    assert set(listed) == {
        "thesis-rig",
        "two-sections-four-gauges",
        "four-sections-two-cables",
        "five-sections-eight-gauges",
    }
    assert listed == builtin_digits()
    monkeypatch.chdir(tmp_path)
    digits = {name: load_params(name) for name in listed}
    assert digits["thesis-rig"] == RigParams()
    newcomer = load_params(_template_edited(tmp_path))  # the same digit from the template, edited
    assert digits["two-sections-four-gauges"] == newcomer
    g = digits["four-sections-two-cables"].geometry
    assert (g.strip_length_m, g.digit_length_m) == pytest.approx((0.32, 0.36), abs=1e-12)  # 4 x 80 mm, 10 mm supports
    for name, params in digits.items():
        assert digit_inconsistencies(params) == [], name
        assert description_notes(params) == [], name
        assert len(params.sensors.adc_channels) == len(params.geometry.gauge_positions_m), name
    # copied to edit; a file of that name in the folder is read instead
    assert main(["params", "two-sections-four-gauges", "--write", "copy.toml"]) == 0
    assert load_params("copy.toml") == newcomer
    (tmp_path / "thesis-rig").write_text(
        "[geometry]\nsection_count = 2\nsection_length_m = 0.1\ngauge_positions_m = [0.05]\n"
        "[sensors]\nadc_channels = [0]\n"
    )
    assert load_params("thesis-rig").geometry.section_count == 2
