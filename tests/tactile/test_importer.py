"""``flexdigit dataset import``: foreign readings files (their own columns, units, delimiters) onto datasets.

Known answers: the files are written here, from the closed-form cantilever of tests/tactile/conftest.py (strain
proportional to m g (a - x_i) beyond each gauge) or from values drawn by hypothesis, in layouts flexdigit does not
write: millivolts, grams, millimetres from the clamp, ';' or tab separated, decimal commas, quoted headers with
units, a byte-order mark, CRLF, comment lines, extra columns. The imported dataset must hold the same readings in SI.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cantilever import NOISE_V
from flexdigit.cli import main
from flexdigit.errors import DataFileError
from flexdigit.tactile.dataset import load_dataset
from flexdigit.tactile.importer import ColumnMap, import_readings
from flexdigit.tactile.protocols import RELAXED
from oracles import cantilever_gauges_v

LENGTH_M = 0.27  # the thesis digit, clamp to tip (RigParams default)
#: the network on 8-position closed-form data locates the load to a few mm (a learned fit, not exact)
POSITION_RMSE_MM = 8.0


def write_foreign(path, header, rows, *, delimiter=";", decimal=",", bom=True, newline="\r\n", comment=None):
    """A spreadsheet-like export: quoted header, numbers with the given decimal mark, None as an empty cell."""

    def cell(v):
        if v is None:
            return ""
        if isinstance(v, str):
            return v
        text = repr(float(v))
        return text.replace(".", decimal)

    lines = [] if comment is None else [f"# {comment}"]
    lines.append(delimiter.join(f'"{h}"' for h in header))
    lines += [delimiter.join(cell(v) for v in row) for row in rows]
    path.write_bytes((("\ufeff" if bom else "") + newline.join(lines) + newline).encode("utf-8"))
    return path


def cantilever_rows(seed=0, masses_g=(12.5, 25.0), from_clamp_mm=(60, 90, 120, 150, 180, 210, 240, 265), reps=8):
    """Readings in mV, g and mm from the clamp (a no-load block before each mass), and the known SI values."""
    rng = np.random.default_rng(seed)
    rows, truth = [], []
    for mass in masses_g:
        for _ in range(reps):
            v = NOISE_V * rng.standard_normal(3)
            rows.append([*(v * 1e3), 0.0, None, "idle"])
            truth.append((v, 0.0, np.nan))
        for a_mm in from_clamp_mm:
            for _ in range(reps):
                v = cantilever_gauges_v(a_mm / 1000, mass / 1000)[0] + NOISE_V * rng.standard_normal(3)
                rows.append([*(v * 1e3), mass, float(a_mm), "ok"])
                truth.append((v, mass / 1000, LENGTH_M - a_mm / 1000))
    return rows, truth


HEADER = ["Strain A [mV]", "Strain B [mV]", "Strain C [mV]", "Mass (g)", "Pos. from clamp (mm)", "note"]
FLAGS = [
    "--gauges",
    "Strain A [mV],Strain B [mV],Strain C [mV]",
    "--gauge-unit",
    "mV",
    "--load",
    "Mass (g)",
    "--load-unit",
    "g",
    "--position",
    "pos. FROM clamp (mm)",  # matched ignoring case
    "--position-unit",
    "mm",
    "--position-from",
    "clamp",
    "--decimal",
    ",",
]


def test_foreign_file_goes_import_train_predict_with_no_python(tmp_path, capsys):
    rows, truth = cantilever_rows()
    src = write_foreign(tmp_path / "lab.csv", HEADER, rows, comment="exported by LabRig 2.1")
    ds_path = tmp_path / "lab.parquet"
    assert main(["dataset", "import", str(src), "--out", str(ds_path), *FLAGS, "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["samples"] == len(rows)
    assert report["delimiter"] == ";"
    assert report["tests"] == 2  # one per no-load block
    ds = load_dataset(ds_path)
    np.testing.assert_allclose(ds.gauges_v, [t[0] for t in truth], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(ds["load_kg"], [t[1] for t in truth], rtol=1e-12)
    np.testing.assert_allclose(ds["position_from_tip_m"], [t[2] for t in truth], atol=1e-9)
    assert set(ds["command"]) == {RELAXED}
    assert not ds.protocol.actuated
    model = tmp_path / "pos.json"
    train = ["train", str(ds_path), "--target", "position", "--hidden", "8", "--tol", "1e-7", "--model", str(model)]
    assert main([*train, "--json"]) == 0
    trained = json.loads(capsys.readouterr().out)
    assert trained["rmse_mm"] < POSITION_RMSE_MM
    assert main(["predict", str(model), str(ds_path), "--json"]) == 0
    predicted = json.loads(capsys.readouterr().out)
    assert predicted["scores"]["corr2"] > 0.99
    assert len(predicted["predicted"]) == int(np.sum(ds["load_kg"] > 0))


def test_a_column_map_toml_with_flags_winning_and_an_actuated_file(tmp_path, capsys):
    # tab-separated, commands and repetitions given, positions in cm from the tip, volts and kg
    rows = []
    for command in (0, 20):
        for rep in range(3):
            rows.append([0.01 * rep, 0.02, 0.03, command, 0.0, None, rep])
        for pos_cm in (2.0, 10.0, 18.0):
            for rep in range(3):
                rows.append([0.1 + pos_cm / 100, 0.2, 0.3 + command / 100, command, 0.025, pos_cm, rep])
    header = ["g1", "g2", "g3", "servo", "m", "x", "rep"]
    src = write_foreign(tmp_path / "a.tsv", header, rows, delimiter="\t", decimal=".", bom=False, newline="\n")
    cmap = tmp_path / "map.toml"
    cmap.write_text(
        'gauges = ["g1", "g2", "g3"]\nload = "m"\nposition = "x"\nposition_unit = "mm"\ncommand = "servo"\n'
        'repetition = "rep"\nname = "bench rig"\n'
    )
    out = tmp_path / "a.parquet"
    assert main(["dataset", "import", str(src), "--map", str(cmap), "--position-unit", "cm", "--out", str(out)]) == 0
    capsys.readouterr()
    ds = load_dataset(out)
    assert ds.protocol.name == "bench rig"
    assert ds.protocol.actuation_commands == (0, 20)
    assert ds.protocol.positions_from_tip_m == (0.02, 0.1, 0.18)  # --position-unit cm won over the map's mm
    assert ds["repetition"].tolist() == [r[6] for r in rows]
    assert ds["test"].tolist() == [0] * 12 + [1] * 12  # a new test when the command changes
    assert ds["position_index"].tolist()[3:12] == [1, 1, 1, 2, 2, 2, 3, 3, 3]
    assert main(["train", str(out), "--target", "contact", "--hidden", "3", "--tol", "1e-5", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["accuracy"] >= 0.75  # runs on the command input as chapter 7


def _bad_case(tmp_path, header, rows, extra_flags=()):
    src = write_foreign(tmp_path / "bad.csv", header, rows, delimiter=",", decimal=".", bom=False, newline="\n")
    flags = ["--gauges", "a,b,c", "--load", "mass_g", "--load-unit", "g", "--position", "x_mm", "--position-unit", "mm"]
    return main(["dataset", "import", str(src), "--out", str(tmp_path / "o.parquet"), *flags, *extra_flags])


GOOD = [1.0, 2.0, 3.0, 25.0, 100.0]


@pytest.mark.parametrize(
    ("header", "rows", "extra", "message"),
    [
        (["a", "b", "mass_g", "x_mm"], [GOOD[:2] + GOOD[3:]], [], r"bad\.csv: no column 'c' \(gauge 3\)"),
        (["a", "b", "c", "mass_g", "x_mm"], [GOOD, [1, "oops", 3, 25, 100]], [],
         r"bad\.csv: line 3, column 'b': 'oops' is not a number"),
        (["a", "b", "c", "mass_g", "x_mm"], [GOOD, [1, 2, "NaN", 25, 100]], [],
         r"bad\.csv: line 3, column 'c': 'NaN' is not a number"),
        (["a", "b", "c", "mass_g", "x_mm"], [GOOD, [1, 2, 3, -12.5, 100]], [],
         r"bad\.csv: line 3, column 'mass_g': -12.5: a negative mass"),
        (["a", "b", "c", "mass_g", "x_mm"], [GOOD, [1, 2, 3, 25, 290]], [],
         r"bad\.csv: line 3, column 'x_mm': 290.0: beyond the digit \(0 to 270 mm from the tip\)"),
        (["a", "b", "c", "mass_g", "x_mm"], [GOOD, [1, 2, 3, 25, None]], [],
         r"bad\.csv: line 3, column 'x_mm': empty: a loaded reading needs a position"),
        (["a", "b", "c", "mass_g", "x_mm"], [GOOD, [1, 2, None, 25, 100]], [],
         r"bad\.csv: line 3, column 'c': empty cell"),
        (["a", "b", "c", "mass_g", "x_mm", "cmd"], [GOOD + [20], GOOD + [20.5]], ["--command", "cmd"],
         r"bad\.csv: line 3, column 'cmd': 20.5: expected a servo command"),
        (["a", "b", "c", "mass_g", "x_mm"], [GOOD], ["--digit-length-m", "0.05"],
         r"beyond the digit \(0 to 50 mm from the tip\)"),
        (["a", "b", "c", "mass_g", "x_mm"], [[1, 2, 3, 0, None]], [], r"bad\.csv: no loaded reading"),
        (["a", "b", "c", "mass_g", "x_mm"], [GOOD, [1, 2, 3, 25000, 100]], [],
         r"line 3, column 'mass_g': 25000.0: more than 10 kg"),
    ],
)  # fmt: skip
def test_bad_mapped_files_give_one_line_errors(tmp_path, capsys, header, rows, extra, message):
    assert _bad_case(tmp_path, header, rows, extra) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("flexdigit dataset: error: "), err
    assert re.search(message, err[0]), err[0]
    assert not (tmp_path / "o.parquet").exists()


def test_map_and_flag_mistakes_are_named(tmp_path, capsys):
    src = write_foreign(tmp_path / "r.csv", ["a", "b", "c", "m", "x"], [GOOD], delimiter=",", decimal=".")
    out = ["--out", str(tmp_path / "o.parquet")]
    assert main(["dataset", "import", str(src), *out, "--gauges", "a,b,c", "--load", "m"]) == 2
    assert "dataset import needs --position (the position column)" in capsys.readouterr().err
    thesis = tmp_path / "thesis.toml"
    thesis.write_text("")  # the thesis rig: three gauges
    two = ["--gauges", "a,b", "--load", "m", "--position", "x", "--params", str(thesis)]
    assert main(["dataset", "import", str(src), *out, *two]) == 2
    assert "names 2 gauge columns but the digit has 3 gauges" in capsys.readouterr().err
    nine = ",".join("abcmxabcm")
    assert main(["dataset", "import", str(src), *out, "--gauges", nine, "--load", "m", "--position", "x"]) == 2
    assert "the column flags: --gauges must be 1 to 8 column names" in capsys.readouterr().err
    bad_map = tmp_path / "m.toml"
    bad_map.write_text('gauges = ["a", "b", "c"]\nload = "m"\nposition = "x"\nload_units = "g"\n')
    assert main(["dataset", "import", str(src), *out, "--map", str(bad_map)]) == 2
    assert "m.toml: unknown key 'load_units'" in capsys.readouterr().err
    bad_map.write_text('gauges = ["a", "b", "c"]\nload = "m"\n')
    assert main(["dataset", "import", str(src), *out, "--map", str(bad_map)]) == 2
    assert "m.toml: missing key 'position' (the position column)" in capsys.readouterr().err
    bad_map.write_text('gauges = ["a", "b", "c"]\nload = "m"\nposition = "x"\ngauge_unit = "uV"\n')
    assert main(["dataset", "import", str(src), *out, "--map", str(bad_map)]) == 2
    assert "m.toml: key 'gauge_unit' must be one of 'V', 'mV'" in capsys.readouterr().err
    # a decimal comma in a ','-separated file (quoted cells) read with '.' is named as such
    comma = tmp_path / "c.csv"
    comma.write_text('a,b,c,m,x\n"1,0","2,0","3,0",25,100\n')
    assert main(["dataset", "import", str(comma), *out, "--gauges", "a,b,c", "--load", "m", "--position", "x"]) == 2
    assert "'1,0' is not a number (a decimal comma? give the decimal mark ',')" in capsys.readouterr().err
    # an existing dataset is kept unless --force
    existing = tmp_path / "o.parquet"
    existing.write_text("keep")
    assert main(["dataset", "import", str(src), *out, "--gauges", "a,b,c", "--load", "m", "--position", "x"]) == 2
    assert "exists; pass --force" in capsys.readouterr().err
    assert existing.read_text() == "keep"


# ------------------------------------------------------------------------------------------- property test
NAMES = st.text(alphabet=st.characters(whitelist_categories=("L", "N"), whitelist_characters=" ()[]_-."), min_size=1,
                max_size=12).map(str.strip).filter(lambda s: s and s[0] not in "#")  # fmt: skip


@st.composite
def foreign_files(draw):
    """A random layout of random readings, with the values it must import to."""
    n_pos = draw(st.integers(1, 5))
    positions_mm = draw(st.lists(st.integers(0, 270), min_size=n_pos, max_size=n_pos, unique=True))
    masses_g = draw(st.lists(st.sampled_from([5.0, 7.5, 12.5, 25.0, 37.5, 50.0]), min_size=1, max_size=3, unique=True))
    reps, no_load = draw(st.integers(1, 3)), draw(st.integers(0, 3))
    gauge_unit, load_unit = draw(st.sampled_from(["V", "mV"])), draw(st.sampled_from(["kg", "g"]))
    pos_unit, pos_from = draw(st.sampled_from(["m", "cm", "mm"])), draw(st.sampled_from(["tip", "clamp"]))
    delimiter = draw(st.sampled_from([",", ";", "\t", "|"]))
    decimal = draw(st.sampled_from(["."] if delimiter == "," else [".", ","]))
    names = draw(st.lists(NAMES, min_size=6, max_size=6, unique_by=lambda s: " ".join(s.lower().split())))
    order = draw(st.permutations(range(6)))  # column order, the sixth an extra column
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))  # the readings, inside the ADC's +-5 V
    rows, truth = [], []
    for m in masses_g:
        for _ in range(no_load):
            volts = rng.uniform(-4.9, 4.9, 3)
            rows.append((volts, 0.0, None))
            truth.append((volts, 0.0, np.nan))
        for p in positions_mm:
            for _ in range(reps):
                volts = rng.uniform(-4.9, 4.9, 3)
                rows.append((volts, m, p))
                truth.append((volts, m / 1000, (p if pos_from == "tip" else 270 - p) / 1000))
    g_scale = {"V": 1.0, "mV": 1e3}[gauge_unit]
    l_scale = {"kg": 1e-3, "g": 1.0}[load_unit]
    p_scale = {"m": 1e-3, "cm": 0.1, "mm": 1.0}[pos_unit]
    table = [
        [*(float(v) * g_scale for v in vs), m * l_scale, None if p is None else p * p_scale, "x"] for vs, m, p in rows
    ]
    header = [names[k] for k in range(6)]
    layout = dict(
        delimiter=delimiter, decimal=decimal, bom=draw(st.booleans()), newline=draw(st.sampled_from(["\n", "\r\n"]))
    )
    cmap = ColumnMap(
        gauges=tuple(header[:3]), gauge_unit=gauge_unit, load=header[3], load_unit=load_unit, position=header[4],
        position_unit=pos_unit, position_from=pos_from, decimal=decimal,
    )  # fmt: skip
    return [header[k] for k in order], [[row[k] for k in order] for row in table], cmap, truth, layout


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(case=foreign_files())
def test_any_layout_imports_to_the_same_si_readings(tmp_path, case):
    header, rows, cmap, truth, layout = case
    path = write_foreign(tmp_path / "f.csv", header, rows, **layout)
    ds = import_readings(path, cmap)
    np.testing.assert_allclose(ds.gauges_v, [t[0] for t in truth], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(ds["load_kg"], [t[1] for t in truth], rtol=1e-12)
    np.testing.assert_allclose(ds["position_from_tip_m"], [t[2] for t in truth], atol=1e-9)
    loaded = ds["load_kg"] > 0
    positions = np.array(ds.protocol.positions_from_tip_m)
    np.testing.assert_allclose(positions[ds["position_index"][loaded] - 1], ds["position_from_tip_m"][loaded])
    assert np.all(ds["position_index"][~loaded] == 0)
    assert ds.meta["rig"]["delimiter"] == layout["delimiter"]


def test_the_importer_refuses_rather_than_guesses_a_delimiter(tmp_path):
    path = tmp_path / "ragged.csv"
    path.write_text("a,b,c,m,x\n1,2,3,25\n1;2;3;25;4\n")
    with pytest.raises(DataFileError, match="no delimiter splits the header"):
        import_readings(path, ColumnMap(gauges=("a", "b", "c"), load="m", position="x"))


@pytest.mark.slow
def test_every_estimator_and_study_runs_on_an_imported_dataset(tmp_path):
    # the estimators of tactile.studies and the 6.2.1 strategies on the closed-form readings imported above:
    # every score finite, the learned ones locating the load to a few cm on this easy data
    from flexdigit.tactile.bounds import TwinGaugeModel
    from flexdigit.tactile.localisation import ESTIMATORS, localisation_study
    from flexdigit.tactile.pipeline import compare_strategies

    rows, _ = cantilever_rows()
    src = write_foreign(tmp_path / "lab.csv", HEADER, rows)
    cmap = ColumnMap(
        gauges=tuple(HEADER[:3]), gauge_unit="mV", load=HEADER[3], load_unit="g", position=HEADER[4],
        position_unit="mm", position_from="clamp", decimal=",",
    )  # fmt: skip
    ds = import_readings(src, cmap)
    loc = localisation_study(ds, TwinGaugeModel(), fast=True, epochs=5)
    assert set(loc.position_rmse_m) == set(ESTIMATORS)
    assert all(np.isfinite(v) for v in loc.position_rmse_m.values())
    assert np.isfinite(loc.crlb_rms_identifiable_m)  # no time column: no drift, not NaN
    assert loc.position_rmse_m["Gaussian process"] < 0.02
    scores = compare_strategies(ds, hidden=6, tol=1e-5, epochs=5)
    assert len(scores) == 3
    assert all(np.isfinite(s.position_corr2) for s in scores)


@pytest.mark.parametrize("count", [1, 5])
def test_a_digit_of_g_gauges_imports_g_gauge_columns(tmp_path, capsys, count):
    """A foreign file of a digit with ``count`` gauges: the dataset holds gauge1_v..gaugeG_v, in the file's order."""
    names = [f"sg{k}" for k in range(count)]
    rows = [[0.1 * (k + 1) for k in range(count)] + [25, 100], [0.2 * (k + 1) for k in range(count)] + [0, None]]
    src = write_foreign(tmp_path / "g.csv", [*names, "m", "x"], rows, delimiter=",", decimal=".")
    out = tmp_path / "g.parquet"
    flags = ["--gauges", ",".join(names), "--load", "m", "--load-unit", "g", "--position", "x", "--position-unit", "mm"]
    assert main(["dataset", "import", str(src), "--out", str(out), *flags]) == 0
    ds = load_dataset(out)
    assert ds.gauge_columns == tuple(f"gauge{k}_v" for k in range(1, count + 1))
    np.testing.assert_allclose(ds.gauges_v[0], [0.1 * (k + 1) for k in range(count)], rtol=1e-12)
