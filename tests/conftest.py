import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))

STUDIES = ROOT / "studies"
REFERENCE = ROOT.parent / "shared" / "reference"


@pytest.hookimpl(trylast=True)   # after pytest's tmpdir plugin has set up its factory
def pytest_configure(config):
    """Hypothesis keeps its example database and a cache of constants in ./.hypothesis
    (the latter from collection on); tests write only under pytest's temporary
    folder, so point Hypothesis there (the fixture tmp_path_factory is this factory)."""
    from hypothesis import configuration
    configuration.set_hypothesis_home_dir(config._tmp_path_factory.mktemp("hypothesis"))


@pytest.fixture(scope="session")
def studies():
    return STUDIES


@pytest.fixture(scope="session")
def reference_dir():
    if not REFERENCE.exists():
        pytest.fail(f"the shared reference tables are missing: {REFERENCE}")
    return REFERENCE
