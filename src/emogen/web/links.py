"""Which URL parameters participants' links carry: a study whose ``participant_param`` no link
matches (``?prolific_pid=`` for ``PROLIFIC_PID``) makes every participant anonymous, so the
server logs a warning once (and the dashboard shows it, :mod:`emogen.web.researcher`) after
:data:`~emogen.study.check.NEVER_MATCHED_AFTER` anonymous sessions and none with an id."""

from __future__ import annotations

import logging
import re
from collections import Counter
from collections.abc import Iterable
from typing import Any

from emogen.study.check import never_matched
from emogen.study.sessions import StudyService

log = logging.getLogger("emogen.web")
#: Parameter names kept per worker (names only, never values: they may be participant ids).
MAX_NAMES = 32
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,63}")


def note_parameters(seen: Counter[str], names: Iterable[str]) -> None:
    """Count the landing page's URL parameter names (at most :data:`MAX_NAMES` different)."""
    for name in names:
        if _NAME.fullmatch(name) and (name in seen or len(seen) < MAX_NAMES):
            seen[name] += 1


def never_matched_warning(state: Any, service: StudyService) -> str | None:
    """The warning for this study now (None: links carry the id, or too few sessions yet)."""
    seen = [name for name, _ in state.link_parameters.most_common()]
    return never_matched(service.participant_sources(), service.ctx.config.participant_param, seen)


def warn_never_matched(state: Any, service: StudyService) -> None:
    """After an anonymous session: log :func:`never_matched_warning` once per worker."""
    if state.never_matched_warned:
        return
    text = never_matched_warning(state, service)
    if text is not None:
        state.never_matched_warned = True
        log.warning("study '%s': %s", service.ctx.config.name, text)
