"""The `omma` console command of the installed package (pyproject.toml [project.scripts]) and
`python3 -m omma`: executes the C++ `omma` binary that `pip install .` bundles in the package
(omma/bin/omma, built by setup.py with the extension), or else the one $OMMA_BINARY names (e.g.
build/omma of a build tree). The binary replaces the Python process (os.execv): arguments, exit
status, stdin/stdout/stderr and signals are the command's own.
"""
import os
import sys
from pathlib import Path
from typing import List, Optional

__all__ = ["binary", "main"]


def binary() -> Optional[str]:
    """Path of the omma binary: the one bundled in the package, else $OMMA_BINARY; None if neither."""
    bundled = Path(__file__).resolve().parent / "bin" / "omma"
    if bundled.is_file() and os.access(bundled, os.X_OK):
        return str(bundled)
    env = os.environ.get("OMMA_BINARY")
    if env and Path(env).is_file() and os.access(env, os.X_OK):
        return env
    return None


def main(argv: Optional[List[str]] = None) -> int:
    """Runs `omma ARGS...` in place of this process (returns only on failure to start it)."""
    exe = binary()
    if exe is None:
        sys.stderr.write("omma: error: this omma package has no bundled omma binary (omma/bin/omma) and "
                         "$OMMA_BINARY is not set to one; install with `pip install .` from the source tree "
                         "or set OMMA_BINARY=path/to/omma\n")
        return 2
    args = sys.argv[1:] if argv is None else list(argv)
    sys.stdout.flush()
    sys.stderr.flush()
    os.execv(exe, [exe] + args)
    return 127  # not reached


if __name__ == "__main__":
    sys.exit(main())
