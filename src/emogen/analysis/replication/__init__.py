"""``emogen replicate``: the paper's Section IV experiments on our model, each finding beside
the paper's.

:func:`replicate` runs the sections and writes the report (``index.html``, ``README.md``,
``figures/``, ``tables/``) and returns the findings, one line each: what the paper found, its
numbers, ours, and a verdict by a written rule (:mod:`.verdicts`) — **holds**, **partly**
(some of it, or only qualitatively), **differs** or **inconclusive** — combined over several
independent seeds (a verdict that changes between seeds is inconclusive).

Each section is an experiment taking typed inputs (a :class:`ConditionRunner` that simulates
conditions, the training set, …) and returning a typed result (its tables, the data of its
figures, its findings); the report is written from those results:

* :mod:`.theoretical_metrics`, :mod:`.empirical_metrics` — Section IV-B (Tables I–II), with
  :mod:`.low_variance` (Fig. 11 on a target in low-variance PCA modes) and
  :mod:`.std_clustering` (IV-B2: std_ED for clustering);
* :mod:`.initialisation`, :mod:`.bias_repeatability`, :mod:`.ga_settings` — Section IV-C
  (Tables III–V, Figs. 14–18, selection pressure); :mod:`.intersample` — IV-C's suggested
  inter-sample statistic against simulation;
* :mod:`.correctives` — the simulations with Section III-A's correctives on;
  :mod:`.interpenetration` — the shown faces' interpenetration and plausibility before and
  after correction (Figs. 1–2);
* :mod:`.analysis_tools` — our GA-noise test and separability on simulated participants, a
  power analysis;
* :mod:`.write_report`, :mod:`.write_metrics`, :mod:`.write_ga`, :mod:`.write_tools` — the
  report; :mod:`.run` — the order of the sections.

Within one seed every simulation uses that seed (common random numbers: conditions differ
only by their settings); the paper sections run on each of the settings' seeds, our own tools
on the first. ``quick`` uses 100 runs per condition and 60 simulated participants instead of
500 and 240, a lighter power analysis and its own seeds (101, …): a few minutes on two cores.
"""

from emogen.analysis.replication.conditions import Condition, ConditionRunner, ConditionSpec
from emogen.analysis.replication.findings import Finding
from emogen.analysis.replication.run import SECTIONS, replicate
from emogen.analysis.replication.settings import ReplicateSettings

__all__ = [
    "SECTIONS",
    "Condition",
    "ConditionRunner",
    "ConditionSpec",
    "Finding",
    "ReplicateSettings",
    "replicate",
]
