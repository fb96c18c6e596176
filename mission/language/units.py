"""Units of the mission language: durations (`90s`, `15min`, `3h`, `1h30min`) and percentages (`20%`).

>>> parse_duration("15min"), parse_duration("1h30min"), parse_duration(90)
(900.0, 5400.0, 90.0)
>>> parse_percent("20%"), parse_percent(12.5)
(20.0, 12.5)
"""

from __future__ import annotations

import re
from typing import Annotated, Any

from pydantic import BeforeValidator, WithJsonSchema

_UNIT_SECONDS = {"ms": 0.001, "s": 1.0, "sec": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0}
_PART = re.compile(r"\s*(\d+(?:\.\d+)?)\s*(ms|sec|s|min|h|d)")
DURATION_PATTERN = r"^\s*(\d+(\.\d+)?\s*(ms|sec|s|min|h|d)\s*)+$"


def parse_duration(value: Any) -> float:
    """Seconds from a number (already seconds) or a string such as `90s`, `15min`, `3h`, `1h30min`."""
    if isinstance(value, bool):
        raise ValueError("expected a duration such as 90s, 15min or 3h")
    if isinstance(value, (int, float)):
        if value < 0:
            raise ValueError("a duration cannot be negative")
        return float(value)
    if not isinstance(value, str) or not re.fullmatch(DURATION_PATTERN, value):
        raise ValueError(f"expected a duration such as 90s, 15min or 3h, got {value!r}")
    return sum(float(n) * _UNIT_SECONDS[u] for n, u in _PART.findall(value))


def parse_percent(value: Any) -> float:
    """Percent from `20%` or a bare number (taken as percent); must lie in [0, 100]."""
    if isinstance(value, bool):
        raise ValueError("expected a percentage such as 20%")
    if isinstance(value, str):
        text = value.strip()
        if not re.fullmatch(r"\d+(\.\d+)?\s*%", text):
            raise ValueError(f"expected a percentage such as 20%, got {value!r}")
        value = float(text.rstrip("%").strip())
    if not isinstance(value, (int, float)):
        raise ValueError(f"expected a percentage such as 20%, got {value!r}")
    if not 0.0 <= float(value) <= 100.0:
        raise ValueError(f"a percentage must lie between 0% and 100%, got {value}")
    return float(value)


Duration = Annotated[
    float,
    BeforeValidator(parse_duration),
    WithJsonSchema(
        {"anyOf": [{"type": "number", "minimum": 0}, {"type": "string", "pattern": DURATION_PATTERN}],
         "description": "seconds, or a string such as 90s, 15min, 3h"}
    ),
]
Percent = Annotated[
    float,
    BeforeValidator(parse_percent),
    WithJsonSchema(
        {"anyOf": [{"type": "number", "minimum": 0, "maximum": 100},
                   {"type": "string", "pattern": r"^\d+(\.\d+)?\s*%$"}],
         "description": "a percentage such as 20%"}
    ),
]
