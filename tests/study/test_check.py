"""``emogen study check``: each defect the field trial of issue #32 found in a study config is
named before anyone takes part; a correct study passes (unit level: no model needed)."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from emogen.cli.app import app
from emogen.study.check import check_study, never_matched
from emogen.study.config import demo_study_path, load_study_config, study_from_dict
from emogen.study.view import completion
from emogen.tasks.registry import TASKS

FIELD = {
    "name": "field",
    "emotions": ["happy", "sad", "angry", "fearful"],
    "identities": ["female-light", "male-dark"],
    "ga": {"generations": 10},
    "completion": {
        "code": "C1A2B3",
        "redirect_url": "https://app.prolific.com/submissions/complete?cc={completion_code}",
    },
}


def _where(config: dict, level: str = "error") -> list[str]:
    report = check_study(study_from_dict(config))
    return [f"{f.where}: {f.message}" for f in report.findings if f.level == level]


def test_a_correct_study_passes() -> None:
    assert _where(FIELD) == [] and _where(FIELD, "warning") == []
    assert check_study(load_study_config(demo_study_path())).errors == []


def test_redirect_url_fills_in_the_completion_code() -> None:
    # before: the literal "{completion_code}" was sent to Prolific, which credited nobody
    url = completion(study_from_dict(FIELD), "P-1")["redirect_url"]
    assert url == "https://app.prolific.com/submissions/complete?cc=C1A2B3"
    cfg = study_from_dict(
        {
            **FIELD,
            "completion": {
                "code": "X 1",
                "redirect_url": "https://e.org/?a={code}&p={participant_id}&q={PROLIFIC_PID}",
            },
        }
    )
    assert completion(cfg, "P/2")["redirect_url"] == "https://e.org/?a=X%201&p=P%2F2&q=P%2F2"


def test_unknown_placeholders_in_any_text_are_errors() -> None:
    found = _where({**FIELD, "prompt": "Make the face look {EMOTIONS}"})
    assert len(found) == 1 and found[0].startswith("prompt: {EMOTIONS} is not filled in")
    assert "did you mean {EMOTION}?" in found[0]
    url = "https://app.prolific.com/submissions/complete?cc={cc}"
    found = _where({**FIELD, "completion": {"code": "C1", "redirect_url": url}})
    assert len(found) == 1 and found[0].startswith("completion.redirect_url: {cc} is not filled")
    assert "{code} or {completion_code} (the completion code)" in found[0]
    found = _where({**FIELD, "consent": "Takes {minutes} minutes.", "title": "Study {name}"})
    assert [f.split(":")[0] for f in found] == ["title", "consent"]
    assert all("fills in no placeholders" in f for f in found)
    blocks = [{"task": "evolve"}, {"task": "categorise", "own": True, "question": "Which {x}?"}]
    assert [f.split(":")[0] for f in _where({**FIELD, "blocks": blocks})] == [
        "blocks[2].question"
    ]  # numbered from 1


def test_emotion_words_are_checked_with_did_you_mean() -> None:
    # before: "fearfull" was shown to participants as FEARFULL
    found = _where({**FIELD, "emotions": ["happy", "fearfull"]})
    assert len(found) == 1 and "'fearfull'" in found[0] and "did you mean 'fearful'?" in found[0]
    assert 'custom_emotions = ["fearfull"]' in found[0]
    assert _where({**FIELD, "emotions": ["happy", "smug"], "custom_emotions": ["smug"]}) == []
    warned = _where({**FIELD, "custom_emotions": ["smug"]}, "warning")
    assert len(warned) == 1 and warned[0].startswith("custom_emotions: 'smug' is not among")


def test_identity_names_are_checked_without_the_model() -> None:
    found = _where({**FIELD, "identities": ["female-light", "male-drak"]})
    assert len(found) == 1 and "did you mean 'male-dark'?" in found[0]


def _minutes(selection: int, rating: int) -> tuple[int, int]:
    """The stated assumptions (6–9 s a selection screen, 3–5 s a rating, 1–2 min of pages),
    by hand."""
    low = selection * 6 + rating * 3 + 60
    high = selection * 9 + rating * 5 + 120
    return round(low / 60), -(-high // 60)


def test_the_session_length_is_estimated_from_the_design() -> None:
    report = check_study(study_from_dict(FIELD))
    # 4 emotions × 2 identities, generations 0 … 10 shown: 8 × 11 = 88 selection screens
    others = {kind: 0 for task in TASKS.values() for kind in task.screens}  # no other block
    assert report.length.screens == {**others, "selection": 88, "rating": 8}
    assert {"selection", "rating", "categorise"} <= set(others)
    assert report.length.minutes == _minutes(88, 8) == (10, 16)
    assert "88 selection screens × 6–9 s" in "\n".join(report.lines())
    small = study_from_dict(
        {**FIELD, "emotions": ["happy"], "identities": ["generic"], "ga": {"generations": 3}}
    )
    assert check_study(small).length.minutes == _minutes(4, 1)


def test_the_default_consent_states_the_estimated_length() -> None:
    # before: "about 10 minutes" whatever the design
    consent = study_from_dict(FIELD).consent
    assert "It takes about 10–16 minutes." in consent
    big = study_from_dict({**FIELD, "repetitions": 2})
    low, high = _minutes(176, 16)
    assert f"It takes about {low}–{high} minutes." in big.consent and high > 16
    agent = study_from_dict({**FIELD, "collect_user_agent": True}).consent
    assert "about 10–16 minutes" in agent and "user agent" in agent
    own = study_from_dict({**FIELD, "consent": "Our own text."})
    assert own.consent == "Our own text."  # a study's own text is left alone


def test_new_keys_at_their_defaults_leave_the_config_hash_alone() -> None:
    base = study_from_dict({**FIELD, "consent": "x"})
    explicit = study_from_dict(
        {
            **FIELD,
            "consent": "x",
            "custom_emotions": [],
            "participant_required": False,
            "counterbalance": "hash",
        }
    )
    assert base.config_hash() == explicit.config_hash()
    assert "counterbalance" not in base.canonical_json()


def test_never_matched_names_the_parameter_the_links_carry() -> None:
    assert never_matched({"generated": 4}, "PROLIFIC_PID") is None  # too few yet
    assert never_matched({"generated": 9, "url": 1}, "PROLIFIC_PID") is None
    text = never_matched({"generated": 5}, "PROLIFIC_PID", ["STUDY_ID", "prolific_pid"])
    assert text is not None and "none of the 5 sessions" in text
    assert "the links came with ?prolific_pid=, not ?PROLIFIC_PID=" in text


def test_cli_check_exits_1_and_names_every_error(tmp_path: Path) -> None:
    study = tmp_path / "study.toml"
    study.write_text(
        'name = "field"\nemotions = ["happy", "fearfull"]\nprompt = "Look {EMOTIONS}"\n'
        '[completion]\ncode = "C1"\nredirect_url = "https://e.org/?cc={completion_code}"\n'
    )
    result = CliRunner().invoke(app, ["study", "check", str(study)])
    assert result.exit_code == 1, result.output
    assert "{EMOTIONS}" in result.output and "'fearfull'" in result.output
    assert "2 errors, 0 warnings: not ready" in result.output
    assert "a session takes about" in result.output
    study.write_text('name = "field"\nemotions = ["happy", "fearful"]\n')
    result = CliRunner().invoke(app, ["study", "check", str(study)])
    assert result.exit_code == 0 and "0 errors, 0 warnings: ready" in result.output


@pytest.mark.parametrize("given", ["{EMOTION}", "{emotion}"])
def test_the_prompt_placeholders_are_filled(given: str) -> None:
    cfg = study_from_dict({**FIELD, "prompt": f"Show {given}"})
    assert "{" not in cfg.prompt_for("happy") and _where({**FIELD, "prompt": f"Show {given}"}) == []


def test_serve_refuses_a_study_with_errors_before_it_loads(tmp_path: Path) -> None:
    study = tmp_path / "study.toml"
    study.write_text('name = "field"\nemotions = ["happy"]\nprompt = "Look {EMOTIONS}"\n')
    result = CliRunner().invoke(app, ["serve", str(study), "--port", "1"])
    assert result.exit_code == 2, result.output
    assert "has 1 error" in result.output and "{EMOTIONS}" in result.output
    assert f"emogen study check {study}" in result.output


def test_cli_check_refuses_a_gene_the_rig_lacks(tmp_path: Path, ict_dir: Path) -> None:
    """A block naming a gene the model's rig has not (gsp's ``dimensions``) is an error of the
    check, as serve and simulate refuse it; the genes the ICT rig has pass."""
    study = tmp_path / "study.toml"
    body = (
        f'name = "field"\nemotions = ["happy"]\nmodel = "{ict_dir}"\n'
        '[[blocks]]\ntask = "gsp"\ndimensions = [{}]\n'
    )
    study.write_text(body.replace("{}", '"jawOpen", "smileWide"'))
    result = CliRunner().invoke(app, ["study", "check", str(study)])
    assert result.exit_code == 1, result.output
    assert "blocks[1]: dimensions: ['smileWide'] are not genes of rig" in result.output
    assert "1 error, 0 warnings: not ready" in result.output
    db = f"sqlite:///{tmp_path / 'pilot.sqlite'}"  # the simulated pilot refuses it the same way
    result = CliRunner().invoke(app, ["study", "simulate", str(study), "--database-url", db])
    assert result.exit_code == 2 and "blocks[1].dimensions: ['smileWide']" in result.output
    study.write_text(body.replace("{}", '"jawOpen", "mouthSmile"'))
    result = CliRunner().invoke(app, ["study", "check", str(study)])
    assert result.exit_code == 0, result.output
