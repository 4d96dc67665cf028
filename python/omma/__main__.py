"""`python3 -m omma ARGS...`: the omma command (omma._cli)."""
import sys

from ._cli import main

if __name__ == "__main__":
    sys.exit(main())
