"""Print the CPU model and the BLAS library and kernel numpy runs on (for CI logs: floating-point
results such as corrected weights can differ in the last bits between CPUs and BLAS kernels).

Run by ``make test`` (and so ``.ci/run``) before the tests; information it cannot find is printed
as unknown.
"""

from __future__ import annotations

import platform
from pathlib import Path


def cpu_model() -> str:
    """The CPU's model name (Linux: /proc/cpuinfo), else what the platform module says."""
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.is_file():
        for line in cpuinfo.read_text(errors="replace").splitlines():
            key, _, value = line.partition(":")
            if key.strip() in ("model name", "Hardware", "Processor") and value.strip():
                return value.strip()
    return platform.processor() or platform.machine() or "unknown"


def blas() -> str:
    """The BLAS numpy loaded: library, version, kernel (threadpoolctl's 'architecture')."""
    import numpy as np

    try:
        from threadpoolctl import threadpool_info
    except ImportError:  # pragma: no cover - threadpoolctl is a dependency
        return f"numpy {np.__version__}: threadpoolctl missing (see numpy.show_config())"
    libs = [i for i in threadpool_info() if i.get("user_api") == "blas"]
    if not libs:
        return f"numpy {np.__version__}: no BLAS found by threadpoolctl"
    return "; ".join(
        f"{i.get('internal_api', '?')} {i.get('version', '?')} kernel "
        f"{i.get('architecture', 'unknown')}, {i.get('num_threads', '?')} threads "
        f"({Path(str(i.get('filepath', '?'))).name})"
        for i in libs
    )


def main() -> None:
    print(f"CPU: {cpu_model()} ({platform.machine()})")
    print(f"BLAS: {blas()}")


if __name__ == "__main__":
    main()
