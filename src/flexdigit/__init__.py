"""flexdigit: the cable-actuated flexible digit of Ward's 2004 MPhil thesis, as software.

Layout (data flows one way): ``params`` -> ``models`` -> ``twin`` -> ``identify`` -> ``control`` -> ``rig`` ->
``tactile`` -> ``report``; one command, ``flexdigit``, with a sub-command per domain.
"""

__version__ = "0.1.0"
