"""EmoGen's genetic algorithm: operators (S, B, M, A, R), Algorithm 1 over runs, the engine."""

from emogen.ga.algorithm import Offspring, classical_next_generation, next_generation
from emogen.ga.draws import CURRENT_STREAM, Draws, generation_draws
from emogen.ga.engine import Engine, Population
from emogen.ga.init import fixed_init, protocol_init, read_fixed_sets
from emogen.ga.operators import average, crossover, mutate, random_faces, select

__all__ = [
    "CURRENT_STREAM",
    "Draws",
    "Engine",
    "Offspring",
    "Population",
    "average",
    "classical_next_generation",
    "crossover",
    "fixed_init",
    "generation_draws",
    "mutate",
    "next_generation",
    "protocol_init",
    "random_faces",
    "read_fixed_sets",
    "select",
]
