"""What every Python test finds: the repository, the built programs and a
scratch directory. The programs come from RBCD_BIN (CTest sets it to the
build's bin/; by hand it defaults to build/bin); a test whose program is
not built is skipped, saying which."""
import os

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def program(name):
    """The built program `name`, or the test is skipped."""
    path = os.path.join(os.environ.get("RBCD_BIN") or os.path.join(ROOT, "build", "bin"), name)
    if not os.access(path, os.X_OK):
        pytest.skip(f"{name} is not built ({path})")
    return path


@pytest.fixture
def root():
    return ROOT
