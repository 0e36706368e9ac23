"""Simulated studies with a known answer, fast enough to run a hundred: the test bed of every
analysis of people (reliability, categorisation models, per-gene inference, perceptive fields).

The participants are those of ``emogen study simulate`` (:mod:`emogen.tasks.simulated`): each
holds their own prototype per emotion (the population prototype of the rig's building blocks,
their emotion's genes moved by N(0, ``spread``²)), makes every face with the GA choosing by gene
ED with softmax choice noise ``select_noise``, and labels faces by a softmax over the distances
to their prototypes (``label_noise``). What differs from ``emogen study simulate`` is only the
path: the GA runs of all participants advance together in the vectorised simulator
(:func:`emogen.simulate.vectorised.simulate_runs`, without corrections) instead of through the
study service and its database one step at a time, so a 50-participant study takes about a
second instead of minutes. The data come out in the shape of a study export's final faces and
``responses`` tables (:mod:`emogen.analysis.people`).

Known answers the design can plant:

* ``groups``: participants are split evenly over named groups; a group's population prototype of
  an emotion is moved by ``shifts[group][emotion] = {gene: amount}`` (a group effect on those
  genes only);
* ``identity_shifts``: faces made on an identity are made toward the prototype moved by
  ``identity_shifts[identity][emotion]`` (an identity effect within participants);
* ``shuffle_prototypes``: each participant labels faces with another participant's prototypes
  (a derangement): own faces are then no nearer their labeller than others' faces — the null of
  the own-distance effect.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from emogen.analysis.elites import simulate_elites
from emogen.analysis.people import People
from emogen.config import GAConfig, MetricConfig, SimulationConfig
from emogen.errors import ConfigError
from emogen.model.rig import Rig
from emogen.rng import _to_seed
from emogen.study.simulate import participant_id as participant_name
from emogen.tasks.simulated import SimulatedDesign, SimulatedParticipant, population_prototypes

Shifts = Mapping[str, Mapping[str, Mapping[str, float]]]


@dataclass(frozen=True)
class PeopleDesign:
    """A simulated study's design and its planted effects (see the module docstring)."""

    emotions: tuple[str, ...] = ("happy", "sad", "angry", "fearful")
    identities: tuple[str, ...] = ("female-medium", "male-medium")
    participants: int = 50
    repetitions: int = 3
    participant: SimulatedDesign = field(default_factory=SimulatedDesign)
    groups: tuple[str, ...] = ()
    shifts: Shifts = field(default_factory=dict)
    identity_shifts: Shifts = field(default_factory=dict)
    #: categorise block: own faces (all), ``others`` faces of other participants (balanced
    #: over emotions), ``random`` faces (uniform: 3–8 genes active at U(0, 1))
    categorise: bool = True
    others: int = 8
    random: int = 8
    shuffle_prototypes: bool = False
    ga: GAConfig = field(default_factory=GAConfig)

    def __post_init__(self) -> None:
        if self.participants < 2 or self.repetitions < 1:
            raise ConfigError(
                f"a simulated study needs >= 2 participants and >= 1 repetition; got "
                f"{self.participants} and {self.repetitions}"
            )
        unknown = sorted(set(self.shifts) - set(self.groups))
        if unknown:
            raise ConfigError(f"shifts name group(s) {unknown} not in groups {self.groups}")


@dataclass(frozen=True, eq=False)
class SimulatedPeople:
    """faces: one row per final face (the columns of :attr:`emogen.analysis.people.People.faces`,
    genes ``g_*`` and weights ``w_*``); responses: one row per categorise answer (as exported);
    prototypes: (participants, emotions, genes) each participant's own prototypes (the truth);
    group: (participants,) each participant's group ('' without groups)."""

    faces: pd.DataFrame
    responses: pd.DataFrame
    prototypes: np.ndarray
    group: np.ndarray
    genes: tuple[str, ...]
    weights: tuple[str, ...]
    seed: int


def simulate_people(design: PeopleDesign, rig: Rig, *, seed: int) -> SimulatedPeople:
    """One simulated study of ``design`` on ``rig`` from ``seed`` (same seed, same data)."""
    root = np.random.SeedSequence(seed)
    proto_ss, ga_ss, label_ss = root.spawn(3)
    rng = np.random.default_rng(proto_ss)
    eye = design.ga.eye_motion
    gene_names = rig.gene_names(eye)
    protos, group = _prototypes(design, rig, rng)
    rows, targets = _trial_plan(design, rig, protos, gene_names)
    final = _run_ga(design, rig, targets, ga_ss)
    genes = rig.contract(final, eye)
    gcols = tuple(f"g_{g}" for g in gene_names)
    wcols = tuple(f"w_{s}" for s in rig.shape_names)
    faces = pd.concat(
        [
            pd.DataFrame(rows),
            pd.DataFrame(genes, columns=list(gcols)),
            pd.DataFrame(final, columns=list(wcols)),
        ],
        axis=1,
    )
    faces["group"] = group[faces["_p"].to_numpy()]
    responses = (
        _categorise(design, rig, faces, protos, gcols, wcols, label_ss)
        if design.categorise
        else pd.DataFrame()
    )
    return SimulatedPeople(
        faces=faces.drop(columns=["_p"]) if design.groups else faces.drop(columns=["_p", "group"]),
        responses=responses,
        prototypes=protos,
        group=group,
        genes=gcols,
        weights=wcols,
        seed=seed,
    )


def _prototypes(
    design: PeopleDesign, rig: Rig, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """(participants, emotions, genes) own prototypes and (participants,) group names."""
    eye = design.ga.eye_motion
    index = {g: i for i, g in enumerate(rig.gene_names(eye))}
    population = population_prototypes(rig, design.emotions, design.participant, eye)
    base = np.stack([population[e] for e in design.emotions])
    n = design.participants
    group = (
        np.array([design.groups[i % len(design.groups)] for i in range(n)], dtype=object)
        if design.groups
        else np.full(n, "", dtype=object)
    )
    out = np.empty((n, len(design.emotions), len(index)))
    active = base > 0
    for i in range(n):
        p = base.copy()
        for k, emotion in enumerate(design.emotions):
            for gene, amount in design.shifts.get(group[i], {}).get(emotion, {}).items():
                p[k, _gene(index, gene)] = np.clip(p[k, _gene(index, gene)] + amount, 0, 1)
        noise = rng.normal(0.0, design.participant.spread, p.shape)
        out[i] = np.where(active | (p > 0), np.clip(p + noise, 0, 1), p)
    return out, group


def _gene(index: Mapping[str, int], name: str) -> int:
    if name not in index:
        raise ConfigError(f"unknown gene '{name}' in a planted shift; genes: {', '.join(index)}")
    return index[name]


def _trial_plan(
    design: PeopleDesign, rig: Rig, protos: np.ndarray, gene_names: tuple[str, ...]
) -> tuple[list[dict[str, object]], np.ndarray]:
    """One row per GA trial (participant × emotion × identity × repetition) and its target."""
    eye = design.ga.eye_motion
    index = {g: i for i, g in enumerate(gene_names)}
    rows, targets = [], []
    for i in range(design.participants):
        trial = 0
        for ident in design.identities:
            for k, emotion in enumerate(design.emotions):
                goal = protos[i, k].copy()
                for gene, amount in design.identity_shifts.get(ident, {}).get(emotion, {}).items():
                    goal[_gene(index, gene)] = np.clip(goal[_gene(index, gene)] + amount, 0, 1)
                for rep in range(design.repetitions):
                    rows.append(
                        {
                            "_p": i,
                            "participant_id": participant_name(i),
                            "session_id": i + 1,
                            "trial": trial,
                            "block_name": f"make_{ident}",
                            "emotion": emotion,
                            "identity": ident,
                            "repetition": rep,
                            "duration_s": np.nan,
                        }
                    )
                    targets.append(goal)
                    trial += 1
    return rows, rig.expand(np.array(targets), eye)


def _run_ga(
    design: PeopleDesign, rig: Rig, targets: np.ndarray, ss: np.random.SeedSequence
) -> np.ndarray:
    """(trials, shapes) final faces of GA runs toward each target (gene ED, softmax choices)."""
    from emogen.simulate import build_problem

    p = design.participant
    first = {rig.shape_names[int(np.argmax(targets[0]))]: 1.0}
    cfg = SimulationConfig(
        ga=design.ga,
        target=first,
        runs=1,
        selections=(max(1, p.n_selected),),
        metric=MetricConfig(name="ed"),
        noise_temperature=p.select_noise,
    )
    problem = build_problem(cfg, rig, all_weights=True)
    seeds = np.array([_to_seed(c) for c in ss.spawn(len(targets))], dtype=np.int64)
    return simulate_elites(problem, np.arange(len(targets)), seeds, target=targets).final


def _categorise(
    design: PeopleDesign,
    rig: Rig,
    faces: pd.DataFrame,
    protos: np.ndarray,
    gcols: tuple[str, ...],
    wcols: tuple[str, ...],
    ss: np.random.SeedSequence,
) -> pd.DataFrame:
    """Every participant's categorise answers: own faces, others' and random faces."""
    n = design.participants
    streams = ss.spawn(n + 1)
    shuffle = np.random.default_rng(streams[n])
    labeller = _derangement(n, shuffle) if design.shuffle_prototypes else np.arange(n)
    owner = faces["_p"].to_numpy()
    emotion = faces["emotion"].to_numpy()
    genes = faces[list(gcols)].to_numpy(dtype=np.float64)
    weights = faces[list(wcols)].to_numpy(dtype=np.float64)
    parts = []
    for i in range(n):
        rng = np.random.default_rng(streams[i])
        judge = SimulatedParticipant(
            prototypes={e: protos[labeller[i], k] for k, e in enumerate(design.emotions)},
            design=design.participant,
            rig=rig,
            eye_motion=design.ga.eye_motion,
            rng=rng,
        )
        own = np.flatnonzero(owner == i)
        other = _others(design, owner, emotion, i, rng)
        rand_g = _random_genes(design.random, len(gcols), rng)
        shown_w = np.vstack(
            [weights[own], weights[other], rig.expand(rand_g, design.ga.eye_motion)]
        )
        answers = [judge.categorise(w, design.emotions, 7) for w in shown_w]
        idx = np.concatenate([own, other])
        k = len(idx)
        part = pd.DataFrame(
            {
                "participant_id": participant_name(i),
                "session_id": i + 1,
                "trial": np.arange(len(shown_w)),
                "source": ["own"] * len(own) + ["other"] * len(other) + ["random"] * design.random,
                "fallback": False,
                "source_participant_id": [
                    *faces["participant_id"].to_numpy()[idx],
                    *[None] * design.random,
                ],
                "source_trial": [*faces["trial"].to_numpy()[idx], *[None] * design.random],
                "intended": [*emotion[idx], *[None] * design.random],
                "identity": [
                    *faces["identity"].to_numpy()[idx],
                    *[design.identities[r % len(design.identities)] for r in range(design.random)],
                ],
                "label": [a[0] for a in answers],
                "intensity": [a[1] for a in answers],
                "confidence": [a[2] for a in answers],
            }
        )
        hit = (part["label"] == part["intended"]).astype(object)
        hit.iloc[k:] = None  # random faces have no right answer
        part["correct"] = hit
        shown_g = np.vstack([genes[idx], rand_g])
        parts.append(
            pd.concat(
                [
                    part,
                    pd.DataFrame(shown_g, columns=list(gcols)),
                    pd.DataFrame(shown_w, columns=list(wcols)),
                ],
                axis=1,
            )
        )
    return pd.concat(parts, ignore_index=True)


def _derangement(n: int, rng: np.random.Generator) -> np.ndarray:
    """A permutation of range(n) with no fixed point (each labels with another's prototypes)."""
    while True:
        p = rng.permutation(n)
        if not np.any(p == np.arange(n)):
            return p


def _others(
    design: PeopleDesign, owner: np.ndarray, emotion: np.ndarray, i: int, rng: np.random.Generator
) -> np.ndarray:
    """Indices of ``design.others`` final faces of other participants, balanced over emotions."""
    if not design.others:
        return np.zeros(0, dtype=np.int64)
    per = -(-design.others // len(design.emotions))
    picked = [
        rng.choice(np.flatnonzero((owner != i) & (emotion == e)), size=per, replace=False)
        for e in design.emotions
    ]
    return np.concatenate(picked)[: design.others]


def _random_genes(count: int, n_genes: int, rng: np.random.Generator) -> np.ndarray:
    """(count, n_genes) uniform random faces: 3–8 genes active at U(0, 1)."""
    g = np.zeros((count, n_genes))
    for r in range(count):
        on = rng.choice(n_genes, size=int(rng.integers(3, 9)), replace=False)
        g[r, on] = rng.uniform(0, 1, len(on))
    return g


def as_people(sim: SimulatedPeople) -> People:
    """The simulated study as :class:`~emogen.analysis.people.People` (what the analyses of a
    study export read); groups, when planted, as the participant column ``group``."""
    faces = sim.faces
    trials = faces[["session_id", "trial", "participant_id", "emotion", "identity"]].assign(
        task="evolve", status="done"
    )
    return People(
        source=Path(f"(simulated study, seed {sim.seed})"),
        faces=faces,
        trials=trials,
        selections=pd.DataFrame(),
        genes=sim.genes,
        weights=sim.weights,
        responses=sim.responses if len(sim.responses) else None,
        participant_columns=("group",) if "group" in faces.columns else (),
    )
