"""``emogen study check`` refuses what ``emogen serve`` would refuse (files that are not there)
and the configs that pass every rule but fail silently in the field (issue #39): each case
named, with one block numbering (from 1, as the config file reads)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from emogen.cli.app import app
from emogen.errors import ConfigError
from emogen.study.check import check_study
from emogen.study.config import study_from_dict

BASE: dict[str, Any] = {
    "name": "field",
    "emotions": ["happy", "sad"],
    "completion": {"code": "C1", "redirect_url": "https://e.org/done?cc={code}"},
    "blocks": [
        {"task": "evolve", "name": "make"},
        {"task": "categorise", "name": "label", "own": True, "random": 2},
    ],
}


def errors(config: dict[str, Any], level: str = "error") -> list[str]:
    return [f.line() for f in check_study(study_from_dict(config)).findings if f.level == level]


def with_block(k: int, **changes: Any) -> dict[str, Any]:
    blocks = [dict(b) for b in BASE["blocks"]]
    blocks[k] = {**blocks[k], **changes}
    return {**BASE, "blocks": blocks}


def test_the_base_config_passes() -> None:
    assert errors(BASE) == [] and errors(BASE, "warning") == []


def test_a_face_table_or_model_that_is_not_there_is_an_error(tmp_path: Path) -> None:
    gone = tmp_path / "faces.csv"
    found = errors(with_block(1, file=str(gone)))
    assert found == [f"error: blocks[2].file: {gone} does not exist: `emogen serve` would refuse"]
    found = errors({**BASE, "model": str(tmp_path / "no-model")})
    assert found == [
        f"error: model: {tmp_path / 'no-model'} does not exist: `emogen serve` would refuse"
    ]
    gone.write_text("happy\n")  # there: the check passes it on (serve reads it with the rig)
    assert errors(with_block(1, file=str(gone))) == []


def test_a_redirect_that_sends_no_code_is_an_error() -> None:
    config = {**BASE, "completion": {"redirect_url": "https://app.prolific.com/c?cc={code}"}}
    (found,) = errors(config)
    assert "completion.redirect_url: fills in {code}, but completion.code is not set" in found
    assert errors({**BASE, "completion": {"redirect_url": "https://e.org/thanks"}}) == []


def test_a_participant_param_in_the_wrong_case_refuses_everyone() -> None:
    config = {**BASE, "participant_param": "prolific_pid", "participant_required": True}
    (found,) = errors(config)
    assert "'prolific_pid' is not what Prolific's links carry ('PROLIFIC_PID'" in found
    assert "every participant would be refused" in found
    (warned,) = errors({**BASE, "participant_param": "prolific_pid"}, "warning")
    assert "anonymous session" in warned


@pytest.mark.parametrize(
    ("config", "words"),
    [
        ({**BASE, "ga": {"generations": "10"}}, "'ga.generations' is text in quotes"),
        (with_block(1, others="8"), "'blocks[2].others' is text in quotes"),
        (with_block(1, own="true"), "'blocks[2].own' is text in quotes"),
        (with_block(1, points=1), "'blocks[2].points' must be >= 2; got 1"),
        (with_block(1, name="make"), "two blocks are named 'make'"),
        (with_block(1, labelz=["happy"]), "unknown key 'labelz' in [blocks[2]]"),
        ({**BASE, "name": "a b"}, "'name' must be 1-64 letters"),
    ],
)
def test_values_that_would_pass_quietly_are_refused(config: dict[str, Any], words: str) -> None:
    with pytest.raises(ConfigError) as err:
        study_from_dict(config, "study.toml")
    message = str(err.value)
    assert words in message
    assert message.count("got ") <= 1  # no doubled "got … got"
    assert "blocks.1" not in message and "blocks.2" not in message  # one block numbering


def test_block_texts_are_numbered_from_1() -> None:
    (found,) = errors(with_block(1, question="Which {emotions}?"))
    assert found.startswith("error: blocks[2].question: {emotions} is not filled in")


def test_the_rating_question_may_name_the_emotion() -> None:
    config = {**BASE, "rating": {"question": "How well does this face show {EMOTION}?"}}
    assert errors(config) == []
    (found,) = errors({**BASE, "rating": {"question": "How {EMOTIONS}?"}})
    assert "rating.question: {EMOTIONS}" in found and "did you mean {EMOTION}" in found


def test_serve_refuses_what_the_check_finds(tmp_path: Path) -> None:
    study = tmp_path / "study.toml"
    study.write_text(
        'name = "f"\nemotions = ["happy"]\n[completion]\nredirect_url = "https://e.org/?cc={code}"\n'
    )
    result = CliRunner().invoke(app, ["study", "check", str(study)])
    assert result.exit_code == 1 and "completion.code is not set" in result.output
    result = CliRunner().invoke(app, ["serve", str(study), "--port", "1"])
    assert result.exit_code == 2 and "completion.code is not set" in result.output


def test_the_rating_screen_names_the_emotion_asked_for(tmp_path: Path, ict_model: Any) -> None:
    from emogen.study.storage import Store
    from tests.study.drive import run_to_end, service_caller, study_service

    config = {
        "name": "rate",
        "emotions": ["sad"],
        "ga": {"generations": 1, "min_selections": 1, "max_selections": 4},
        "rating": {"question": "How well does this face show {EMOTION}?"},
    }
    store = Store(f"sqlite:///{tmp_path / 'rate.sqlite'}")
    try:
        service = study_service(study_from_dict(config), store, ict_model)
        token, state = service.create_session("P-1")
        state = run_to_end(
            state,
            service_caller(service, token),
            stop=lambda s: (s["trial"] or {}).get("status") == "rating",
        )
        assert state["view"]["rating"]["question"] == "How well does this face show SAD?"
        assert state["trial"]["prompt"] == "Make the face look SAD"  # the heading, kept above it
    finally:
        store.dispose()
