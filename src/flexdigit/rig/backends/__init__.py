"""The rig backends and their transports, each behind the :class:`~flexdigit.rig.base.Rig` contract.

``sim`` (the twin), ``serial`` (the thesis's servo board, :mod:`~flexdigit.rig.backends.servo_board` its frame),
``daq`` (a USB DAQ), ``stream`` (a microcontroller ADC over USB serial: :mod:`~flexdigit.rig.backends.stream_framing`
encodes and decodes its lines, :mod:`~flexdigit.rig.backends.stream_emulator` plays a board) and ``replay`` (a
recorded log). :func:`flexdigit.rig.base.open_rig` chooses one by name or URL.
"""
