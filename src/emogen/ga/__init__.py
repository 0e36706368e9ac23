"""EmoGen's genetic algorithm: operators (S, B, M, A, R), initialisation, the engine."""

from emogen.ga.classical import classical_next_generation
from emogen.ga.engine import Engine, Population
from emogen.ga.init import fixed_init, protocol_init, read_fixed_sets
from emogen.ga.operators import average, crossover, mutate, random_faces, select
from emogen.ga.step import Offspring, next_generation

__all__ = [
    "Engine",
    "Offspring",
    "Population",
    "average",
    "classical_next_generation",
    "crossover",
    "fixed_init",
    "mutate",
    "next_generation",
    "protocol_init",
    "random_faces",
    "read_fixed_sets",
    "select",
]
