#!/usr/bin/env python3
"""Rewrites the RTL for Yosys 0.23, whose SystemVerilog reader takes package members only as
`pkg::name` (no `import pkg::*;`). Every module's `import` lines are dropped and the members of the
imported packages are qualified. Verilator and Icarus read the sources as written; only the Yosys
steps (lint.sh, docs/results/rtl_synth.sh) go through this.

usage: yosys_compat.py OUT_DIR FILE.sv...   (writes OUT_DIR/<name>.sv for every file)
"""
import os
import re
import sys


def package_members(text):
    members = {}
    for m in re.finditer(r"package\s+(\w+)\s*;(.*?)endpackage", text, re.S):
        pkg, body = m.group(1), m.group(2)
        names = re.findall(r"localparam\s+int\s+(\w+)", body)
        names += re.findall(r"function\s+automatic\s+[^;(]*?(\w+)\s*\(", body)
        members[pkg] = names
    return members


def main():
    out, files = sys.argv[1], sys.argv[2:]
    os.makedirs(out, exist_ok=True)
    texts = {f: open(f).read() for f in files}
    members = {}
    for t in texts.values():
        members.update(package_members(t))
    for f, t in texts.items():
        if "package " not in t:
            imported = re.findall(r"import\s+(\w+)::\*\s*;", t)
            t = re.sub(r"\s*import\s+\w+::\*\s*;", "", t)
            for pkg in imported:
                for name in members.get(pkg, []):
                    t = re.sub(r"(?<!::)(?<![\w.'$])" + name + r"\b", pkg + "::" + name, t)
        with open(os.path.join(out, os.path.basename(f)), "w") as fh:
            fh.write(t)


if __name__ == "__main__":
    main()
