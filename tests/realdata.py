"""Where the real robot logs of other labs are (never copied into the repository)."""

from pathlib import Path

import pytest

#: ``../shared/realdata`` beside the repository.
REALDATA = Path(__file__).resolve().parents[2] / "shared" / "realdata"

needs_realdata = pytest.mark.skipif(
    not (REALDATA / "ur10e").is_dir(), reason=f"real robot logs not found at {REALDATA}"
)
