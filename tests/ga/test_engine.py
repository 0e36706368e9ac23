"""The engine: ask/tell over generations 0..G, records, JSON state, exact replay."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from emogen.config import GAConfig, InitConfig
from emogen.errors import ConfigError, SelectionError
from emogen.ga.engine import Engine, Population


def choose(pop: Population, rng: np.random.Generator, max_n: int = 10) -> tuple[int, list[int]]:
    """A random valid selection (the elite and 0..max_n-1 others)."""
    n = int(rng.integers(1, max_n + 1))
    picked = rng.permutation(pop.ids)[:n]
    return int(picked[0]), [int(i) for i in picked[1:]]


def fingerprint(pop: Population) -> bytes:
    return b"|".join(
        [
            pop.genes.tobytes(),
            pop.weights.tobytes(),
            pop.ids.tobytes(),
            pop.parent_ids.tobytes(),
            "/".join(pop.operators.tolist()).encode(),
            f"{pop.generation},{pop.attempt}".encode(),
        ]
    )


def assert_symmetric(rig, pop: Population, eye_motion: bool) -> None:
    index = {s: i for i, s in enumerate(rig.shape_names)}
    for gene in rig.genes:
        cols = pop.weights[:, [index[s] for s in gene.shapes]]
        assert np.all(cols == cols[:, :1]), gene.name
    for shape in rig.disabled_shapes(eye_motion):
        assert np.all(pop.weights[:, index[shape]] == 0), shape


def test_a_whole_run(ict_model) -> None:
    engine = Engine(GAConfig(), ict_model.rig, seed=7)
    rng = np.random.default_rng(0)
    seen_ids: set[int] = set()
    previous: Population | None = None
    shown = 0
    while not engine.done:
        pop = engine.ask()
        assert pop.generation == shown and len(pop) == 10
        assert pop.genes.shape == (10, 30) and pop.weights.shape == (10, 57)
        assert not seen_ids & set(pop.ids.tolist())
        seen_ids |= set(pop.ids.tolist())
        if previous is None:
            assert np.all(pop.parent_ids == -1)
            assert all(op.startswith("init_") for op in pop.operators)
        else:
            parents = pop.parent_ids[pop.parent_ids >= 0]
            assert set(parents.tolist()) <= set(previous.ids.tolist())
            assert pop.operators[0] == "elite"
            assert pop.operators[6:].tolist() == ["random"] * 4
        elite, others = choose(pop, rng)
        engine.tell(elite, others)
        previous = pop
        shown += 1
    assert shown == 11  # generations 0..10
    assert engine.result.ids.tolist() == [engine.selections[-1]["elite"]]
    assert engine.result.generation == 10 and engine.result.genes.shape == (1, 30)
    with pytest.raises(SelectionError, match="finished after generation 10"):
        engine.ask()
    with pytest.raises(SelectionError, match="finished"):
        engine.tell(0)


def test_population_arrays_are_read_only(ict_model) -> None:
    pop = Engine(GAConfig(), ict_model.rig, seed=1).ask()
    with pytest.raises(ValueError, match="read-only"):
        pop.genes[0, 0] = 1.0


def test_result_before_the_end(ict_model) -> None:
    with pytest.raises(SelectionError, match="no result yet"):
        _ = Engine(GAConfig(), ict_model.rig, seed=1).result


def run(engine: Engine, selections_seed: int, steps: int) -> list[bytes]:
    rng = np.random.default_rng(selections_seed)
    out = []
    for _ in range(steps):
        pop = engine.ask()
        out.append(fingerprint(pop))
        engine.tell(*choose(pop, rng))
    return out


@pytest.mark.parametrize(
    "config",
    [
        GAConfig(),
        GAConfig(eye_motion=False, init=InitConfig(kind="fixed")),
        GAConfig(variant="classical", population_size=9, random_faces=2, max_selections=9),
    ],
)
def test_same_seed_same_selections_same_populations(ict_model, config) -> None:
    rig = ict_model.rig
    a = run(Engine(config, rig, seed=42), 5, 11)
    b = run(Engine(config, rig, seed=42), 5, 11)
    assert a == b
    c = run(Engine(config, rig, seed=43), 5, 11)
    assert a[0] != c[0]


def test_json_round_trip_is_exact(ict_model) -> None:
    rig = ict_model.rig
    config = GAConfig(init=InitConfig(activation_range=(2, 9)))
    a = Engine(config, rig, seed=2**62 + 12345)
    rng = np.random.default_rng(8)
    for _ in range(4):
        a.tell(*choose(a.ask(), rng))
    text = a.to_json()
    b = Engine.from_json(text, rig)
    assert b.to_json() == text
    assert fingerprint(b.ask()) == fingerprint(a.ask())
    # both continue identically, through the end and a reset
    rng_a, rng_b = np.random.default_rng(9), np.random.default_rng(9)
    for engine, r in ((a, rng_a), (b, rng_b)):
        while not engine.done:
            engine.tell(*choose(engine.ask(), r))
        engine.reset()
        engine.tell(*choose(engine.ask(), r))
    assert fingerprint(a.ask()) == fingerprint(b.ask())
    assert fingerprint(a.result if a.done else a.ask()) == fingerprint(b.ask())
    assert a.to_json() == b.to_json()
    # the saved state is plain JSON with the record fields
    state = json.loads(text)
    assert (
        state["seed"] == 2**62 + 12345
        and state["schema"] == "emogen.ga.engine/4"
        and state["stream"] == 2
    )
    assert state["config"]["init"]["activation_range"] == [2, 9]
    assert len(state["selections"]) == 4


def test_replay_from_seed_and_selections(ict_model) -> None:
    rig = ict_model.rig
    config = GAConfig()
    a = Engine(config, rig, seed=11)
    rng = np.random.default_rng(3)
    history = []
    for _ in range(2):
        while not a.done:
            pop = a.ask()
            history.append(fingerprint(pop))
            a.tell(*choose(pop, rng))
        a.reset()
    history.append(fingerprint(a.ask()))
    b = Engine.replay(config, rig, 11, a.selections, attempt=a.attempt)
    assert fingerprint(b.ask()) == history[-1]
    assert b.attempt == 2 and b.selections == a.selections
    # and a replay stopped half way shows that generation's population
    c = Engine.replay(config, rig, 11, a.selections[:5])
    assert fingerprint(c.ask()) == history[5]


def test_replay_rejects_out_of_order_records(ict_model) -> None:
    with pytest.raises(SelectionError, match="does not follow"):
        Engine.replay(
            GAConfig(),
            ict_model.rig,
            1,
            [{"attempt": 0, "generation": 3, "elite": 0, "others": []}],
        )


def test_reset_reinitialise_or_keep(ict_model) -> None:
    rig = ict_model.rig
    for on_reset, same in (("reinitialise", False), ("keep", True)):
        engine = Engine(GAConfig(init=InitConfig(on_reset=on_reset)), rig, seed=5)
        first = engine.ask()
        engine.tell(int(first.ids[0]))
        again = engine.reset()
        assert again.generation == 0 and again.attempt == 1 and engine.generation == 0
        assert np.array_equal(again.genes, first.genes) is same
        assert not set(again.ids.tolist()) & set(first.ids.tolist())
        if same:
            assert again.operators.tolist() == first.operators.tolist()


def test_selection_limits_from_config(ict_model) -> None:
    engine = Engine(GAConfig(min_selections=2, max_selections=3), ict_model.rig, seed=1)
    ids = engine.ask().ids.tolist()
    with pytest.raises(SelectionError, match=r"must be in \[2, 3\]; got 1"):
        engine.tell(ids[0])
    with pytest.raises(SelectionError, match=r"must be in \[2, 3\]; got 4"):
        engine.tell(ids[0], ids[1:4])
    with pytest.raises(SelectionError, match="exactly one elite"):
        engine.tell([ids[0], ids[1]], ids[2:3])
    engine.tell(ids[0], ids[1:3])
    assert engine.generation == 1


def test_generations_and_population_size_configurable(ict_model) -> None:
    cfg = GAConfig(
        generations=3, population_size=12, random_faces=5, mutation_genes=1, random_genes=3
    )
    engine = Engine(cfg, ict_model.rig, seed=1)
    rng = np.random.default_rng(1)
    counts = 0
    while not engine.done:
        pop = engine.ask()
        assert len(pop) == 12
        if pop.generation > 0:
            assert (pop.operators == "random").sum() == 5
            assert np.all((pop.genes[pop.operators == "random"] > 0).sum(1) <= 3)
        engine.tell(*choose(pop, rng))
        counts += 1
    assert counts == 4
    # protocol init with 12 faces: 8 emotional, 3 arbitrary, 1 neutral
    first = Engine(cfg, ict_model.rig, seed=2).ask()
    assert (first.operators == "init_arbitrary").sum() == 3


def test_identity_and_eye_motion(ict_model) -> None:
    rig = ict_model.rig
    assert Engine(GAConfig(identity="female"), rig, seed=1).config.identity == "female"
    with pytest.raises(ConfigError, match="identity must be one of: generic, female, male"):
        Engine(GAConfig(identity="alien"), rig, seed=1)
    pop = Engine(GAConfig(eye_motion=False), rig, seed=1).ask()
    assert pop.genes.shape == (10, 24)
    assert_symmetric(rig, pop, eye_motion=False)


def test_fixed_init_engine(ict_model) -> None:
    cfg = GAConfig(init=InitConfig(kind="fixed", fixed_option=3))
    engine = Engine(cfg, ict_model.rig, seed=1)
    assert engine.ask().operators.tolist() == ["init_fixed"] * 10
    assert engine.fixed_options == [3]
    with pytest.raises(ConfigError, match=r"fixed_option must be in \[1, 3\]"):
        Engine(GAConfig(init=InitConfig(kind="fixed", fixed_option=4)), ict_model.rig, seed=1)


def test_state_text_is_python_json_compacted_and_older_texts_resume(ict_model) -> None:
    """The stored text (orjson) parses to exactly the state (every float the same bits); a
    state written by an earlier version (Python's json: spaced, 1e-05 where orjson writes
    0.00001) resumes to the same engine; a non-finite gene is refused, not written as null."""
    rig = ict_model.rig
    a = Engine(GAConfig(), rig, seed=2**63 - 1)
    rng = np.random.default_rng(3)
    for _ in range(3):
        a.tell(*choose(a.ask(), rng))
    text = a.to_json()
    assert json.loads(text) == a.state() and ", " not in text
    older = json.dumps(a.state())  # how states were written before
    assert older != text and Engine.from_json(older, rig).to_json() == text
    broken = a.ask().genes.copy()
    broken[3, 1] = np.nan
    a._population = replace(a._population, genes=broken)
    with pytest.raises(ValueError, match="population genes have a non-finite value"):
        a.to_json()


def test_bad_seed_and_foreign_state(ict_model, tiny_model) -> None:
    with pytest.raises(ConfigError, match="seed must be"):
        Engine(GAConfig(), ict_model.rig, seed=-1)
    text = Engine(GAConfig(), ict_model.rig, seed=1).to_json()
    with pytest.raises(ConfigError, match="saved with rig 'ict-facekit'"):
        Engine.from_json(text, tiny_model.rig)
    with pytest.raises(ConfigError, match="schema"):
        Engine.from_json("{}", ict_model.rig)


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**63 - 1),
    selection_seed=st.integers(0, 2**32 - 1),
    eye_motion=st.booleans(),
    variant=st.sampled_from(["emogen", "classical"]),
)
def test_every_face_is_symmetric_and_in_range(
    ict_model, seed, selection_seed, eye_motion, variant
) -> None:
    rig = ict_model.rig
    engine = Engine(GAConfig(eye_motion=eye_motion, variant=variant), rig, seed=seed)
    rng = np.random.default_rng(selection_seed)
    while not engine.done:
        pop = engine.ask()
        assert_symmetric(rig, pop, eye_motion)
        assert np.all((pop.genes >= 0) & (pop.genes <= 1))
        assert np.all((pop.genes[pop.operators == "random"] > 0).sum(1) <= 6)
        engine.tell(*choose(pop, rng))


def test_an_engine_state_names_its_collision_solver(ict_model) -> None:
    """``collision_solver`` of a stored state: recorded (2 now), 1 for a ``/1`` state recorded
    before solvers were numbered, and an unknown or missing number is an error naming it (not a
    silent fallback)."""
    from emogen.ga.engine import correctives_of
    from emogen.ga.state import collision_solver_of_state

    engine = Engine(GAConfig(), ict_model.rig, 5, corrector=correctives_of(ict_model))
    engine.ask()
    state = json.loads(engine.to_json())
    assert state["collision_solver"] == 2 and collision_solver_of_state(state) == 2
    assert collision_solver_of_state({**state, "collision_solver": 1}) == 1
    missing = {k: v for k, v in state.items() if k != "collision_solver"}
    with pytest.raises(ConfigError, match="collision_solver"):
        collision_solver_of_state(missing)
    with pytest.raises(ConfigError, match="collision solver must be one of \\[1, 2\\]; got 7"):
        collision_solver_of_state({**state, "collision_solver": 7})


@pytest.mark.parametrize("schema", ["emogen.ga.engine/2", "emogen.ga.engine/3", None])
def test_a_state_of_an_unreleased_or_unknown_schema_is_refused(ict_model, schema) -> None:
    """Only ``/4`` states and the ``/1`` states of recorded studies load; ``/2`` and ``/3`` were
    never released and name the attempt ``trial``."""
    state = json.loads(Engine(GAConfig(), ict_model.rig, 5).to_json())
    state["schema"] = schema
    with pytest.raises(ConfigError, match="engine state schema must be one of"):
        Engine.from_json(json.dumps(state), ict_model.rig)
