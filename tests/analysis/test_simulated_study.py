"""The fast simulated study (the test bed of the analyses of people): its planted answers are
there, checked with plain numpy on its own output tables."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.analysis.simulated_study import PeopleDesign, as_people, simulate_people
from emogen.errors import ConfigError
from emogen.tasks.simulated import SimulatedDesign


@pytest.fixture(scope="module")
def rig(ict_model):  # type: ignore[no-untyped-def]
    return ict_model.rig


SMALL = PeopleDesign(participants=12, repetitions=2, identities=("female-medium",))


def test_same_seed_same_study(rig) -> None:  # type: ignore[no-untyped-def]
    a, b = simulate_people(SMALL, rig, seed=3), simulate_people(SMALL, rig, seed=3)
    assert a.faces.equals(b.faces) and a.responses.equals(b.responses)
    c = simulate_people(SMALL, rig, seed=4)
    assert not np.allclose(a.faces[list(a.genes)], c.faces[list(c.genes)])


def test_shape_of_a_study(rig) -> None:  # type: ignore[no-untyped-def]
    sim = simulate_people(SMALL, rig, seed=1)
    f = sim.faces
    # every participant made every emotion `repetitions` times
    counts = f.groupby(["participant_id", "emotion"]).size()
    assert len(counts) == 12 * 4 and (counts == 2).all()
    r = sim.responses
    per = r.groupby(["participant_id", "source"]).size().unstack()
    assert (per["own"] == 8).all() and (per["other"] == 8).all() and (per["random"] == 8).all()
    # others' faces are never one's own, and balanced over emotions
    other = r[r["source"] == "other"]
    assert (other["source_participant_id"] != other["participant_id"]).all()
    assert (other.groupby(["participant_id", "intended"]).size() == 2).all()
    people = as_people(sim)
    assert people.n_participants == 12 and people.emotions == tuple(sorted(SMALL.emotions))


def test_final_faces_land_near_their_makers_prototypes(rig) -> None:  # type: ignore[no-untyped-def]
    sim = simulate_people(SMALL, rig, seed=2)
    g = sim.faces[list(sim.genes)].to_numpy()
    p = sim.faces["participant_id"].str[4:].astype(int).to_numpy() - 1
    e = sim.faces["emotion"].map({x: i for i, x in enumerate(SMALL.emotions)}).to_numpy()
    own = np.linalg.norm(g - sim.prototypes[p, e], axis=1)
    other = np.linalg.norm(g - sim.prototypes[(p + 1) % 12, e], axis=1)
    assert np.mean(own < other) > 0.75  # the GA found the participant, not the population


def test_planted_group_shift_moves_that_gene_only(rig) -> None:  # type: ignore[no-untyped-def]
    design = PeopleDesign(
        participants=20,
        repetitions=1,
        identities=("female-medium",),
        categorise=False,
        groups=("a", "b"),
        shifts={"b": {"happy": {"browInnerUp": 0.6}}},
        participant=SimulatedDesign(spread=0.1),
    )
    sim = simulate_people(design, rig, seed=5)
    happy = sim.faces[sim.faces["emotion"] == "happy"]
    means = happy.groupby("group")[["g_browInnerUp", "g_mouthSmile"]].mean()
    assert means.loc["b", "g_browInnerUp"] - means.loc["a", "g_browInnerUp"] > 0.15
    assert abs(means.loc["b", "g_mouthSmile"] - means.loc["a", "g_mouthSmile"]) < 0.2


def test_shuffled_prototypes_remove_the_own_face_advantage(rig) -> None:  # type: ignore[no-untyped-def]
    def advantage(shuffle: bool) -> float:
        d = PeopleDesign(
            participants=30,
            repetitions=1,
            identities=("female-medium",),
            shuffle_prototypes=shuffle,
        )
        r = simulate_people(d, rig, seed=6).responses
        acc = r[r["source"] != "random"].groupby("source")["correct"].mean()
        return float(acc["own"] - acc["other"])

    assert advantage(False) > 0.1
    assert abs(advantage(True)) < 0.08


def test_bad_designs_are_refused() -> None:
    with pytest.raises(ConfigError, match="participants"):
        PeopleDesign(participants=1)
    with pytest.raises(ConfigError, match="group"):
        PeopleDesign(groups=("a",), shifts={"b": {}})
