"""The type stubs (omma/__init__.pyi, py.typed) against the runtime with mypy's stubtest, and a typed
example (stub_example.py) through mypy --strict; a wrong call must be caught. Needs mypy
(Debian: python3-mypy)."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

import omma

mypy = pytest.importorskip("mypy")
HERE = Path(__file__).resolve().parent
PACKAGE_ROOT = str(Path(omma.__file__).resolve().parent.parent)  # build/python (or site-packages)


def run(args, tmp_path):
    env = dict(os.environ, PYTHONPATH=PACKAGE_ROOT)
    if "site-packages" not in PACKAGE_ROOT:  # a build tree; an installed package is found as PEP 561's
        env["MYPYPATH"] = PACKAGE_ROOT
    cache = ["--cache-dir", str(tmp_path / "mypy-cache")] if args[0] == "mypy" else []  # stubtest keeps none
    return subprocess.run([sys.executable, "-m", *args, *cache], env=env, capture_output=True, text=True,
                          cwd=tmp_path)


def test_package_ships_stubs():
    pkg = Path(omma.__file__).parent
    assert (pkg / "py.typed").exists() and (pkg / "__init__.pyi").exists()


def test_stubtest_finds_no_difference(tmp_path):
    r = run(["mypy.stubtest", "omma", "--allowlist", str(HERE / "stubtest_allowlist.txt")], tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "Success: no issues found" in r.stdout


def test_mypy_checks_a_typed_example(tmp_path):
    # One mypy run (--strict) over the typed example, which must be clean, and a file of wrong calls,
    # each of which must be caught.
    bad = tmp_path / "bad.py"
    bad.write_text("import omma\n"
                   "omma.stitch(omma.thesis_prototype_rig(), [], method=3)\n"
                   "x: str = omma.plan()\n"
                   "omma.run(omma.Rig.load('thesis-24'), source='sim:colon', framez=10)\n")
    r = run(["mypy", "--strict", str(HERE / "stub_example.py"), str(bad)], tmp_path)
    assert r.returncode == 1
    assert "stub_example.py" not in r.stdout, r.stdout
    assert 'bad.py:2: error: Argument "method" to "stitch" has incompatible type "int"; expected "str"' in r.stdout
    assert "bad.py:3: error: Incompatible types in assignment" in r.stdout
    assert 'bad.py:4: error: Unexpected keyword argument "framez" for "run"' in r.stdout
    assert "Found 3 errors in 1 file (checked 2 source files)" in r.stdout, r.stdout
