"""The GA engine: ``ask()`` the population to show, ``tell(elite, others)`` the selection.

A participant (web) and a simulated observer drive it through the same two calls. The engine
records its integer seed and every selection; generation g of attempt a (a restart within a
trial starts the next attempt) draws from :func:`emogen.rng.generation_rng` (seed, a, g), so a
run replays exactly from its seed and its selections (:meth:`Engine.replay`), and its state
survives a JSON round trip (:meth:`Engine.to_json` / :meth:`Engine.from_json`) byte for byte.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import orjson

from emogen.config import GAConfig
from emogen.errors import ConfigError, SelectionError
from emogen.ga.algorithm import Offspring, classical_next_generation, next_generation
from emogen.ga.corrector import Corrector, corrected, correctives_of
from emogen.ga.draws import CURRENT_STREAM, block_size, check_stream, generation_draws
from emogen.ga.genome import STATIC, Genome, genome_of
from emogen.ga.init import first_generation, read_fixed_sets
from emogen.ga.operators import select
from emogen.ga.population import Population, readonly
from emogen.ga.state import (
    STATE_SCHEMA,
    read_state_header,
    selection_attempt,
    state_data,
    stream_of_state,
)
from emogen.model.rig import Rig
from emogen.rng import check_seed, generation_rng

__all__ = [
    "STATE_SCHEMA",
    "Corrector",
    "Engine",
    "Population",  # re-exported: it lives in emogen.ga.population
    "correctives_of",
    "stream_of_state",
]


class Engine:
    """EmoGen's GA for one participant (or one simulated run).

    With a ``corrector`` (:func:`correctives_of`), every population is corrected before it is
    shown and carries its corrective weights beside the core weights (deterministic: no rng,
    so replays stay exact). Correction is done when a population is first asked for
    (:meth:`ask`, :attr:`result`), never for one only told about: an engine restored from its
    state (:meth:`from_json`) to take a selection corrects only the population it then shows.

    ``Engine(config, rig, seed)`` makes generation 0 at once. Generations are numbered
    g = 0 … G (``config.generations``); a selection is told in every one of them, and the elite
    of generation G is the :attr:`result` (G = 10 shows 11 populations). :meth:`reset` starts a
    new attempt (re-initialised or with the same initial set, as configured); :attr:`attempt`
    counts them from 0.
    """

    def __init__(
        self,
        config: GAConfig,
        rig: Rig,
        seed: int,
        *,
        corrector: Corrector | None = None,
        stream: int = CURRENT_STREAM,
        genome: Genome = STATIC,
    ) -> None:
        self._setup(config, rig, seed, corrector, stream, genome)
        self._show(self._initialise())

    def _setup(
        self,
        config: GAConfig,
        rig: Rig,
        seed: int,
        corrector: Corrector | None = None,
        stream: int = CURRENT_STREAM,
        genome: Genome = STATIC,
    ) -> None:
        self.corrector = corrector
        #: What a gene is (:mod:`emogen.ga.genome`); a dynamic genome is recorded in the state.
        self.genome = genome
        #: The GA's random stream (:mod:`emogen.ga.draws`), recorded in the state.
        self.stream = check_stream(stream)
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
        self.attempt = 0
        self.generation = 0
        self._next_id = 0
        self._selections: list[dict[str, Any]] = []
        self._initial: tuple[np.ndarray, np.ndarray] | None = None
        self.fixed_options: list[int] = []
        self._result: Population | None = None
        self._population: Population  # uncorrected: genes, ids, parents, operators
        self._corrected_population: Population | None = None  # made on the first ask()

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
        if self.corrector is not None and self._result.correctives is None:
            self._result = self._corrected(self._result)  # a face's correction is its own
        return self._result

    @property
    def selections(self) -> list[dict[str, Any]]:
        """Every selection told so far: {attempt, generation, elite, others} (face ids)."""
        return [dict(s, others=list(s["others"])) for s in self._selections]

    def ask(self) -> Population:
        """The population to show now."""
        self._check_running()
        if self._corrected_population is None:
            self._corrected_population = self._corrected(self._population)
        return self._corrected_population

    def _check_running(self) -> None:
        if self.done:
            raise SelectionError(
                f"the run finished after generation {self.config.generations}; read .result "
                "or reset()"
            )

    def _show(self, population: Population) -> None:
        """The population to show next (uncorrected; :meth:`ask` corrects it once)."""
        self._population = population
        self._corrected_population = None

    def tell(self, elite: int | Sequence[int], others: Iterable[int] = ()) -> None:
        """The selection of the shown population: one elite id and the other selected ids.

        For the classical variant ``others`` is a fitness ranking (best first).
        """
        self._check_running()
        pop = self._population  # the selection needs genes and ids only, not correctives
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
                "attempt": self.attempt,
                "generation": self.generation,
                "elite": int(pop.ids[e]),
                "others": [int(pop.ids[i]) for i in o],
            }
        )
        if self.generation >= cfg.generations:
            shown = self._corrected_population
            self._result = (shown if shown is not None else pop).row(e)
            return
        g, k = self.generation, pop.genes.shape[1]
        draws = generation_draws(
            [self.seed],
            self.attempt,
            g + 1,
            stream=self.stream,
            block=block_size(len(pop), k, cfg.mutation_genes, cfg.random_genes)
            + len(pop) * self.genome.extra_draws(k, cfg.mutation_genes),
        )
        params: dict[str, Any] = {
            "random_faces_count": cfg.random_faces,
            "mutation_genes": cfg.mutation_genes,
            "random_genes": cfg.random_genes,
            "genome": self.genome,
        }
        off: Offspring
        genes = pop.genes[None]
        if cfg.variant == "classical":
            off = classical_next_generation(genes, np.r_[e, o][None], draws=draws, **params)
        else:
            off = next_generation(genes, np.array([e]), o[None], g, draws=draws, **params)
        parents = off.parents[0]
        parent_ids = np.where(parents >= 0, pop.ids[np.maximum(parents, 0)], -1)
        self.generation = g + 1
        self._show(self._make_population(off.genes[0], parent_ids, off.operators))

    def reset(self) -> Population:
        """Start a new attempt at generation 0 (``init.on_reset``: reinitialise or keep)."""
        self.attempt += 1
        self.generation = 0
        self._result = None
        self._show(self._initialise())
        return self.ask()

    # ---- internals -----------------------------------------------------------------------
    def _initialise(self) -> Population:
        if self.config.init.on_reset == "keep" and self._initial is not None:
            genes, labels = self._initial
        else:
            rng = generation_rng(self.seed, self.attempt, 0)
            genes, labels, option = first_generation(
                self.config, self.rig, self._fixed_sets, rng=rng
            )
            genes = self.genome.initial(genes, rng)
            if self._fixed_sets is not None:
                self.fixed_options.append(option)
            self._initial = (readonly(genes), readonly(labels))
        parents = np.full((len(genes), 2), -1, dtype=np.int64)
        return self._make_population(genes, parents, labels)

    def _make_population(
        self, genes: np.ndarray, parent_ids: np.ndarray, operators: np.ndarray
    ) -> Population:
        n = len(genes)
        ids = np.arange(self._next_id, self._next_id + n, dtype=np.int64)
        self._next_id += n
        genes = np.asarray(genes, dtype=np.float64)
        return Population(
            genes=readonly(genes),
            weights=readonly(self._expand(genes)),
            ids=readonly(ids),
            parent_ids=readonly(np.asarray(parent_ids, dtype=np.int64)),
            operators=readonly(np.asarray(operators, dtype=str)),
            generation=self.generation,
            attempt=self.attempt,
        )

    def _expand(self, genes: np.ndarray) -> np.ndarray:
        """Full weight vectors of genes (a dynamic face's: its amplitudes, the peak profile)."""
        return self.rig.expand(self.genome.amplitude(genes), self.config.eye_motion)

    def _corrected(self, population: Population) -> Population:
        """The population with its corrective weights, when the engine has a corrector."""
        if self.corrector is None:
            return population
        expand = lambda genes: self.rig.expand(genes, self.config.eye_motion)  # noqa: E731
        return corrected(population, self.corrector, self.genome, expand)

    # ---- records -------------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        """Everything needed to resume (JSON-ready): config, seed, selections, current arrays."""
        from emogen import __version__

        init = None
        if self._initial is not None:
            init = {"genes": self._initial[0].tolist(), "labels": self._initial[1].tolist()}
        spec = self.genome.to_dict()
        dynamic = {} if spec is None else {"genome": spec}  # a static state is as before
        return {
            "schema": STATE_SCHEMA,
            "stream": self.stream,
            **dynamic,
            "collision_solver": getattr(self.corrector, "solver", None),
            "emogen_version": __version__,
            "config": self.config.model_dump(mode="json"),
            "rig": {"name": self.rig.name, "genes": list(self.gene_names)},
            "seed": self.seed,
            "attempt": self.attempt,
            "generation": self.generation,
            "next_id": self._next_id,
            "fixed_options": list(self.fixed_options),
            "selections": self.selections,
            "initial": init,
            "population": self._population.to_dict(),
            "result": None if self._result is None else self._result.to_dict(),
        }

    def to_json(self) -> str:
        """:meth:`state` as compact JSON by orjson (~20x cheaper than Python's encoder; exact
        round trip); it would write a non-finite number as null, so such a state is refused."""
        arrays = {
            "initial": None if self._initial is None else self._initial[0],
            "population": self._population.genes,
            "result": None if self._result is None else self._result.genes,
        }
        for part, genes in arrays.items():
            if genes is not None and not np.isfinite(genes).all():
                raise ValueError(f"engine state: the {part} genes have a non-finite value")
        return orjson.dumps(self.state()).decode()

    @classmethod
    def from_json(
        cls, text: str | dict[str, Any], rig: Rig, *, corrector: Corrector | None = None
    ) -> Engine:
        """Resume an engine saved with :meth:`to_json` (the rig must have the same genes)."""
        data = state_data(text)
        self = cls.__new__(cls)
        config, seed, stream = read_state_header(data)
        self._setup(config, rig, seed, corrector, stream, genome_of(data.get("genome")))
        if list(self.gene_names) != data["rig"]["genes"]:
            raise ConfigError(
                f"engine state was saved with rig '{data['rig']['name']}' genes "
                f"{data['rig']['genes']}; this rig '{rig.name}' has {list(self.gene_names)}"
            )
        self.attempt = int(data["attempt"])
        self.generation = int(data["generation"])
        self._next_id = int(data["next_id"])
        self.fixed_options = [int(o) for o in data["fixed_options"]]
        self._selections = [dict(s) for s in data["selections"]]
        if data["initial"] is not None:
            self._initial = (
                readonly(np.array(data["initial"]["genes"], dtype=np.float64)),
                readonly(np.array(data["initial"]["labels"], dtype=str)),
            )
        self._show(self._population_from(data["population"]))
        self._result = None if data["result"] is None else self._population_from(data["result"])
        return self

    def _population_from(self, d: dict[str, Any]) -> Population:
        tail = () if self.genome.params is None else (len(self.genome.params),)
        return Population.from_dict(d, (len(self.gene_names), *tail), self._expand)

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
        attempt: int | None = None,
        corrector: Corrector | None = None,
        stream: int = CURRENT_STREAM,
        genome: Genome = STATIC,
    ) -> Engine:
        """A fresh engine driven through recorded selections ({attempt, generation, elite,
        others}).

        ``attempt``: the attempt to end in, for a restart after the last recorded selection
        (default: the last recorded selection's attempt). ``stream``: the stream the run was
        recorded with (:func:`stream_of_state` reads it off a stored state).
        """
        engine = cls(config, rig, seed, corrector=corrector, stream=stream, genome=genome)
        for s in selections:
            at = selection_attempt(s)
            while engine.attempt < at:
                engine.reset()
            if int(s["generation"]) != engine.generation or at != engine.attempt:
                raise SelectionError(
                    f"recorded selection for generation {s['generation']} of attempt {at} "
                    f"does not follow generation {engine.generation} of attempt {engine.attempt}"
                )
            engine.tell(int(s["elite"]), s["others"])
        if attempt is not None:
            if attempt < engine.attempt:
                raise SelectionError(
                    f"attempt must be at least the last recorded one ({engine.attempt}); "
                    f"got {attempt}"
                )
            while engine.attempt < attempt:
                engine.reset()
        return engine
