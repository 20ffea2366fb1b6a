"""Runs tests/python with pytest under ctest; exits 77 (skipped, saying why) when pytest, numpy or
scipy is missing from this interpreter (Debian: python3-pytest python3-numpy python3-scipy).

Everything runs under the __main__ guard: the Dask tests start worker processes by
multiprocessing's "spawn", which imports this file again in each of them (as __mp_main__), and
without the guard every worker ran the whole suite again (it timed out on a fresh machine)."""

import importlib.util
import os
import sys


def main():
    missing = [name for name in ("pytest", "numpy", "scipy") if importlib.util.find_spec(name) is None]
    if missing:
        print(f"SKIP: {sys.executable} lacks {', '.join(missing)} (Debian: python3-pytest python3-numpy python3-scipy)")
        return 77
    import pytest

    return pytest.main(["-q", "-p", "no:cacheprovider", os.path.dirname(os.path.abspath(__file__))])


if __name__ == "__main__":
    sys.exit(main())
