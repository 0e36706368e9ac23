"""The participant page's default texts of a study config: consent and instructions."""

from __future__ import annotations

from typing import Any

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
DEFAULT_INSTRUCTIONS = (
    "You will see ten faces at a time. Click the face that best shows the emotion you are asked "
    "for: it is marked with a star (★). Then click any other faces that are also acceptable: "
    "they are marked with a tick (✓); the ★ on a face makes that face the best. Press “Next "
    "round” and new faces will be bred from the ones you chose. After the last round you rate "
    "the final face.\n\nKeyboard: Tab or "
    "the arrow keys move between faces, Enter or Space selects, B makes a face the best one."
)

#: What the default instructions add for a categorise block (and say alone without the GA).
CATEGORISE_INSTRUCTIONS = (
    "you will see one face at a time. Choose the emotion it shows (the number keys 1–9 choose "
    "too); where you are asked, also say how intense the expression is and how sure you are, "
    "then press “Continue”."
)


def default_instructions(blocks: Any) -> str | None:
    """The default instructions of a study of these ``[[blocks]]`` tables, where they differ
    from the GA's (None: the GA's text; a study without categorise blocks keeps its hash)."""
    tasks = [b.get("task", "evolve") if isinstance(b, dict) else None for b in blocks or ()]
    if "categorise" not in tasks:
        return None
    if "evolve" not in tasks:
        return "In this study " + CATEGORISE_INSTRUCTIONS
    return DEFAULT_INSTRUCTIONS + "\n\nIn another part of the study " + CATEGORISE_INSTRUCTIONS
