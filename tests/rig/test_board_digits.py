"""A digit's ``--params`` on the reference firmware's backends (issue 24): ``board://`` (an Uno) and ``hil://`` (its
image on simavr) serve a digit the firmware can read (3 gauges, the thesis rig's commands: its image's exported
controller relaxes to the thesis's straight command) and refuse any other in one line before a port or harness is
opened; ``run --on-board --params`` is refused in one line (the image's controller is the thesis rig's)."""

from __future__ import annotations

import pytest

from digits import write_digit
from flexdigit.cli import main
from flexdigit.errors import ParameterError
from flexdigit.params import load_params
from flexdigit.rig.backends.board_link import check_board_digit
from flexdigit.rig.base import open_rig


@pytest.mark.parametrize(
    ("name", "reason"),
    [("five-sections-eight-gauges", "the digit has 8 gauges"), ("four-sections-two-cables", "straight command 127")],
)
def test_the_boards_refuse_a_digit_their_firmware_cannot_serve(name, reason, tmp_path):
    params = load_params(write_digit(name, tmp_path))
    elf = tmp_path / "board.elf"
    elf.write_bytes(b"\x7fELF")  # refused before the image is read or the harness looked for
    for url in (f"hil://{elf}", "board://loop://"):
        with pytest.raises(ParameterError, match=reason) as err:
            open_rig(url, params)
        message = str(err.value)
        assert message.startswith(url.split("?")[0]) and "\n" not in message


def test_a_three_gauge_digit_with_the_thesis_commands_is_served():
    # the thesis geometry with its 3 gauges moved: read as the firmware reads it, relaxed where it relaxes
    from flexdigit.params import RigParams

    moved = RigParams.from_dict({"geometry": {"gauge_positions_m": [0.06, 0.14, 0.2]}})
    check_board_digit(moved, "board://x")
    check_board_digit(None, "board://x")


def test_run_on_board_with_params_is_one_line(tmp_path, capsys):
    path = write_digit("two-sections", tmp_path)
    code = main(["run", "--on-board", "--backend", f"hil://{tmp_path / 'board.elf'}", "--params", str(path)])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert "--params" in err and "--on-board" in err and "\n" not in err


def test_a_hardware_map_with_no_operator_is_one_line(monkeypatch, capsys):
    # run on hardware asks the operator for the rotation at each command (--map-from operator): with stdin at its
    # end that is one line naming what to give instead, not an EOFError; a reply that is no number is named too
    import io

    from flexdigit.cli.run import _ask_operator
    from flexdigit.errors import RigError

    monkeypatch.setattr("sys.stdin", io.StringIO(""))
    with pytest.raises(RigError, match="--map-from twin"):
        _ask_operator(8)
    monkeypatch.setattr("sys.stdin", io.StringIO("ten\n"))
    with pytest.raises(ParameterError, match="'ten'"):
        _ask_operator(8)
    monkeypatch.setattr("sys.stdin", io.StringIO("12.5\n"))
    assert _ask_operator(8) == 12.5
    assert "tip rotation now" in capsys.readouterr().err
