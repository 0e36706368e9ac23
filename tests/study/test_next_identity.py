"""The state names the next trial's identity (``trial.next_identity``, issue #39): the page
makes that face model ahead. Checked against the identities the participant is then shown."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tests.study.drive import command, run_to_end, study_service

STUDY: dict[str, Any] = {
    "name": "next",
    "emotions": ["happy", "sad"],
    "identities": ["female-medium", "male-medium"],
    "seed": 6,
    "ga": {"generations": 1, "min_selections": 1, "max_selections": 3},
    "blocks": [
        {"task": "evolve", "name": "f", "identities": ["female-medium"], "order": "fixed"},
        {"task": "evolve", "name": "m", "identities": ["male-medium"], "order": "fixed"},
        {"task": "categorise", "name": "label", "own": True},
    ],
}


def test_next_identity_is_the_identity_shown_next(ict_model, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    from emogen.study.config import study_from_dict
    from emogen.study.storage import Store

    store = Store(f"sqlite:///{tmp_path / 'next.sqlite'}")
    service = study_service(study_from_dict(STUDY), store, ict_model)
    token, state = service.create_session("P-1")
    seen: list[dict[str, Any]] = []

    def call(kind: str, body: dict[str, Any]) -> dict[str, Any]:
        out: dict[str, Any] = service.step(token, command(kind, body))
        if out["trial"] is not None:
            seen.append(out["trial"])
        return out

    run_to_end(state, call)
    store.dispose()
    shown = {t["position"]: t["identity"] for t in seen}
    assert len(shown) == 8  # 2 + 2 evolve trials, 4 own faces labelled
    said = {(t["position"], t["next_identity"]) for t in seen}
    for position, next_identity in said:
        if position == 3:  # the categorise block draws its faces when it starts: not known yet
            assert next_identity is None
        else:
            assert next_identity == shown.get(position + 1), (position, next_identity, shown)
    assert shown[1] == "female-medium" and shown[2] == "male-medium"
