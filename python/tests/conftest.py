"""Shared fixtures: the repository root and the command-line binary the renders are compared with."""
import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def repo():
    return REPO


@pytest.fixture(scope="session")
def cli():
    """Runs `manylights ARGS…`: $MANYLIGHTS_BIN, else the release binary, built if missing or
    stale (cargo does nothing when it is current; the Python build shares its dependencies)."""
    binary = os.environ.get("MANYLIGHTS_BIN")
    if not binary:
        build = subprocess.run(["cargo", "build", "--release", "--quiet", "-p", "manylights"],
                               cwd=REPO, capture_output=True, text=True)
        if build.returncode != 0:
            pytest.skip(f"cannot build the manylights binary: {build.stderr.strip()[-500:]}")
        binary = REPO / "target" / "release" / "manylights"

    def run(*args):
        return subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)

    return run
