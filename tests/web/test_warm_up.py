"""`emogen serve` prepares the face correction before it listens: the first participant's first
step does not wait for the correction's kernels to be compiled or loaded."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]

PROBE = textwrap.dedent(
    """
    import sys
    from types import SimpleNamespace

    from emogen.correct import solve
    from emogen.model import load_model
    from emogen.web.server import warm_up

    model = load_model(sys.argv[1])
    app = SimpleNamespace(state=SimpleNamespace(config=SimpleNamespace(correct=False), model=model))
    warm_up(app)
    print("uncorrected study:", len(solve._solve_compiled.signatures))
    app.state.config.correct = True
    warm_up(app, announce=True)
    print()
    print("corrected study:", len(solve._solve_compiled.signatures))
    """
)


def test_serving_a_corrected_study_prepares_the_correction_first(ict_dir: Path) -> None:
    """In a fresh process (nothing compiled or loaded yet): a study without correction loads
    nothing; one with correction has the compiled detect-solve loop ready, and says so."""
    done = subprocess.run(
        [sys.executable, "-c", PROBE, str(ict_dir)],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert "uncorrected study: 0" in lines
    assert "corrected study: 1" in lines
    assert any(
        line.startswith("Preparing the face correction") and "ready (" in line for line in lines
    )
