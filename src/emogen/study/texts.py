"""The participant page's default texts of a study config: consent and instructions."""

from __future__ import annotations

from typing import Any

from emogen.tasks.registry import DEFAULT_TASK, TASKS, task_named

#: The consent text of studies written before the length was estimated (still accepted as
#: "the default" when given explicitly); new studies get :func:`default_consent`.
DEFAULT_CONSENT = (
    "This study asks you to make faces show emotions by choosing among computer-generated "
    "faces. It takes about 10 minutes. Your choices and their timings are recorded with a "
    "participant id; no other personal data are collected. You may stop at any time by "
    "closing the page.\n\nBy clicking “I agree” you consent to take part."
)
#: The default consent text of a study that collects the browser's user agent.
DEFAULT_CONSENT_USER_AGENT = DEFAULT_CONSENT.replace(
    "no other personal data are collected.",
    "your browser's identification string (its user agent: browser, version and operating "
    "system) is also recorded; no other personal data are collected.",
)


def default_consent(minutes: str, *, user_agent: bool) -> str:
    """The default consent text with the session length estimated from the design
    (``minutes``: :meth:`emogen.study.length.SessionLength.words`, e.g. "about 10–16 minutes");
    ``user_agent``: the text saying the browser's user agent is recorded."""
    text = DEFAULT_CONSENT_USER_AGENT if user_agent else DEFAULT_CONSENT
    return text.replace("about 10 minutes", minutes)


#: A consent text of a study collecting user agents must name it with one of these (any case).
USER_AGENT_WORDS = ("user agent", "user-agent", "useragent")
#: The default instructions: the default task's (the GA's).
DEFAULT_INSTRUCTIONS: str = task_named(DEFAULT_TASK).instructions


def default_instructions(blocks: Any) -> str | None:
    """The default instructions of a study of these ``[[blocks]]`` tables, where they differ
    from the default task's (None: its text; a study of that task alone keeps its hash): each
    other task's instructions, after the default task's where the study has both."""
    names = [b.get("task", DEFAULT_TASK) if isinstance(b, dict) else None for b in blocks or ()]
    others = [TASKS[n] for n in dict.fromkeys(names) if n in TASKS and n != DEFAULT_TASK]
    if not others:
        return None
    if DEFAULT_TASK not in names:
        return " ".join("In this study " + t.instructions for t in others)
    return DEFAULT_INSTRUCTIONS + "".join(
        "\n\nIn another part of the study " + t.instructions for t in others
    )
