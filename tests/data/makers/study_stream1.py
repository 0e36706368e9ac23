"""A study recorded with the pre-redesign engine (stream 1), for the replay-compatibility test."""
import sys; sys.path.insert(0, ".")
import os
from pathlib import Path
import emogen
from emogen.study.config import study_from_dict
from emogen.study.sessions import StudyService
from emogen.study.storage import Store
from tests.study.drive import new_key, step_args

path = Path("tests/data/study_stream1.sqlite")
path.unlink(missing_ok=True)
model = emogen.load_model(os.environ["EMOGEN_MODEL"])
cfg = study_from_dict({
    "name": "recorded-before-redesign", "emotions": ["happy", "sad"], "seed": 77,
    "ga": {"generations": 4, "min_selections": 1, "max_selections": 5},
})
store = Store(f"sqlite:///{path}")
svc = StudyService(cfg, store, model.rig, model_name=model.name, model_hash=model.model_hash, model=model)

def drive(token, stop_after=None):
    state = svc.begin(token, new_key())
    steps = 0
    while state["stage"] != "done":
        if stop_after is not None and steps >= stop_after:
            return
        if state["trial"]["status"] == "active":
            ids = [f["id"] for f in state["population"]["faces"]]
            g = state["progress"]["generation"]
            n_others = (g + steps) % 5  # 1..5 selections
            k = (3 * g + steps) % len(ids)
            others = [ids[(k + j) % len(ids)] for j in range(1, n_others + 1)]
            if steps == 2 and stop_after is None:
                state = svc.restart(token, new_key(), **step_args(state)); steps += 1; continue
            state = svc.select(token, new_key(), **step_args(state), elite=ids[k], others=others, response_ms=900.0)
        else:
            state = svc.rate(token, new_key(), trial=state["progress"]["trial"], value=5, response_ms=700.0)
        steps += 1

t1, _ = svc.create_session("OLD-1"); drive(t1)
t2, _ = svc.create_session("OLD-2"); drive(t2, stop_after=3)
store.dispose()
print(path.stat().st_size, t1, t2)
