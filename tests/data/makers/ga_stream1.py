"""Stream-1 goldens made with the pre-redesign GA (commit ae3fc5f): hashes of step/classical outputs."""
import hashlib, json
import numpy as np
from emogen.ga.step import next_generation
from emogen.ga.classical import classical_next_generation
from emogen.rng import generation_rng

def digest(off):
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(off.genes, dtype="<f8").tobytes())
    h.update(np.ascontiguousarray(off.parents, dtype="<i8").tobytes())
    h.update("|".join(off.operators.tolist()).encode())
    return h.hexdigest()

cases = []
for (n, k, nr, m, x) in [(10, 30, 4, 2, 6), (10, 7, 4, 3, 6), (6, 5, 2, 3, 2), (10, 30, 0, 0, 6), (5, 3, 1, 1, 1), (10, 1, 3, 2, 6)]:
    for s in [1, 2, 3, 5]:
        if s > n: continue
        for g in [0, 1, 2, 3]:
            case = len(cases)
            data = np.random.default_rng([2026, case])
            genes = data.random((n, k)); sel = data.permutation(n)[:s]; seed = int(data.integers(0, 2**62))
            p = dict(random_faces_count=nr, mutation_genes=m, random_genes=x)
            off = next_generation(genes, sel[0], sel[1:], g, rng=generation_rng(seed, 1, g + 1), **p)
            cl = classical_next_generation(genes, sel, rng=generation_rng(seed, 1, g + 1), **p)
            cases.append(dict(case=case, n=n, k=k, random_faces=nr, m=m, x=x, s=s, generation=g,
                              emogen=digest(off), classical=digest(cl)))
json.dump({"made_with": "emogen ae3fc5f (ga/step.py, ga/classical.py)", "inputs": "rng = default_rng([2026, case]); genes = rng.random((n, k)); selection = rng.permutation(n)[:s]; seed = rng.integers(0, 2**62); generator = generation_rng(seed, 1, generation + 1)", "cases": cases}, open("tests/data/ga_stream1.json", "w"), indent=1)
print(len(cases))
