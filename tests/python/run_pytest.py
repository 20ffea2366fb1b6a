"""Runs tests/python with pytest under ctest; exits 77 (skipped, saying why) when pytest, numpy or
scipy is missing from this interpreter (Debian: python3-pytest python3-numpy python3-scipy)."""

import importlib.util
import os
import sys

missing = [name for name in ("pytest", "numpy", "scipy") if importlib.util.find_spec(name) is None]
if missing:
    print(f"SKIP: {sys.executable} lacks {', '.join(missing)} (Debian: python3-pytest python3-numpy python3-scipy)")
    sys.exit(77)

import pytest  # noqa: E402

sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", os.path.dirname(os.path.abspath(__file__))]))
