"""The rig backends and their transports, each behind the :class:`~flexdigit.rig.base.Rig` contract.

``sim`` (the twin), ``serial`` (the thesis's servo board, :mod:`~flexdigit.rig.backends.servo_board` its frame),
``daq`` (a USB DAQ), ``stream`` (a microcontroller ADC over USB serial: :mod:`~flexdigit.rig.backends.stream_framing`
encodes and decodes its lines, :mod:`~flexdigit.rig.backends.stream_emulator` plays a board), ``replay`` (a
recorded log), ``hil`` (the reference firmware on simavr, joined to the twin) and ``board`` (the same firmware on a
real Uno; :mod:`~flexdigit.rig.backends.board_link` what it says). :func:`flexdigit.rig.base.open_rig` chooses
one by name or URL.
"""

from flexdigit._lazy import lazy_exports

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "SimRig": "flexdigit.rig.backends.sim_backend",
        "SerialRig": "flexdigit.rig.backends.serial_backend",
        "DaqRig": "flexdigit.rig.backends.daq_backend",
        "StreamRig": "flexdigit.rig.backends.stream_backend",
        "ReplayRig": "flexdigit.rig.backends.replay_backend",
        "HilRig": "flexdigit.rig.backends.hil_backend",
        "BoardRig": "flexdigit.rig.backends.board_backend",
        "BoardState": "flexdigit.rig.backends.board_link",
        "StreamEmulator": "flexdigit.rig.backends.stream_emulator",
        "Framing": "flexdigit.rig.backends.servo_board",
        "encode_frame": "flexdigit.rig.backends.servo_board",
        "FrameDecoder": "flexdigit.rig.backends.servo_board",
        "LineDecoder": "flexdigit.rig.backends.stream_framing",
        "encode_line": "flexdigit.rig.backends.stream_framing",
    },
)
