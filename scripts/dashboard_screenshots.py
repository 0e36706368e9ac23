"""Screenshots of the researcher dashboard (docs/images/dashboard_*.png) and of the page a link
without the participant id gets (``participant_required``).

A 4 emotions × 2 identities study (10 generations, Latin square, ``counterbalance = "arrival"``)
on a throwaway SQLite database: seven participants start through the
HTTP API as the page does, four finish, one stops in the middle. Sessions driven by a script end
in seconds, so for the picture the finished sessions' consent times are moved back by 9–15
minutes (the durations shown are illustrative, not measured; the caption in docs/study.md says
so). Run from the repository root with the model in $EMOGEN_MODEL:

    python scripts/dashboard_screenshots.py [OUT_FOLDER]     # default docs/images
"""

from __future__ import annotations

import sqlite3
import sys
import tempfile
from datetime import datetime, timedelta
from pathlib import Path

import httpx
from benchmarks.bench_study import BENCH_TOKEN, ServerProcess, write_study_toml
from playwright.sync_api import sync_playwright
from tests.study.drive import command, new_key, run_to_end
from tests.web.viewer_site import CHROMIUM, CHROMIUM_ARGS

STUDY = {
    "name": "faces-2025",
    "emotions": ["happy", "sad", "angry", "fearful"],
    "identities": ["female-light", "male-dark"],
    "order": "latin_square",
    "counterbalance": "arrival",
    "seed": 11,
    "ga": {"generations": 10},
    "completion": {"code": "C1A2B3"},
}
MINUTES = (12.5, 9.0, 14.75, 11.25)  # illustrative durations of the four finished sessions


def _populate(url: str) -> list[int]:
    """Seven sessions: four finished, one in its third trial; the finished ones' ids."""
    finished = []
    for k in range(7):
        created = httpx.post(f"{url}/api/sessions", json={"participant_id": f"5f{k:02d}a9c"})
        token = created.json()["token"]
        if k == 6:
            continue  # consented, not begun
        step = f"{url}/api/s/{token}/step"
        state = httpx.post(step, json={"command": "begin", "key": new_key()}).json()

        def call(kind: str, body: dict, step: str = step) -> dict:
            return httpx.post(step, json=command(kind, body), timeout=60).json()

        stop = (lambda s: s["progress"]["trial"] >= 2) if k in (4, 5) else (lambda s: False)
        run_to_end(state, call, stop=stop)
        if k < 4:
            finished.append(k)
    return finished


def _backdate(database: Path) -> None:
    with sqlite3.connect(database) as db:
        rows = db.execute(
            "SELECT id, completed_at FROM sessions WHERE completed_at IS NOT NULL ORDER BY id"
        ).fetchall()
        for (sid, completed), minutes in zip(rows, MINUTES, strict=False):
            start = datetime.fromisoformat(completed) - timedelta(minutes=minutes)
            db.execute(
                "UPDATE sessions SET consented_at = ?, created_at = ? WHERE id = ?",
                (start.isoformat(sep=" "), start.isoformat(sep=" "), sid),
            )


def main() -> None:
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/images")
    model = Path(__import__("os").environ["EMOGEN_MODEL"])
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        database = folder / "study.sqlite"
        config = write_study_toml(STUDY, folder / "study.toml")
        server = ServerProcess(config, f"sqlite:///{database}", model, folder / "log").start()
        try:
            _populate(server.url)
            _backdate(database)
            with sync_playwright() as p:
                browser = p.chromium.launch(
                    executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS
                )
                page = browser.new_page(viewport={"width": 1366, "height": 768})
                page.goto(f"{server.url}/researcher")
                page.fill("#token", BENCH_TOKEN)
                page.click("#token-form button")
                page.locator("#sessions tbody tr").first.wait_for(timeout=20_000)
                page.screenshot(path=str(out / "dashboard_1366x768.png"), full_page=True)
                page.close()
                page = browser.new_page(viewport={"width": 390, "height": 844})
                required = {**STUDY, "name": "required", "participant_required": True}
                server.stop()
                config = write_study_toml(required, folder / "required.toml")
                server = ServerProcess(config, f"sqlite:///{database}", model, folder / "log")
                server.start()
                page.goto(f"{server.url}/")
                page.screenshot(path=str(out / "participant_id_missing_390x844.png"))
                browser.close()
        finally:
            server.stop()
    print(f"wrote {out / 'dashboard_1366x768.png'}, {out / 'participant_id_missing_390x844.png'}")


if __name__ == "__main__":
    main()
