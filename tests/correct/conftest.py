"""Fixtures for the correctives: the ICT model's correctives and GA faces."""

from __future__ import annotations

import numpy as np
import pytest

from emogen.correct import model_correctives


@pytest.fixture(scope="session")
def ict_correctives(ict_model):  # type: ignore[no-untyped-def]
    return model_correctives(ict_model)


@pytest.fixture(scope="session")
def mouth(ict_model):  # type: ignore[no-untyped-def]
    from emogen.correct.lips import mouth_geometry

    return mouth_geometry(
        ict_model.base_neutral.astype(np.float64), ict_model.polygons, ict_model.regions
    )


@pytest.fixture(scope="session")
def ga_weights(ict_model) -> tuple[np.ndarray, np.ndarray]:
    """≥ 500 faces from the GA's generators (protocol, random R(6), evolved), fixed seed."""
    from benchmarks.bench_correct import ga_faces

    return ga_faces(ict_model.rig, 510, seed=7)
