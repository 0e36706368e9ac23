"""The GA engine: ``ask()`` the population to show, ``tell(elite, others)`` the selection.

A participant (web) and a simulated observer drive it through the same two calls. The engine
records its integer seed and every selection; generation g of trial t draws from
:func:`emogen.rng.generation_rng` (seed, t, g), so a run replays exactly from its seed and its
selections (:meth:`Engine.replay`), and its state survives a JSON round trip
(:meth:`Engine.to_json` / :meth:`Engine.from_json`) byte for byte.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from emogen.config import GAConfig, validate_config
from emogen.errors import ConfigError, SelectionError
from emogen.ga.classical import classical_next_generation
from emogen.ga.init import first_generation, read_fixed_sets
from emogen.ga.operators import select
from emogen.ga.step import Offspring, next_generation
from emogen.model.rig import Rig
from emogen.rng import check_seed, generation_rng

STATE_SCHEMA = "emogen.ga.engine/1"


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Population:
    """The faces shown in one generation (arrays read-only).

    genes : (n_faces, n_genes) float in [0, 1], the rig's gene space
    weights : (n_faces, n_shapes) float, full weight vectors (``rig.expand(genes)``)
    ids : (n_faces,) int, unique within an engine
    parent_ids : (n_faces, 2) int, ids of the parents in the previous generation, -1 for none
      (a ``mean_all`` face's parents are all that generation's selections)
    operators : (n_faces,) str — ``elite``, ``mean_all``, ``mean_elite_other``, ``kept``,
      ``crossover_mutation``, ``random``, or ``init_<emotion>``, ``init_arbitrary``,
      ``init_neutral``, ``init_fixed`` in generation 0
    correctives : (n_faces, C) float or None, corrective weights computed after the core
      weights by the engine's corrector (combinational, then collision); never evolved
    corrective_names : (C,) names of those columns
    """

    genes: np.ndarray
    weights: np.ndarray
    ids: np.ndarray
    parent_ids: np.ndarray
    operators: np.ndarray
    generation: int
    trial: int
    correctives: np.ndarray | None = None
    corrective_names: tuple[str, ...] = ()

    def __len__(self) -> int:
        return len(self.ids)

    def row(self, i: int) -> Population:
        """Face ``i`` as a population of one."""
        s = slice(i, i + 1)
        return Population(
            _readonly(self.genes[s]),
            _readonly(self.weights[s]),
            _readonly(self.ids[s]),
            _readonly(self.parent_ids[s]),
            _readonly(self.operators[s]),
            self.generation,
            self.trial,
            None if self.correctives is None else _readonly(self.correctives[s]),
            self.corrective_names,
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "generation": self.generation,
            "trial": self.trial,
            "ids": self.ids.tolist(),
            "parent_ids": self.parent_ids.tolist(),
            "operators": self.operators.tolist(),
            "genes": self.genes.tolist(),
        }


#: Corrects a batch of full weight vectors before they are shown: returns
#: (corrective names, (n_faces, C) corrective weights). ``correctives_of(model)`` makes one.
Corrector = Callable[[np.ndarray], tuple[tuple[str, ...], np.ndarray]]


def correctives_of(model: Any) -> Corrector:
    """A corrector from a face model: :func:`emogen.correct.correct_faces` (combinational +
    collision correctives)."""
    from emogen.correct.faces import correct_faces

    def correct(weights: np.ndarray) -> tuple[tuple[str, ...], np.ndarray]:
        result = correct_faces(model, weights)
        return tuple(result.corrective_names), np.asarray(result.correctives, dtype=np.float64)

    return correct


class Engine:
    """EmoGen's GA for one participant (or one simulated run).

    With a ``corrector`` (:func:`correctives_of`), every population is corrected before it is
    shown and carries its corrective weights beside the core weights (deterministic: no rng,
    so replays stay exact).

    ``Engine(config, rig, seed)`` makes generation 0 at once. Generations are numbered
    g = 0 … G (``config.generations``); a selection is told in every one of them, and the elite
    of generation G is the :attr:`result` (G = 10 shows 11 populations). :meth:`reset` starts a
    new trial (re-initialised or with the same initial set, as configured).
    """

    def __init__(
        self, config: GAConfig, rig: Rig, seed: int, *, corrector: Corrector | None = None
    ) -> None:
        self._setup(config, rig, seed, corrector)
        self._population = self._initialise()

    def _setup(
        self, config: GAConfig, rig: Rig, seed: int, corrector: Corrector | None = None
    ) -> None:
        self.corrector = corrector
        self.config = config
        self.rig = rig
        self.seed = check_seed(seed)
        if config.identity != "generic" and config.identity not in rig.identities:
            raise ConfigError(
                f"identity must be one of: generic, {', '.join(sorted(rig.identities))}; "
                f"got '{config.identity}'"
            )
        self.gene_names = rig.gene_names(config.eye_motion)
        self._fixed_sets: np.ndarray | None = None
        if config.init.kind == "fixed":
            self._fixed_sets = read_fixed_sets(
                config.init.fixed_file,
                rig,
                eye_motion=config.eye_motion,
                population_size=config.population_size,
            )
            if config.init.fixed_option is not None and config.init.fixed_option > len(
                self._fixed_sets
            ):
                raise ConfigError(
                    f"init.fixed_option must be in [1, {len(self._fixed_sets)}] (sets in the "
                    f"file); got {config.init.fixed_option}"
                )
        self.trial = 0
        self.generation = 0
        self._next_id = 0
        self._selections: list[dict[str, Any]] = []
        self._initial: tuple[np.ndarray, np.ndarray] | None = None
        self.fixed_options: list[int] = []
        self._result: Population | None = None

    # ---- the loop ------------------------------------------------------------------------
    @property
    def done(self) -> bool:
        """True once generation G's selection has been told."""
        return self._result is not None

    @property
    def result(self) -> Population:
        """The elite of generation G (a population of one)."""
        if self._result is None:
            raise SelectionError(
                f"no result yet: the run is at generation {self.generation} of "
                f"{self.config.generations}"
            )
        return self._result

    @property
    def selections(self) -> list[dict[str, Any]]:
        """Every selection told so far: {trial, generation, elite, others} (face ids)."""
        return [dict(s, others=list(s["others"])) for s in self._selections]

    def ask(self) -> Population:
        """The population to show now."""
        if self.done:
            raise SelectionError(
                f"the run finished after generation {self.config.generations}; read .result "
                "or reset()"
            )
        return self._population

    def tell(self, elite: int | Sequence[int], others: Iterable[int] = ()) -> None:
        """The selection of the shown population: one elite id and the other selected ids.

        For the classical variant ``others`` is a fitness ranking (best first).
        """
        pop = self.ask()
        cfg = self.config
        e, o = select(
            pop.ids,
            elite,
            list(others),
            min_selections=cfg.min_selections,
            max_selections=cfg.max_selections,
        )
        self._selections.append(
            {
                "trial": self.trial,
                "generation": self.generation,
                "elite": int(pop.ids[e]),
                "others": [int(pop.ids[i]) for i in o],
            }
        )
        if self.generation >= cfg.generations:
            self._result = pop.row(e)
            return
        g = self.generation
        rng = generation_rng(self.seed, self.trial, g + 1)
        params = {
            "random_faces_count": cfg.random_faces,
            "mutation_genes": cfg.mutation_genes,
            "random_genes": cfg.random_genes,
        }
        off: Offspring
        if cfg.variant == "classical":
            off = classical_next_generation(pop.genes, np.r_[e, o], rng=rng, **params)
        else:
            off = next_generation(pop.genes, e, o, g, rng=rng, **params)
        parent_ids = np.where(off.parents >= 0, pop.ids[np.maximum(off.parents, 0)], -1)
        self.generation = g + 1
        self._population = self._make_population(off.genes, parent_ids, off.operators)

    def reset(self) -> Population:
        """Start a new trial at generation 0 (``init.on_reset``: reinitialise or keep)."""
        self.trial += 1
        self.generation = 0
        self._result = None
        self._population = self._initialise()
        return self._population

    # ---- internals -----------------------------------------------------------------------
    def _initialise(self) -> Population:
        if self.config.init.on_reset == "keep" and self._initial is not None:
            genes, labels = self._initial
        else:
            rng = generation_rng(self.seed, self.trial, 0)
            genes, labels, option = first_generation(
                self.config, self.rig, self._fixed_sets, rng=rng
            )
            if self._fixed_sets is not None:
                self.fixed_options.append(option)
            self._initial = (_readonly(genes), _readonly(labels))
        parents = np.full((len(genes), 2), -1, dtype=np.int64)
        return self._make_population(genes, parents, labels)

    def _make_population(
        self, genes: np.ndarray, parent_ids: np.ndarray, operators: np.ndarray
    ) -> Population:
        n = len(genes)
        ids = np.arange(self._next_id, self._next_id + n, dtype=np.int64)
        self._next_id += n
        genes = np.asarray(genes, dtype=np.float64)
        return self._corrected(
            Population(
                genes=_readonly(genes),
                weights=_readonly(self.rig.expand(genes, self.config.eye_motion)),
                ids=_readonly(ids),
                parent_ids=_readonly(np.asarray(parent_ids, dtype=np.int64)),
                operators=_readonly(np.asarray(operators, dtype=str)),
                generation=self.generation,
                trial=self.trial,
            )
        )

    def _corrected(self, population: Population) -> Population:
        """The population with its corrective weights, when the engine has a corrector."""
        if self.corrector is None:
            return population
        names, values = self.corrector(population.weights)
        return replace(
            population, correctives=_readonly(np.asarray(values)), corrective_names=tuple(names)
        )

    # ---- records -------------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        """Everything needed to resume (JSON-ready): config, seed, selections, current arrays."""
        from emogen import __version__

        init = None
        if self._initial is not None:
            init = {"genes": self._initial[0].tolist(), "labels": self._initial[1].tolist()}
        return {
            "schema": STATE_SCHEMA,
            "emogen_version": __version__,
            "config": self.config.model_dump(mode="json"),
            "rig": {"name": self.rig.name, "genes": list(self.gene_names)},
            "seed": self.seed,
            "trial": self.trial,
            "generation": self.generation,
            "next_id": self._next_id,
            "fixed_options": list(self.fixed_options),
            "selections": self.selections,
            "initial": init,
            "population": self._population.to_dict(),
            "result": None if self._result is None else self._result.to_dict(),
        }

    def to_json(self) -> str:
        return json.dumps(self.state())

    @classmethod
    def from_json(
        cls, text: str | dict[str, Any], rig: Rig, *, corrector: Corrector | None = None
    ) -> Engine:
        """Resume an engine saved with :meth:`to_json` (the rig must have the same genes)."""
        try:
            data = json.loads(text) if isinstance(text, str) else dict(text)
        except json.JSONDecodeError as exc:
            raise ConfigError(f"engine state is not valid JSON: {exc}") from None
        if data.get("schema") != STATE_SCHEMA:
            raise ConfigError(
                f"engine state schema must be '{STATE_SCHEMA}'; got {data.get('schema')!r}"
            )
        config = validate_config(GAConfig, data["config"], "(engine state)")
        self = cls.__new__(cls)
        self._setup(config, rig, data["seed"], corrector)
        if list(self.gene_names) != data["rig"]["genes"]:
            raise ConfigError(
                f"engine state was saved with rig '{data['rig']['name']}' genes "
                f"{data['rig']['genes']}; this rig '{rig.name}' has {list(self.gene_names)}"
            )
        self.trial = int(data["trial"])
        self.generation = int(data["generation"])
        self._next_id = int(data["next_id"])
        self.fixed_options = [int(o) for o in data["fixed_options"]]
        self._selections = [dict(s) for s in data["selections"]]
        if data["initial"] is not None:
            self._initial = (
                _readonly(np.array(data["initial"]["genes"], dtype=np.float64)),
                _readonly(np.array(data["initial"]["labels"], dtype=str)),
            )
        self._population = self._population_from(data["population"])
        self._result = None if data["result"] is None else self._population_from(data["result"])
        return self

    def _population_from(self, d: dict[str, Any]) -> Population:
        genes = np.array(d["genes"], dtype=np.float64).reshape(-1, len(self.gene_names))
        return self._corrected(
            Population(
                genes=_readonly(genes),
                weights=_readonly(self.rig.expand(genes, self.config.eye_motion)),
                ids=_readonly(np.array(d["ids"], dtype=np.int64)),
                parent_ids=_readonly(np.array(d["parent_ids"], dtype=np.int64).reshape(-1, 2)),
                operators=_readonly(np.array(d["operators"], dtype=str)),
                generation=int(d["generation"]),
                trial=int(d["trial"]),
            )
        )

    def save(self, path: Path) -> None:
        Path(path).write_text(self.to_json())

    @classmethod
    def replay(
        cls,
        config: GAConfig,
        rig: Rig,
        seed: int,
        selections: Iterable[dict[str, Any]],
        *,
        trial: int | None = None,
        corrector: Corrector | None = None,
    ) -> Engine:
        """A fresh engine driven through recorded selections ({trial, generation, elite, others}).

        ``trial``: the trial to end in, for a reset after the last recorded selection
        (default: the last recorded selection's trial).
        """
        engine = cls(config, rig, seed, corrector=corrector)
        for s in selections:
            while engine.trial < int(s["trial"]):
                engine.reset()
            if int(s["generation"]) != engine.generation or int(s["trial"]) != engine.trial:
                raise SelectionError(
                    f"recorded selection for generation {s['generation']} of trial {s['trial']} "
                    f"does not follow generation {engine.generation} of trial {engine.trial}"
                )
            engine.tell(int(s["elite"]), s["others"])
        if trial is not None:
            if trial < engine.trial:
                raise SelectionError(
                    f"trial must be at least the last recorded one ({engine.trial}); got {trial}"
                )
            while engine.trial < trial:
                engine.reset()
        return engine
