"""The own-distance categorisation model on planted-answer studies written independently of
EmoGen's simulator (``benchmarks/planted_study.py``: a Gaussian kernel on squared distance, t-
distributed individual prototypes, lapses — not the model's logit-linear distance), exported in
EmoGen's study format and read back by ``load_people``.

    python benchmarks/calibrate_planted.py                       # 200 studies per condition
    python benchmarks/calibrate_planted.py --studies 50 --conditions null

Conditions: ``null`` (labels by the population's prototypes, own_weight 0), ``ignore`` (labels
ignore the faces: the intended label with P 0.7; people's emotions more or less distinct,
distinctness_sd 0.6: the null of fields ↔ accuracy), ``effect`` (own_weight 0.5), ``fields``
(labels by one's own prototypes, distinctness_sd 0.6: fields ↔ accuracy planted). For each, prints
the studies with a crash, a NaN anywhere in a result, and each test's fits without an estimate
or with a fallback; then per test the rejection rate at α with its Wilson 95% interval: the
primary test (the shuffled-prototype permutation over participants, ``--shuffles`` derangements:
with 49, p is a multiple of 0.02 and the test's level 0.04), the secondary GEE, two-stage and
the pooled conditional logit's two-way cluster-robust t test (``two_way``: the primary test
before), the same pooled fit with model-based (unclustered) SEs — the reference the primary
test's power is compared with — and the fields ↔ accuracy test
(:mod:`emogen.analysis.fields_accuracy`, 999 permutations; then the mean of its r and how many
of its rejections had r below and above 0). ``--seed``: the first study's seed
(the docs' table: ``--seed 141000``, seeds not used while choosing the test).
``--fields-only`` runs the fields ↔ accuracy test alone (the categorisation models skipped:
about 0.5 s a study instead of several), for its null on many studies, with a Clopper–Pearson
interval beside Wilson's:

    python benchmarks/calibrate_planted.py --fields-only --conditions null --studies 500 --seed 900000
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.exact import clopper_pearson
from benchmarks.planted_study import PlantedDesign, write_planted_study

CONDITIONS = {
    "null": {"own_weight": 0.0},
    "ignore": {"labelling": "ignore_faces", "distinctness_sd": 0.6},
    "effect": {"own_weight": 0.5},
    "fields": {"own_weight": 1.0, "distinctness_sd": 0.6},
}
TESTS = ("primary", "gee", "two_stage", "two_way", "pooled_naive", "fields_accuracy")


def naive_p(table) -> float | None:  # type: ignore[no-untyped-def]
    """The pooled conditional logit's contrast p with model-based SEs (answers independent)."""
    from scipy import stats

    from emogen.analysis.categorisation_clogit import conditional_logit, table_arrays

    x, avail, chosen, _first, _labels = table_arrays(table, ("d_own", "d_ref"), constants=True)
    fit = conditional_logit(x, avail, chosen)
    if not fit.converged:
        return None
    cov = np.linalg.inv(fit.info)
    se = float(np.sqrt(cov[0, 0] + cov[1, 1] - 2 * cov[0, 1]))
    return float(2 * stats.norm.sf(abs(fit.beta[0] - fit.beta[1]) / se))


def one_study(
    design: PlantedDesign, seed: int, shuffles: int, fields_only: bool = False
) -> dict[str, object]:
    """Crash, NaN, failures and p of every test of one planted study (``fields_only``: of the
    fields ↔ accuracy test alone)."""
    from emogen.analysis.categorisation_models import OwnDistance, own_distance
    from emogen.analysis.fields_accuracy import distinctness_accuracy
    from emogen.analysis.people import load_people

    with tempfile.TemporaryDirectory() as tmp:
        people = load_people(write_planted_study(design, Path(tmp), seed=seed))
    if fields_only:
        fa = distinctness_accuracy(people, rng=np.random.default_rng(seed), permutations=999)
        text = json.dumps({k: v for k, v in fa.items() if k != "table"})
        return {
            "crash": "",
            "nan": "NaN" in text or "Infinity" in text,
            "failed": [] if fa["status"] == "ok" else ["fields_accuracy"],
            "warned": [],
            "p": {"fields_accuracy": fa["p_perm"]},
            "contrast": None,
            "fields_r": fa["r"],
        }
    try:
        res = own_distance(people, rng=np.random.default_rng(seed), n_shuffles=shuffles)
    except Exception as exc:
        return {"crash": f"{type(exc).__name__}: {exc}"}
    if not isinstance(res, OwnDistance):
        return {"crash": f"no model: {res}"}
    tests = {
        "primary": res.primary,
        "gee": res.gee,
        "two_stage": res.two_stage,
        "control": {k: v for k, v in res.control.items() if k != "control"},
    }
    text = json.dumps(tests, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o))
    p = {name: t.get("p_t" if name == "two_stage" else "p") for name, t in tests.items()}
    p["two_way"] = res.primary.get("p_two_way")
    p["pooled_naive"] = naive_p(res.table)
    fa = distinctness_accuracy(people, rng=np.random.default_rng(seed), permutations=999)
    p["fields_accuracy"] = fa["p_perm"]
    text += json.dumps({k: v for k, v in fa.items() if k != "table"})
    return {
        "crash": "",
        "nan": "NaN" in text or "Infinity" in text,
        "failed": [n for n, t in tests.items() if t["status"] != "ok"],
        "warned": [n for n, t in tests.items() if t.get("warnings")],
        "p": p,
        "contrast": res.primary.get("contrast"),
        "fields_r": fa["r"],
    }


def wilson(k: int, n: int) -> tuple[float, float]:
    if n == 0:
        return (float("nan"), float("nan"))
    z, phat = 1.959964, k / n
    centre = (phat + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(phat * (1 - phat) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--studies", type=int, default=200)
    ap.add_argument("--participants", type=int, default=16)
    ap.add_argument("--repetitions", type=int, default=1)
    ap.add_argument("--shuffles", type=int, default=49)
    ap.add_argument("--alpha", type=float, default=0.05)
    ap.add_argument("--seed", type=int, default=41_000)
    ap.add_argument("--conditions", nargs="+", choices=tuple(CONDITIONS), default=list(CONDITIONS))
    ap.add_argument("--fields-only", action="store_true", help="the fields ↔ accuracy test alone")
    args = ap.parse_args()
    for name in args.conditions:
        c = list(CONDITIONS).index(name)  # a condition's seeds do not depend on the others run
        design = PlantedDesign(
            participants=args.participants,
            repetitions=args.repetitions,
            **CONDITIONS[name],  # type: ignore[arg-type]
        )
        start = time.perf_counter()
        runs = [
            one_study(design, args.seed + 10_000 * c + s, args.shuffles, args.fields_only)
            for s in range(args.studies)
        ]
        report(name, runs, args, time.perf_counter() - start)


def report(name: str, runs: list[dict[str, object]], args: argparse.Namespace, sec: float) -> None:
    n = len(runs)
    crashes = [r["crash"] for r in runs if r["crash"]]
    ok = [r for r in runs if not r["crash"]]
    print(
        f"\n== {name}: {n} studies of {args.participants} participants, "
        f"{args.repetitions} repetition(s), seeds from {args.seed} ({sec:.0f} s)"
    )
    print(f"crashes: {len(crashes)}{' — ' + str(crashes[:3]) if crashes else ''}")
    print(f"studies with a NaN in a result: {sum(bool(r['nan']) for r in ok)}")
    for test in () if args.fields_only else ("primary", "gee", "two_stage", "control"):
        failed = sum(test in r["failed"] for r in ok)  # type: ignore[operator]
        warned = sum(test in r["warned"] for r in ok)  # type: ignore[operator]
        print(f"  {test}: no estimate in {failed}, a warning or fallback in {warned}")
    print(f"rejections at α = {args.alpha} (Wilson 95% interval), of studies with an estimate:")
    for test in ("fields_accuracy",) if args.fields_only else TESTS:
        p = [r["p"][test] for r in ok if r["p"][test] is not None]  # type: ignore[index]
        k = int(np.sum(np.array(p) <= args.alpha))
        lo, hi = wilson(k, len(p))
        cp = clopper_pearson(k, len(p))
        print(
            f"  {test:15s} {k:4d} of {len(p):4d} = {k / max(len(p), 1):.3f} [{lo:.3f}, {hi:.3f}]"
            f" (Clopper–Pearson [{cp[0]:.3f}, {cp[1]:.3f}])"
        )
    contrasts = [r["contrast"] for r in ok if r["contrast"] is not None]
    if contrasts:
        sd = np.std(contrasts, ddof=1)
        print(f"primary contrast: mean {np.mean(contrasts):+.3f}, SD {sd:.3f}")
    with_r = [r for r in ok if r["fields_r"] is not None]
    if with_r:
        rs = np.array([r["fields_r"] for r in with_r], dtype=float)
        hit = np.array([r["p"]["fields_accuracy"] <= args.alpha for r in with_r])  # type: ignore[index]
        se = rs.std(ddof=1) / np.sqrt(len(rs))
        print(
            f"fields ↔ accuracy r: mean {rs.mean():+.3f} (SE {se:.3f}); rejections with "
            f"r < 0: {int(np.sum(hit & (rs < 0)))}, with r > 0: {int(np.sum(hit & (rs > 0)))}"
        )


if __name__ == "__main__":
    main()
