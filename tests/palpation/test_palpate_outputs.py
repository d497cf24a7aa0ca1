"""``flexdigit palpate``'s loop logs and seed follow issue 16's rules: an existing log is refused before the rig
moves and replaced with ``--force``; the URL's ``seed=`` is not overridden by a default ``--seed``, and the seed
used is reported."""

from __future__ import annotations

import json

import pytest

from digits import write_digit
from flexdigit.cli import main
from flexdigit.errors import DataFileError
from flexdigit.palpation.palpation_files import MAX_SERIES, load_palpation_protocol
from flexdigit.rig.sample_log import read_log_runs

#: The shortest palpation there is: a 0.1 s force hold (after the 1 s tare) on the twin.
HOLD = "[force]\nsetpoint_n = 0.2\nduration_s = 0.1\n"


def test_palpate_log_is_refused_then_replaced_with_force_and_the_urls_seed_is_used(tmp_path, capsys):
    # 0.1 s never reaches 0.2 N: the hold ends in one line, exit 2 (never a success that touched nothing), its
    # loop's log written all the same
    protocol = tmp_path / "hold.toml"
    protocol.write_text(HOLD)
    log = tmp_path / "p.jsonl"
    argv = ["palpate", "--tissue", "soft-block", "--protocol", str(protocol), "--log", str(log), "--json"]
    assert main(argv) == 2
    assert "never reached 0.2 N" in json.loads(capsys.readouterr().out)["error"]
    ((_, header, _, _),) = read_log_runs(log)
    assert "seed=0," in header["rig"]  # the default
    before = log.read_bytes()

    assert main(argv) == 2  # refused before the rig moves: the log is as it was
    assert "the file exists; pass --force" in json.loads(capsys.readouterr().out)["error"]
    assert log.read_bytes() == before

    # --force replaces it (it failed inside the loop before: the loop refused the file the command had cleared);
    # sim?seed=5 with no --seed is the twin of seed 5 (the default --seed 0 made it a conflict)
    assert main([*argv, "--force", "--backend", "sim?seed=5"]) == 2
    assert "never reached" in json.loads(capsys.readouterr().out)["error"]
    ((_, header, samples, footer),) = read_log_runs(log)  # one run: replaced, not appended
    assert "seed=5," in header["rig"]
    assert footer["stop"] == "completed"
    assert len(samples) == 5  # 0.1 s of 20 ms frames


def test_a_series_that_would_fill_the_memory_is_refused(tmp_path):
    """Found by the TOML fuzz suite: a {from, to, step} with a tiny step built a list until the machine ran out of
    memory (the test run was OOM-killed at 24 GB)."""
    path = tmp_path / "huge.toml"
    path.write_text("[sweep]\ncommands = { from = 8, to = 30, step = 1e-300 }\n")
    with pytest.raises(DataFileError, match=rf"huge.toml: key 'sweep.commands' .* more than {MAX_SERIES} values"):
        load_palpation_protocol(path)
    path.write_text("[sweep]\ncommands = { from = 8, to = 30, step = 2 }\n")  # the same form, sized: loads
    assert load_palpation_protocol(path).sweep.commands == tuple(range(8, 31, 2))


def test_a_sweep_that_barely_presses_the_tissue_reports_no_modulus(tmp_path, capsys):
    # the thesis rig's commands 8..30 on the 4:1 geared digit do not reach soft-block (surface 30 mm away): its fit
    # found a near-zero modulus at a made-up gap (1.7 +- 2.4 N/m^2 for a true 1000) and printed it; now no stiffness
    # is reported (the built-in sweep is laid out on the digit, 8..96, and reaches it: tests/cli/test_palpate_pairs)
    params = write_digit("six-gauges-geared", tmp_path)
    protocol = tmp_path / "thesis_commands.toml"
    protocol.write_text("[sweep]\ncommands = { from = 8, to = 30, step = 1 }\n")
    code = main(["palpate", "--tissue", "soft-block", "--params", str(params), "--protocol", str(protocol)])
    err = capsys.readouterr().err
    assert code == 2
    assert "the modulus is not determined" in err
