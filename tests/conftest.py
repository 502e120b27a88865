import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))

STUDIES = ROOT / "studies"
REFERENCE = ROOT.parent / "shared" / "reference"


@pytest.fixture(scope="session")
def studies():
    return STUDIES


@pytest.fixture(scope="session")
def reference_dir():
    if not REFERENCE.exists():
        pytest.fail(f"the shared reference tables are missing: {REFERENCE}")
    return REFERENCE
