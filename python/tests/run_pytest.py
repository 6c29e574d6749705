"""Runs the module's pytest suite for ctest: exit 77 (ctest's skip) where
pytest is not installed, rather than a failure that says nothing of tetiso."""
import sys

try:
    import pytest
except ImportError:
    print("pytest is not installed (python3-pytest): the Python module's suite is skipped")
    sys.exit(77)

sys.exit(pytest.main(sys.argv[1:]))
