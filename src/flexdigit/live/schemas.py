"""JSON Schemas of the live page's recorded estimates (``/flexdigit/shape`` and ``/flexdigit/contact``).

The rig's own samples have theirs in :mod:`flexdigit.rig.recording`; these are the channels the live session adds,
so any MCAP tool can decode and check them. Units are SI; null where a value is not known.
"""

from __future__ import annotations

_NUMBER = {"type": "number"}
_NULLABLE = {"type": ["number", "null"]}
_POINT = {"type": "array", "items": _NUMBER, "minItems": 2, "maxItems": 2}

#: The shape estimate (:meth:`flexdigit.shape.shape.ShapeEstimate.row`), every 5 mm along the digit.
SHAPE_SCHEMA = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "flexdigit.Shape",
    "description": "The digit's centre line from the three gauges (flexdigit.shape.shape), m, with its "
    "standard deviation normal to the line; the load found, if any.",
    "type": "object",
    "properties": {
        "t": {"type": "number", "description": "rig time, s"},
        "s_m": {"type": "array", "items": _NUMBER, "description": "arc positions from the clamp, m"},
        "centre_line_m": {"type": "array", "items": _POINT, "description": "(along, towards the cable), m"},
        "sd_normal_m": {"type": "array", "items": _NULLABLE},
        "tip_m": {"type": "array", "items": _NULLABLE, "minItems": 2, "maxItems": 2},
        "tip_sd_m": {"type": "array", "items": _NULLABLE, "minItems": 2, "maxItems": 2},
        "tip_angle_deg": _NULLABLE,
        "tension_n": _NULLABLE,
        "consistent": {"type": "boolean"},
        "contact": {"type": "boolean"},
        "load_kind": {"enum": ["weight", "press", "none"]},
        "load_position_from_base_m": _NULLABLE,
        "load_position_sd_m": _NULLABLE,
        "load_position_interval_m": {"type": ["array", "null"], "items": _NULLABLE},
        "load_force_n": _NULLABLE,
        "load_force_sd_n": _NULLABLE,
        "load_mass_kg": _NULLABLE,
    },
    "required": ["t", "s_m", "centre_line_m", "sd_normal_m", "contact"],
}

_SOURCE = {
    "type": "object",
    "properties": {
        "source": {"type": "string"},
        "contact": {"type": "boolean"},
        "position_from_base_m": _NULLABLE,
        "position_sd_m": _NULLABLE,
        "position_interval_m": {"type": ["array", "null"], "items": _NULLABLE},
        "force_n": _NULLABLE,
        "mass_kg": _NULLABLE,
        "located": {"type": "boolean"},
        "consistent": {"type": "boolean"},
        "note": {"type": "string"},
    },
    "required": ["source", "contact", "located", "note"],
}

#: The contact estimates, one per source (beam inversion, a trained network, ...).
CONTACT_SCHEMA = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "flexdigit.Contact",
    "description": "Where the digit is touched, per estimator: position from the clamp (m) with its standard "
    "deviation and the interval consistent with the readings, force (N), and whether it is located.",
    "type": "object",
    "properties": {"t": {"type": "number"}, "sources": {"type": "array", "items": _SOURCE}},
    "required": ["t", "sources"],
}
