"""Write src/emogen/data/ict_manifest.json: checksums of the ICT-FaceKit files `emogen model fetch`
downloads.

Usage: python scripts/make_ict_manifest.py [ICT_FACEKIT_DIR] [OUTPUT_JSON]

The manifest holds only paths, sizes and SHA-256 digests; the model data itself is never copied
into this repository.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

REPOSITORY = "ICT-VGL/ICT-FaceKit"
COMMIT = "da5f95a607f5e6b37755b38d3385d7f2853732e5"

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SOURCE = ROOT.parent / "shared" / "ict-facekit"
DEFAULT_OUTPUT = ROOT / "src" / "emogen" / "data" / "ict_manifest.json"


def sha256_of(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for chunk in iter(lambda: handle.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def manifest_entries(source: Path) -> list[dict[str, object]]:
    model_dir = source / "FaceXModel"
    if not model_dir.is_dir():
        raise SystemExit(f"ICT-FaceKit folder {source} has no FaceXModel/ subfolder")
    files = sorted(p for p in model_dir.iterdir() if p.is_file())
    files.append(source / "LICENSE")
    entries: list[dict[str, object]] = []
    for path in files:
        if not path.is_file():
            raise SystemExit(f"missing file {path}")
        entries.append(
            {
                "path": path.relative_to(source).as_posix(),
                "sha256": sha256_of(path),
                "size": path.stat().st_size,
            }
        )
    return entries


def main(argv: list[str]) -> int:
    source = Path(argv[1]) if len(argv) > 1 else DEFAULT_SOURCE
    output = Path(argv[2]) if len(argv) > 2 else DEFAULT_OUTPUT
    commit_file = source / "SOURCE_COMMIT"
    if commit_file.is_file():
        found = commit_file.read_text().strip()
        if found != COMMIT:
            raise SystemExit(f"{commit_file} names commit {found}, expected {COMMIT}")
    entries = manifest_entries(source)
    manifest = {"repository": REPOSITORY, "commit": COMMIT, "files": entries}
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(json.dumps(manifest, indent=2) + "\n")
    total = sum(int(str(entry["size"])) for entry in entries)
    sys.stdout.write(f"wrote {output}: {len(entries)} files, {total} bytes\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
