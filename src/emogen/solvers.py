"""The numbered eq. 5 collision solvers (docs/correctives.md), apart from their code.

A corrected study trial records the solver its faces were corrected with, so that it is
corrected the same way until it ends and replays bit for bit. Reading or checking that number
(engine states, exports, replay) must not load the compiled correction code: this module
imports nothing.
"""

from __future__ import annotations

#: The eq. 5 block solvers; :mod:`emogen.correct.solve` implements them. Solver 1 is needed by
#: tests/study/test_recorded_before.py::test_recorded_study_replays_exactly (and
#: ::test_a_session_recorded_mid_trial_continues_and_replays).
SOLVERS = {1: "scipy.optimize.lsq_linear (BVLS)", 2: "compiled exact active set"}
#: The solver new trials use.
CURRENT_SOLVER = 2


def check_solver(solver: object) -> int:
    """The solver number, checked (a recorded number this version does not know is an error,
    not a silent fallback)."""
    if isinstance(solver, bool) or not isinstance(solver, int) or solver not in SOLVERS:
        raise ValueError(f"collision solver must be one of {sorted(SOLVERS)}; got {solver!r}")
    return solver
