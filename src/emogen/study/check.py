"""``emogen study check STUDY.toml``: what a study config would do wrong before anyone takes part.

:func:`check_study` returns findings — *errors* (``emogen serve`` refuses to start on them) and
*warnings* — and the session length estimated from the design (:mod:`emogen.study.length`):

* every text's ``{placeholders}``: each text fills in only its own (the prompt ``{EMOTION}`` and
  ``{emotion}``; ``completion.redirect_url`` the code and the participant id, :data:`REDIRECT`;
  the others none), so any other is an error naming the text, with a did-you-mean;
* every emotion word against :data:`KNOWN_EMOTIONS` (a misspelt one is shown to participants as
  it is, e.g. FEARFULL), with a did-you-mean; a word the study means goes in
  ``custom_emotions``;
* the identities against the presets, the study's own and the rig (:func:`check_identities`).

:func:`never_matched` words the warning for a participant URL parameter that no link carries.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal

from emogen.appearance.identities import PRESETS
from emogen.errors import ConfigError, EmoGenError
from emogen.study.config import StudyConfig
from emogen.study.emotion_words import KNOWN_EMOTIONS
from emogen.study.length import SessionLength, session_length

if TYPE_CHECKING:
    from emogen.model.face import FaceModel
    from emogen.model.rig import Rig

#: Placeholders of ``completion.redirect_url`` besides the study's ``{participant_param}``:
#: what each is filled with.
REDIRECT = {
    "code": "the completion code",
    "completion_code": "the completion code",
    "participant": "the participant id",
    "participant_id": "the participant id",
}
PROMPT = {"EMOTION": "the emotion in capitals", "emotion": "the emotion as written"}
QUOTED = "'{}'"
_BRACED = re.compile(r"\{([^{}\s]{0,64})\}")
#: Anonymous sessions, none with an id from the link, before :func:`never_matched` warns.
NEVER_MATCHED_AFTER = 5


@dataclass(frozen=True)
class Finding:
    """One thing the check found: ``where`` is the config key (``completion.redirect_url``)."""

    level: Literal["error", "warning"]
    where: str
    message: str

    def line(self) -> str:
        return f"{self.level}: {self.where}: {self.message}"


@dataclass(frozen=True)
class CheckReport:
    findings: tuple[Finding, ...]
    length: SessionLength
    notes: tuple[str, ...] = field(default=())

    @property
    def errors(self) -> list[Finding]:
        return [f for f in self.findings if f.level == "error"]

    @property
    def warnings(self) -> list[Finding]:
        return [f for f in self.findings if f.level == "warning"]

    def lines(self) -> list[str]:
        """Findings first, then the length and notes; a last line with the verdict."""
        out = [f.line() for f in self.findings]
        out += [self.length.explained(), *self.notes]
        n_err, n_warn = len(self.errors), len(self.warnings)
        verdict = "not ready: fix the errors above" if n_err else "ready"
        out.append(
            f"{n_err} error{'s' * (n_err != 1)}, {n_warn} warning{'s' * (n_warn != 1)}: {verdict}"
        )
        return out


def _suggest(word: str, options: Iterable[str], form: str = "{{{}}}") -> str:
    """`` (did you mean {X}?)`` with the closest option (``form``: how it is written)."""
    options = list(options)
    close = difflib.get_close_matches(word, options, n=1, cutoff=0.6)
    if not close:
        lowered = {o.lower(): o for o in options}
        close = [lowered[w] for w in difflib.get_close_matches(word.lower(), lowered, n=1)]
    return f" (did you mean {form.format(close[0])}?)" if close else ""


def texts(config: StudyConfig) -> dict[str, str]:
    """Every text a participant reads (or is sent to), by config key."""
    out = {
        "title": config.title,
        "consent": config.consent,
        "instructions": config.instructions,
        "prompt": config.prompt,
        "rating.question": config.rating.question,
        "rating.low_label": config.rating.low_label,
        "rating.high_label": config.rating.high_label,
        "completion.message": config.completion.message,
    }
    if config.completion.code is not None:
        out["completion.code"] = config.completion.code
    if config.completion.redirect_url is not None:
        out["completion.redirect_url"] = config.completion.redirect_url
    for k, block in enumerate(config.blocks):
        out.update({f"blocks[{k + 1}].{key}": text for key, text in block.texts().items()})
    return out


def placeholders_of(config: StudyConfig, key: str) -> dict[str, str]:
    """The placeholders the text at ``key`` fills in, and with what."""
    # the study's prompt and rating question, and a block's own prompt, fill the same
    if key in ("prompt", "rating.question") or key.endswith("].prompt"):
        return PROMPT
    if key == "completion.redirect_url":
        return {**REDIRECT, config.participant_param: "the participant id"}
    return {}


def _fills(known: Mapping[str, str]) -> str:
    """``{code} or {completion_code} (the completion code), …``: placeholders by what they fill."""
    if not known:
        return "it fills in no placeholders"
    by_what: dict[str, list[str]] = {}
    for name, what in known.items():
        by_what.setdefault(what, []).append(f"{{{name}}}")
    return "it fills in " + ", ".join(f"{' or '.join(n)} ({w})" for w, n in by_what.items())


def check_placeholders(config: StudyConfig) -> list[Finding]:
    out = []
    for key, text in texts(config).items():
        known = placeholders_of(config, key)
        shown = (
            "the link would keep it as typed (a panel such as Prolific would not recognise it)"
            if key == "completion.redirect_url"
            else "participants would see it with its braces"
        )
        for name in dict.fromkeys(_BRACED.findall(text)):
            if name not in known:
                out.append(
                    Finding(
                        "error",
                        key,
                        (
                            f"{{{name}}} is not filled in: {shown}; "
                            f"{_fills(known)}{_suggest(name, known)}"
                        ),
                    )
                )
    return out


def study_emotions(config: StudyConfig) -> list[str]:
    """Every emotion word of the study: its emotions, its blocks' emotions and labels."""
    words = dict.fromkeys(config.emotions)
    for block in config.blocks:
        words.update(dict.fromkeys(block.words()))
    return list(words)


def check_emotions(config: StudyConfig) -> list[Finding]:
    out = []
    marked = {w.lower() for w in config.custom_emotions}
    for word in study_emotions(config):
        if word.lower() in KNOWN_EMOTIONS or word.lower() in marked:
            continue
        close = difflib.get_close_matches(word.lower(), sorted(KNOWN_EMOTIONS), n=1, cutoff=0.75)
        hint = f"did you mean '{close[0]}'? " if close else ""
        out.append(
            Finding(
                "error",
                "emotions",
                (
                    f"'{word}' is not an emotion word this check knows (participants would read "
                    f"{word.upper()}): {hint}if the study means it, add it to "
                    f'custom_emotions = ["{word}"]'
                ),
            )
        )
    words = {w.lower() for w in study_emotions(config)}
    for word in config.custom_emotions:
        if word.lower() not in words:
            out.append(
                Finding(
                    "warning",
                    "custom_emotions",
                    (
                        f"'{word}' is not among the study's emotions; custom_emotions only marks "
                        "emotion words the study uses"
                    ),
                )
            )
    return out


def check_files(config: StudyConfig) -> list[Finding]:
    """Every file the server reads at start must be there: the model, the rig, the GA's fixed
    initial faces and each block's face tables."""
    wanted: dict[str, Path | None] = {
        "model": config.model,
        "rig": config.rig,
        "ga.init.fixed_file": config.ga.init.fixed_file,
    }
    for k, block in enumerate(config.blocks):
        wanted.update({f"blocks[{k + 1}].{key}": p for key, p in block.files().items()})
    out = []
    for key, path in wanted.items():
        if path is None or Path(path).exists():
            continue
        out.append(Finding("error", key, f"{path} does not exist: `emogen serve` would refuse"))
    return out


#: URL parameters recruitment panels put in their links (exactly so: names are case-sensitive).
PANEL_PARAMS = {"PROLIFIC_PID": "Prolific", "workerId": "MTurk", "participantId": "CloudResearch"}


def check_field_traps(config: StudyConfig) -> list[Finding]:
    """What passes every rule but fails in the field: a redirect that sends no completion code,
    a participant parameter a panel never sends."""
    out = []
    url = config.completion.redirect_url or ""
    if config.completion.code is None and ("{code}" in url or "{completion_code}" in url):
        out.append(
            Finding(
                "error",
                "completion.redirect_url",
                "fills in {code}, but completion.code is not set: the panel would get an empty "
                "code and credit nobody (set [completion] code = …)",
            )
        )
    param = config.participant_param
    for name, panel in PANEL_PARAMS.items():
        if param != name and param.lower() == name.lower():
            refused = config.participant_required
            out.append(
                Finding(
                    "error" if refused else "warning",
                    "participant_param",
                    f"'{param}' is not what {panel}'s links carry ('{name}'; names are "
                    "case-sensitive): "
                    + (
                        "with participant_required = true every participant would be refused"
                        if refused
                        else "every participant would start an anonymous session"
                    ),
                )
            )
    return out


def check_launch(config: StudyConfig) -> list[Finding]:
    """What each block warns that a launch (many participants at once) would see."""
    conditions = config.conditions()
    minutes = session_length(conditions, config.ga.generations).words()
    wave = f"; the first wave is everyone who starts before the first session ends, {minutes} in"
    return [
        Finding("warning", key, message + wave)
        for k, block in enumerate(config.blocks)
        for key, message in block.warnings(k + 1, sum(c.block == k for c in conditions)).items()
    ]


def check_servable(config: StudyConfig) -> list[Finding]:
    """Blocks that participants cannot yet be shown: ``emogen serve`` refuses them."""
    return [
        Finding("error", f"blocks[{k + 1}]", why)
        for k, block in enumerate(config.blocks)
        if (why := block.unservable()) is not None
    ]


def check_study(config: StudyConfig, rig: Rig | None = None) -> CheckReport:
    """Every finding about ``config`` (with ``rig``: its identities' shapes too)."""
    findings = [
        *check_placeholders(config),
        *check_emotions(config),
        *check_files(config),
        *check_field_traps(config),
        *check_launch(config),
        *check_servable(config),
    ]
    if rig is not None:
        try:
            check_identities(config, rig)
        except ConfigError as exc:
            findings.append(Finding("error", "identities", str(exc)))
        for k, block in enumerate(config.study_blocks()):
            try:
                block.check_rig(rig, config.ga.eye_motion)
            except ValueError as exc:
                findings.append(Finding("error", f"blocks[{k + 1}]", str(exc)))
    else:
        findings += check_identity_names(config)
    anonymous = (
        "links without it are refused (participant_required = true)"
        if config.participant_required
        else "links without it start an anonymous session with a generated id "
        "(participant_required = true refuses them)"
    )
    notes = (f"participants open /?{config.participant_param}=PARTICIPANT_ID; {anonymous}",)
    return CheckReport(
        tuple(findings), session_length(config.conditions(), config.ga.generations), notes
    )


def check_identity_names(config: StudyConfig) -> list[Finding]:
    """Identity names against the presets and the study's own (without loading the model; a
    study with its own ``rig`` may have more presets: then a warning)."""
    known = sorted({*PRESETS, *config.identity})
    level: Literal["error", "warning"] = "error" if config.rig is None else "warning"
    return [
        Finding(
            level,
            "identities",
            (
                f"'{name}' is neither a preset ({', '.join(PRESETS)}) nor one of the study's own "
                f"[identity.NAME] tables{_suggest(name, known, QUOTED)}"
            ),
        )
        for name in config.all_identities()
        if name not in known
    ]


def never_matched(sources: Mapping[str, int], param: str, seen: Iterable[str] = ()) -> str | None:
    """The warning for a study whose links never carried the participant id (``sources``:
    sessions by ``participant_source``; ``seen``: the URL parameters links came with)."""
    anonymous, given = sources.get("generated", 0), sources.get("url", 0)
    if given or anonymous < NEVER_MATCHED_AFTER:
        return None
    others = [p for p in seen if p not in (param, "participant")]
    alike = [p for p in others if p.lower() == param.lower()] or difflib.get_close_matches(
        param, others, n=1
    )
    came = f"; the links came with ?{alike[0]}=, not ?{param}=" if alike else ""
    return (
        f"none of the {anonymous} sessions so far had a participant id from its link (the study "
        f"reads ?{param}=; parameter names are case-sensitive){came}: check the link the "
        "participants are given, or set participant_param; participant_required = true refuses "
        "links without the id"
    )


def check_identities(config: StudyConfig, rig: Rig, model: FaceModel | None = None) -> None:
    """Every identity of the study must be a preset or the lab's own, and every shape one the
    rig has (``generic`` or its presets); with ``model``, coefficient shapes must fit it."""
    shapes = ["generic", *sorted(rig.identities)]
    known = sorted({*PRESETS, *config.identity, *rig.identities})
    bad = [i for i in config.all_identities() if i not in known]
    if bad:
        raise ConfigError(
            f"invalid study config: 'identities' must be among the presets and the study's own "
            f"[identity.NAME] tables ({', '.join(known)}); got {bad}"
        )
    for name in config.all_identities():
        shape = config.identity_of(name).shape
        if isinstance(shape, str) and shape not in shapes:
            raise ConfigError(
                f"invalid study config: identity '{name}' has shape '{shape}'; the model's "
                f"shapes are {', '.join(shapes)} (or a list of identity coefficients)"
            )
        if model is not None and not isinstance(shape, str):
            try:
                model.resolve_identity(shape)
            except EmoGenError as exc:
                raise ConfigError(f"invalid study config: identity '{name}': {exc}") from None
