"""Shared fixtures: the repository's scenes and the `vcm` command line tool."""

import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def scenes():
    """The folder of the repository's own scenes."""
    return ROOT / "scenes"


@pytest.fixture(scope="session")
def vcm_cli():
    """The `vcm` binary the test script built (VCM_BIN, else target/release/vcm)."""
    path = pathlib.Path(os.environ.get("VCM_BIN", ROOT / "target" / "release" / "vcm"))
    if not path.is_file():
        pytest.fail(f"{path}: build it first with `cargo build --release --bin vcm`")
    return path
