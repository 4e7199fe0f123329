"""CTest's entry to the pytest suite (Python.Pytest): fails, with a message naming the module and
the interpreter, when NumPy or pytest is missing, instead of letting anything pass by skipping."""
import sys

try:
    import numpy  # noqa: F401
    import pytest
except ImportError as e:
    print(f"hapsyn Python tests: {e.name} is not installed for {sys.executable} "
          "(Debian: apt install python3-numpy python3-pytest; or configure with "
          "-DPython3_EXECUTABLE=<an interpreter that has them>)", file=sys.stderr)
    sys.exit(1)

sys.exit(pytest.main(sys.argv[1:]))
