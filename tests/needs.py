"""What tests need from the machine (database servers, a browser, the public data): skip without it, but fail under
CI=true."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

#: the flags Chromium needs here: headless as root, and no background connections to a closed network
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


#: the public data files the tests read (the avivt, MP dataset and Neural A* files): `../shared/data` beside the
#: repository root, found from this file only
PUBLIC_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def skip_or_fail(problem: str, *, module: bool = False) -> None:
    """Skip the test for `problem` (`module`: the whole module, at import); under CI=true, fail it (CI must run
    every test)."""
    if os.environ.get("CI") == "true":
        pytest.fail(f"CI=true and this test cannot run: {problem}")
    pytest.skip(problem, allow_module_level=module)


def public_data(name: str) -> Path:
    """The public data file `../shared/data/<name>` (`PUBLIC_DATA`); without it, `skip_or_fail` naming the file."""
    path = PUBLIC_DATA / name
    if not path.is_file():
        skip_or_fail(f"the public data file ../shared/data/{name} is not present ({path})")
    return path


def chromium() -> str:
    """Path of Debian's Chromium ($VINADV_CHROMIUM as given, else `chromium` on PATH or /usr/bin/chromium), with
    Playwright's Python package importable; otherwise `skip_or_fail`."""
    explicit = os.environ.get("VINADV_CHROMIUM")
    if explicit:
        found = shutil.which(explicit) or (explicit if os.path.exists(explicit) else None)
    else:
        found = shutil.which("chromium") or ("/usr/bin/chromium" if os.path.exists("/usr/bin/chromium") else None)
    if found is None:
        skip_or_fail(
            f"Chromium not found at {explicit or 'chromium'} (apt-get install -y chromium, which "
            "`make test` does; or set VINADV_CHROMIUM)"
        )
    try:
        import playwright.sync_api  # noqa: F401, PLC0415 (whether it is installed)
    except ImportError:
        skip_or_fail("Playwright's Python package is missing (pip install -e '.[dev]')")
    return found


def cpu_vendor() -> str:
    try:
        with open("/proc/cpuinfo") as fh:
            return next((line.split(":", 1)[1].strip() for line in fh if line.startswith("vendor_id")), "")
    except OSError:
        return ""


#: The BLAS kernels whose summation orders `vinadv.planners.vin.replay` models were read off MKL on AMD EPYC. Elsewhere
#: (seen: MKL's AVX-512 kernels on an Intel Xeon) the r layer's and fc's sums may follow no modelled order; the replay
#: then uses PyTorch itself, exact and slower, which the bit-for-bit tests check all the same. There, the tests of the
#: replay itself are skipped; on AMD they must find the orders.
MODELLED_CPU = cpu_vendor() == "AuthenticAMD"
