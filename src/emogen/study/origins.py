"""The web origins allowed to embed a study (``embed_origins``): pages elsewhere — a jsPsych
experiment on JATOS, Pavlovia or a lab's own server — that call the study's API from the
participant's browser (CORS). Each is an exact origin: scheme, host and port, nothing else.
"""

from __future__ import annotations

import re

_ORIGIN = re.compile(
    r"^(?P<scheme>https?)://(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9]([A-Za-z0-9.-]{0,251}[A-Za-z0-9])?)"
    r"(?::(?P<port>[0-9]{1,5}))?$"
)


def check_origin(value: str) -> str:
    """``value`` if it is one exact web origin (``https://experiments.example.org``,
    ``http://localhost:8080``), else a ValueError naming it and what an origin is."""
    if value == "*" or "*" in value:
        raise ValueError(
            f"embed_origins must name exact origins, no wildcard; got {value!r} "
            "(list each site that embeds the study, e.g. 'https://jatos.example.org')"
        )
    match = _ORIGIN.match(value)
    if match is None or value != value.strip():
        raise ValueError(
            f"embed_origins entries must be origins 'scheme://host[:port]' (http or https, no "
            f"path, no trailing '/'); got {value!r}"
        )
    port = match.group("port")
    if port is not None and not 0 < int(port) < 65536:
        raise ValueError(f"embed_origins entry {value!r} has port {port}; expected 1-65535")
    return value.lower()
