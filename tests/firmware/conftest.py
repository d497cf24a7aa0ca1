"""Build the reference firmware and its simavr harness once per session, as ``make firmware`` does.

Nothing here is skipped: these tests need Debian's gcc-avr, avr-libc, binutils-avr and libsimavr-dev, which
``make test`` installs when missing (``make avr``); without them the build fails and says which tool is absent.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import flexdigit

FIRMWARE = Path(__file__).resolve().parents[2] / "firmware"
TOOLS = ("avr-gcc", "avr-objcopy", "avr-size", "gcc", "make")


def build(
    tmp_root: Path,
    period_s: float,
    fmt: str,
    rotation_map: Path | None,
    params: Path | None = None,
    out: Path | None = None,
) -> Path:
    """``make -C firmware`` into a fresh directory (or ``out``), the controller exported with ``rotation_map`` (None:
    calibrated on the twin by the export) for the digit ``params`` (None: the thesis rig); returns the image. Fails
    (never skips) without the tools."""
    missing = [t for t in TOOLS if shutil.which(t) is None]
    assert not missing, f"the firmware tests need {missing}: run 'make avr' (apt-get install gcc-avr avr-libc ...)"
    assert Path("/usr/include/simavr/sim_avr.h").exists(), "the HIL harness needs libsimavr-dev: run 'make avr'"
    out = out or tmp_root / f"{fmt}-{int(round(period_s * 1e6))}us{'-' + params.stem if params else ''}"
    src = str(Path(flexdigit.__file__).resolve().parents[1])
    env = dict(os.environ, PYTHONPATH=src + os.pathsep + os.environ.get("PYTHONPATH", ""))
    cmd = [
        "make",
        "-s",
        "-C",
        str(FIRMWARE),
        f"BUILD={out}",
        f"PERIOD_S={period_s}",
        f"FORMAT={fmt}",
        f"MAP={rotation_map or ''}",
        f"PARAMS={params or ''}",
        f"FLEXDIGIT={sys.executable} -m flexdigit.cli",
    ]
    done = subprocess.run(cmd, capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return out / "flexdigit_board.elf"


@pytest.fixture(scope="session")
def rotation_map(tmp_path_factory) -> Path:
    """The gauge -> rotation map every image of the session is exported with (calibrated on the twin, seed 0, as
    ``flexdigit export controller`` calibrates it by default), saved as ``flexdigit run --rotation-map`` reads it:
    the host loops the board is compared with run on the same map."""
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.rotation import calibrate_rotation, save_rotation_map

    path = tmp_path_factory.mktemp("map") / "rotation-map.json"
    with open_rig("sim") as rig:
        save_rotation_map(calibrate_rotation(rig), path)
    return path


@pytest.fixture(scope="session")
def firmware(tmp_path_factory, rotation_map):
    """``firmware(period_s, fmt)`` -> the built image (cached per session), exported with :func:`rotation_map`."""
    root = tmp_path_factory.mktemp("firmware")
    cache: dict[tuple[float, str], Path] = {}

    def get(period_s: float = 0.020, fmt: str = "float") -> Path:
        key = (period_s, fmt)
        if key not in cache:
            cache[key] = build(root, period_s, fmt, rotation_map)
        return cache[key]

    return get


@pytest.fixture(scope="session")
def digit_firmware(tmp_path_factory):
    """``digit_firmware(name, period_s, fmt)`` -> ``(image, params file)`` of a test digit (tests/digits.py), built
    as ``make firmware PARAMS=name.toml`` builds it (its map calibrated on its twin by the export), cached."""
    from digits import write_digit

    root = tmp_path_factory.mktemp("digit-firmware")
    cache: dict[tuple[str, float, str], tuple[Path, Path]] = {}

    def get(name: str, period_s: float = 0.020, fmt: str = "float") -> tuple[Path, Path]:
        key = (name, period_s, fmt)
        if key not in cache:
            params = write_digit(name, root)
            cache[key] = (build(root, period_s, fmt, None, params), params)
        return cache[key]

    return get


@pytest.fixture
def make_image(rotation_map):
    """``make_image(out, period_s, fmt)``: ``make -C firmware BUILD=out ...`` (no cache), exported with
    :func:`rotation_map`; returns the image."""

    def get(out: Path, period_s: float, fmt: str) -> Path:
        return build(out.parent, period_s, fmt, rotation_map, out=out)

    return get


#: The eight-gauge test digit less its tip gauge: the seven-gauge digit a Nano serves (A0..A6).
SEVEN_GAUGES = {
    "geometry": {"gauge_positions_m": [0.03, 0.07, 0.13, 0.17, 0.23, 0.27, 0.33]},
    "sensors": {"adc_channels": list(range(7))},
}


@pytest.fixture(scope="session")
def mapped_digit_firmware(tmp_path_factory):
    """``mapped_digit_firmware(gauges, period_s, fmt)`` -> ``(image, params file, map file)`` of the eight-gauge test
    digit (``five-sections-eight-gauges``; with 7, its tip gauge left off), built with a rotation map saved first
    (calibrated on its twin, mounted as the export and ``run --params`` mount it: the map the export would calibrate
    itself), so the Python loop can run on the same map (``run --rotation-map``). Cached."""
    from digits import write_digit
    from flexdigit.control.design20ms import digit_mount
    from flexdigit.params import load_params
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.rotation import calibrate_rotation, save_rotation_map
    from flexdigit.twin.digit_calibration import twin_calibration

    root = tmp_path_factory.mktemp("eight-gauges")
    cache: dict[tuple[int, float, str], tuple[Path, Path, Path]] = {}
    maps: dict[int, tuple[Path, Path]] = {}

    def get(gauges: int = 8, period_s: float = 0.020, fmt: str = "float") -> tuple[Path, Path, Path]:
        if gauges not in maps:
            folder = root / f"g{gauges}"
            folder.mkdir()
            params = write_digit("five-sections-eight-gauges", folder, **(SEVEN_GAUGES if gauges == 7 else {}))
            p = load_params(params)
            calibration = twin_calibration(p)
            with open_rig("sim", p, calibration=calibration, orientation=digit_mount(p, calibration)) as rig:
                save_rotation_map(calibrate_rotation(rig), folder / "rotation-map.json")
            maps[gauges] = (params, folder / "rotation-map.json")
        key = (gauges, period_s, fmt)
        if key not in cache:
            params, rotation_map = maps[gauges]
            out = root / f"g{gauges}-{fmt}-{int(round(period_s * 1e6))}us"
            cache[key] = (build(root, period_s, fmt, rotation_map, params, out=out), params, rotation_map)
        return cache[key]

    return get
