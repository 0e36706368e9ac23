"""The methods block of a report: what made it, so a reader can reproduce every number.

EmoGen's version, the face model (name and hash), the study (its name and config hash(es) from
the export's ``study`` table — several when the config changed during the study), the command
line, the seed and the settings every test used, and the exclusion rule.
"""

from __future__ import annotations

from importlib import metadata
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import pandas as pd

    from emogen.analysis.analyse_options import AnalysisOptions
    from emogen.analysis.data import Dataset
    from emogen.model.face import FaceModel


def methods_record(
    ds: Dataset, opts: AnalysisOptions, model: FaceModel | None, study: pd.DataFrame | None
) -> dict[str, Any]:
    """The facts of the methods block (also ``analysis.json``'s ``methods``)."""
    try:
        version = metadata.version("emogen")
    except metadata.PackageNotFoundError:
        version = "unknown"
    record: dict[str, Any] = {
        "emogen_version": version,
        "command": opts.command or "emogen.analysis.analyse() (the Python API)",
        "source": str(ds.source),
        "kind": ds.kind,
        "seed": opts.seed,
        "alpha": opts.alpha,
        "noise_runs": opts.noise_runs,
        "choice_noise": opts.choice_noise,
        "model": None if model is None else {"name": model.name, "hash": model.model_hash},
        "exclusion_rule": None if opts.exclusions is None else opts.exclusions.describe(),
        "primary_tests": list(opts.primary),
    }
    if study is not None and len(study):
        record["study"] = sorted(set(study["study"].astype(str))) if "study" in study else []
        if "study_config_hash" in study:
            record["study_config_hashes"] = sorted(set(study["study_config_hash"].astype(str)))
        if "model_hash" in study:
            recorded = sorted(set(study["model_hash"].astype(str)))
            record["recorded_model_hashes"] = recorded
            record["model_matches"] = model is None or any(model.hash_matches(h) for h in recorded)
    return record


def methods_text(record: dict[str, Any]) -> str:
    """The block in words, for the top of the report."""
    model = record["model"]
    parts = [
        f"EmoGen {record['emogen_version']}",
        f"command `{record['command']}`",
        f"seed {record['seed']}, α = {record['alpha']}, {record['noise_runs']} simulated GA "
        "runs per group for the GA noise",
        "face model " + (f"{model['name']} (hash {model['hash']})" if model else "not given"),
    ]
    if record.get("study"):
        hashes = record.get("study_config_hashes", [])
        parts.append(
            f"study {', '.join(record['study'])} (config hash {', '.join(hashes)}"
            + ("; several versions of the config: see the export" if len(hashes) > 1 else "")
            + ")"
        )
    recorded = record.get("recorded_model_hashes", [])
    if not record.get("model_matches", True):
        parts.append(
            f"**the study recorded model hash {', '.join(recorded)}, not this model's**: "
            "renders and vertex distances may not be the faces participants saw"
        )
    rule = record["exclusion_rule"]
    parts.append("exclusion rule: " + ("; ".join(rule) if rule else "none (--no-exclusions)"))
    primary = record.get("primary_tests", [])
    parts.append(
        "primary test(s): "
        + (", ".join(f"`{p}`" for p in primary) or "none")
        + "; every other test is exploratory (the multiplicity plan at the end)"
    )
    return "**Methods.** " + "; ".join(parts) + "."
