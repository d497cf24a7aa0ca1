"""The DAQ backend: the gauge channels of an MCC card through ``uldaq`` (thesis 2.5.1, table 2.2): the thesis rig's
three, or one per gauge of a ``params`` digit (``sensors.adc_channels``, 1 to 8).

The thesis reads the amplified half-bridges on analog inputs 0, 1, 2 (pins 2, 4, 6, "Ch n high") of a
PCI-DAS1602/16 set to +-5 V. The channels and range come from ``params.sensors`` (``adc_channels``,
``adc_range_v``). The servo's potentiometer (0.47..2.48 V over 0..219 deg, 3.2.4) was wired to "one of the
channels of the data acquisition card" (3.2.4, number not given): name it with ``pot_channel`` (URL
``daq://0?pot=3``, or ``serial://PORT?daq=0&pot=3``); without it the pot reads NaN. ``uldaq`` is an optional
extra (``pip install flexdigit[daq]``, plus MCC's ``libuldaq``) and is imported only when a DAQ rig is opened.
Note: libuldaq drives MCC's USB and Ethernet devices; a PCI card needs MCC's PCI driver (or an equivalent USB card
such as a USB-1608).

A DAQ card alone cannot move the servo: use ``serial://PORT?daq=0`` for the full rig. :class:`DaqRig` on its
own is a sensor (``write_command`` raises :class:`~flexdigit.errors.RigError` unless given an ``actuator``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from flexdigit._validation import check_int
from flexdigit.errors import ParameterError, RigError
from flexdigit.params import RigParams
from flexdigit.rig.base import Rig, UrlOption

__all__ = ["DaqRig", "uldaq_range", "from_url", "MISSING_ULDAQ"]

MISSING_ULDAQ = (
    "the daq backend needs the optional 'uldaq' package (pip install 'flexdigit[daq]') and MCC's libuldaq; "
    "it is not installed"
)

#: Bipolar ranges uldaq names, by half-span in volts.
_BIPOLAR = {10.0: "BIP10VOLTS", 5.0: "BIP5VOLTS", 2.5: "BIP2PT5VOLTS", 2.0: "BIP2VOLTS", 1.0: "BIP1VOLTS"}


def _import_uldaq() -> Any:
    try:
        import uldaq
    except ImportError as exc:  # also OSError-like failures of the C library surface here as ImportError
        raise RigError(MISSING_ULDAQ) from exc
    return uldaq


def uldaq_range(range_v: tuple[float, float], uldaq: Any) -> Any:
    """The ``uldaq.Range`` member for a symmetric ADC range, e.g. (-5, 5) -> ``Range.BIP5VOLTS`` (table 2.2)."""
    low, high = float(range_v[0]), float(range_v[1])
    name = _BIPOLAR.get(high) if math.isclose(-low, high) else None
    if name is None:
        raise ParameterError(
            f"The 'adc_range_v' parameter of Sensors must be a symmetric range uldaq supports "
            f"(+-{sorted(_BIPOLAR)} V). Got {range_v!r} instead."
        )
    return getattr(uldaq.Range, name)


class DaqRig(Rig):
    """Gauge voltages from an MCC card (board number ``board``), channels and range from ``params.sensors``.

    Parameters
    ----------
    board : int
        Index into ``uldaq.get_daq_device_inventory(InterfaceType.ANY)``.
    input_mode : {"single_ended", "differential"}
        The thesis wires each gauge to "Ch n high" with a common analog ground: single-ended.
    pot_channel : int, optional
        Analog input the servo potentiometer is wired to (3.2.4; read in the same range as the gauges). None (the
        default): no pot channel, ``pot_v`` is NaN.
    actuator : callable, optional
        ``actuator(command)`` to send servo commands (e.g. a :class:`~flexdigit.rig.backends.serial_backend.SerialRig`'s
        ``write_command``); without it this rig is read-only.
    uldaq : module, optional
        The ``uldaq`` module (tests pass a fake); imported lazily otherwise.
    """

    name = "daq"

    def __init__(
        self,
        board: int = 0,
        params: RigParams | None = None,
        *,
        input_mode: str = "single_ended",
        pot_channel: int | None = None,
        actuator: Callable[[int], object] | None = None,
        uldaq: Any = None,
        **kwargs: Any,
    ) -> None:
        super().__init__(params, **kwargs)
        self.board = int(board)
        self.name = f"daq {self.board}"
        self._ul = uldaq if uldaq is not None else _import_uldaq()
        sensors = self.params.sensors
        self.channels = tuple(int(c) for c in sensors.adc_channels)
        self.range = uldaq_range(sensors.adc_range_v, self._ul)
        if pot_channel is not None:
            pot_channel = check_int(pot_channel, "pot_channel", "DaqRig", low=0)
            if pot_channel in self.channels:
                raise ParameterError(
                    f"The 'pot_channel' parameter of DaqRig must differ from the gauge channels {self.channels}. "
                    f"Got {pot_channel} instead."
                )
        self.pot_channel = pot_channel
        modes = {"single_ended": "SINGLE_ENDED", "differential": "DIFFERENTIAL"}
        if input_mode not in modes:
            raise ParameterError(
                f"The 'input_mode' parameter of DaqRig must be one of {sorted(modes)}. Got {input_mode!r}"
            )
        self.input_mode = getattr(self._ul.AiInputMode, modes[input_mode])
        self.actuator = actuator
        try:
            inventory = self._ul.get_daq_device_inventory(self._ul.InterfaceType.ANY)
        except Exception as exc:  # noqa: BLE001 - ULException is not an OSError
            raise RigError(f"{self.name}: cannot list MCC devices ({exc})") from exc
        if self.board >= len(inventory) or self.board < 0:
            self._closed = True
            raise RigError(f"{self.name}: no such MCC device; found {len(inventory)} device(s)")
        try:
            self._device = self._ul.DaqDevice(inventory[self.board])
            self._device.connect()
            self._ai = self._device.get_ai_device()
        except Exception as exc:  # noqa: BLE001
            self._closed = True
            raise RigError(f"{self.name}: cannot connect ({exc})") from exc

    def read_gauges(self) -> tuple[np.ndarray, float]:
        """``(gauges_v, pot_v)``: one ``a_in`` per gauge channel, then the pot channel (NaN without one), volts."""
        channels = self.channels if self.pot_channel is None else (*self.channels, self.pot_channel)
        try:
            values = [self._ai.a_in(ch, self.input_mode, self.range, self._ul.AInFlag.DEFAULT) for ch in channels]
        except Exception as exc:  # noqa: BLE001
            raise RigError(f"{self.name}: analog read failed ({exc})") from exc
        count = len(self.channels)  # one per gauge of the digit (params.sensors.adc_channels: 1 to 8)
        pot = float(values[count]) if self.pot_channel is not None else math.nan
        return np.asarray(values[:count], dtype=float), pot

    def _read(self) -> tuple[np.ndarray, float]:
        return self.read_gauges()

    def settings(self) -> dict[str, Any]:
        return {
            "backend": "daq",
            "board": self.board,
            "channels": list(self.channels),
            "pot_channel": self.pot_channel,
            "input_mode": str(getattr(self.input_mode, "name", self.input_mode)),
        }

    def _send(self, command: int) -> None:
        if self.actuator is None:
            raise RigError(f"{self.name}: a DAQ card alone cannot move the servo; open 'serial://PORT?daq=0' instead")
        self.actuator(command)

    def close(self) -> None:
        if self._closed:
            return
        if self.actuator is None:  # nothing to relax: read-only
            self._closed = True
            self._close()
            return
        super().close()

    def _close(self) -> None:
        device = getattr(self, "_device", None)
        if device is not None:
            try:
                device.disconnect()
                device.release()
            except Exception:  # noqa: BLE001 - releasing a vanished device must not raise
                pass


#: Options a ``daq://`` URL may carry (the other keyword arguments of :class:`DaqRig` are Python-only).
URL_OPTIONS = (
    UrlOption("pot", "int", low=0, none=True, help="the analog input the servo potentiometer is wired to"),
    UrlOption("input_mode", "choice", choices=("single_ended", "differential"), help="how the gauges are wired"),
)
#: Keyword arguments only Python passes.
PYTHON_OPTIONS = ("actuator", "uldaq", "clock", "sleep", "operator")


def from_url(location: str, params: RigParams | None, options: dict[str, Any]) -> DaqRig:
    """``daq://0`` (board number, default 0), ``daq://0?pot=3`` (pot on channel 3), ``&input_mode=differential``."""
    try:
        board = int(location or 0)
    except ValueError:
        board = -1
    if board < 0:
        raise ParameterError(f"daq://{location}: the board must be a number >= 0, e.g. daq://0")
    options = dict(options)
    if "pot" in options:
        options["pot_channel"] = options.pop("pot")
    return DaqRig(board, params, **options)
