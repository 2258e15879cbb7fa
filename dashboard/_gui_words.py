"""GUI wording for messages that drive_link writes for its command line, and values shown in
the unit of the GUI's own fields.

drive_link's errors name CLI flags and commands (``--force``, ``drive-link disable``); a person
at the web bench has checkboxes and buttons instead, so :func:`gui_text` says which. A DCF
diff lists raw SI values (``1.48e-05 → 2e-05``); :func:`shown` gives them in the unit the
GUI's fields use (14.8 µH → 20 µH).
"""

from __future__ import annotations

import math
import re

__all__ = ["CONFIG_FORCE_LABEL", "diff_rows", "gui_text", "shown"]

#: the Config tab's checkbox that does what the CLI's --force does for a DCF
CONFIG_FORCE_LABEL = "Load even with poor margins"

#: (pattern, GUI wording) for CLI phrases in drive_link's messages
_CLI_PHRASES = (
    (re.compile(r"\s*\(--force loads it anyway\)"),
     f" (tick '{CONFIG_FORCE_LABEL}' to load it anyway)"),
    (re.compile(r"run `drive-link disable` first"), "press Disable first"),
    (re.compile(r"`drive-link enable`"), "Enable"),
    (re.compile(r"\bunless --force\b"), "unless 'Override margin check' is ticked"),
    (re.compile(r"\s*\(?--force[^;)]*\)?"), " (tick the override checkbox to go ahead)"),
)

#: SI unit of an OD object → (unit shown in the GUI's fields, factor)
_DISPLAY = {
    "H": ("µH", 1e6),
    "Ohm": ("mΩ", 1e3),
    "100 us": ("µs", 100.0),
    "N*m": ("N·m", 1.0),
    "1": ("", 1.0),
}


def gui_text(message: str) -> str:
    """``message`` with drive_link's command-line wording replaced by the GUI's controls."""
    for pattern, words in _CLI_PHRASES:
        message = pattern.sub(words, message)
    return message


def shown(value: object, unit: str) -> str:
    """``value`` (as the drive stores it, in the OD's ``unit``) in the unit of the GUI's
    fields, e.g. (1.48e-05, "H") → "14.8 µH", (0.0062, "Ohm") → "6.2 mΩ"."""
    disp, factor = _DISPLAY.get(unit, (unit, 1.0))
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"{value} {disp}".strip()
    if isinstance(value, int) and factor == 1.0:
        return f"{value} {disp}".strip()
    x = float(value) * factor
    txt = f"{x:.6g}" if math.isfinite(x) else str(x)
    return f"{txt} {disp}".strip()


def diff_rows(changes: list[dict], limit: int = 12) -> str:
    """"name: drive → file" per changed object (values in the fields' units), at most
    ``limit`` of them and how many more."""
    rows = "; ".join(
        f"{c['name']}: {shown(c['drive'], c.get('unit', ''))} → "
        f"{shown(c['file'], c.get('unit', ''))}"
        for c in changes[:limit]
    )
    more = f" (+{len(changes) - limit} more)" if len(changes) > limit else ""
    return rows + more
