"""A digit's ``--params`` on the reference firmware's backends (issue 24): ``board://`` (an Uno, or a Nano or Pro
Mini for 7-8 gauges) and ``hil://`` (its image on simavr) serve a digit of up to 8 gauges on an image built for it
(``make firmware PARAMS=D.toml``), refuse a digit of more gauges than the board declares analogue inputs (its
banner's ``adc_channels``: 6 on an Uno) in one line, and refuse an image built for another digit (its banner's
gauges, straight command, range) in one line. The runs on such images are in tests/firmware/test_digit_images.py
and tests/firmware/test_eight_gauges.py."""

from __future__ import annotations

import pytest

from digits import write_digit
from flexdigit.errors import ParameterError
from flexdigit.params import load_params
from flexdigit.rig.backends.board_link import BoardState, check_board_digit, check_board_image

BANNER = "# flexdigit-stream 2 adc=atmega328p period_us=20000 fixed=0 gauges={g} straight={s} range=0..254\r\n"


def test_an_eight_gauge_digit_is_refused_on_a_board_declaring_six_inputs(tmp_path):
    eight = load_params(write_digit("five-sections-eight-gauges", tmp_path))
    check_board_digit(eight, "hil://board.elf")  # the ATmega328P has ADC0..ADC7: no refusal before the banner
    for banner in (BANNER.format(g=8, s=8), BANNER.format(g=8, s=8).replace("\r", " target=uno adc_channels=6\r")):
        uno = BoardState()  # an image from before the board's fields counts as an Uno's
        uno.feed(banner.encode(), time_s=0.0)
        with pytest.raises(ParameterError, match=r"declares 6 analogue inputs \(uno: A0..A5\); the digit has 8") as err:
            check_board_image(uno, eight, "board://x")
        assert "\n" not in str(err.value)
        assert "BOARD=nano" in str(err.value)
    nano = BoardState()
    nano.feed(BANNER.format(g=8, s=8).replace("\r", " target=nano adc_channels=8\r").encode(), time_s=0.0)
    check_board_image(nano, eight, "board://x")  # its own image, on its board


@pytest.mark.parametrize(
    "name", ["thesis", "six-gauges-geared", "four-sections-two-cables", "one-section", "five-sections-eight-gauges"]
)
def test_a_digit_of_up_to_eight_gauges_is_served(name, tmp_path):
    check_board_digit(load_params(write_digit(name, tmp_path)), "board://x")
    check_board_digit(None, "board://x")


def test_an_image_for_another_digit_is_refused_by_its_banner(tmp_path):
    pair = load_params(write_digit("four-sections-two-cables", tmp_path))
    board = BoardState()
    board.feed(BANNER.format(g=4, s=127).encode(), time_s=0.0)
    assert board.image_digit() == (4, 127, (0, 254))
    check_board_image(board, pair, "hil://pair.elf")  # its own image
    with pytest.raises(ParameterError, match="built for 4 gauges, straight command 127.*has 3 gauges") as err:
        check_board_image(board, None, "hil://pair.elf")  # the thesis rig on it
    assert "\n" not in str(err.value)
    assert "PARAMS=" in str(err.value)
    old = BoardState()  # an image from before G gauges says nothing: the thesis rig's
    old.feed(b"# flexdigit-stream 1 period_us=20000\r\n", time_s=0.0)
    check_board_image(old, None, "board://x")
    with pytest.raises(ParameterError, match="has 4 gauges, straight command 127"):
        check_board_image(old, pair, "board://x")
    garbled = BoardState()
    garbled.feed(BANNER.format(g="six", s=8).encode(), time_s=0.0)
    with pytest.raises(OSError, match="gauges=six") as err:  # RigError: one line, not a ValueError
        check_board_image(garbled, None, "board://x")
    assert "\n" not in str(err.value)


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
