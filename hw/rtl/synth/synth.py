#!/usr/bin/env python3
"""Yosys synth_xilinx (7-series) of every RTL block on its own and of the two tops: LUTs,
flip-flops, DSP48E1 and block RAM (RAMB36E1 = 1, RAMB18E1 = 1/2), as a markdown table (stdout)
and JSON (--json FILE). Run by docs/results/rtl_synth.sh; needs the generated package (build/hw/rtl/gen).

usage: synth.py GEN_DIR [--json FILE] [--only NAME...] [--jobs N]
"""
import concurrent.futures
import json
import os
import re
import subprocess
import sys
import tempfile
import time

RTL = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# The frame memories (24 x 62,500 x 16 bit, four read ports) are not synthesized: their block RAM is
# counted in docs/results/rtl_synth.md (Yosys takes very long over 24 Mbit and would only replicate the arrays).
FRONT = ["common/ram_sdp.sv", "frontend/link_deser.sv", "frontend/bayer_store.sv",
         "frontend/demosaic_bilinear.sv", "frontend/single_cam_top.sv"]
PIPE = ["GEN/omma_hw_pkg.sv", "pipeline/omma_arith_pkg.sv", "common/ram_sdp.sv", "pipeline/config_regs.sv",
        "pipeline/angle_gen.sv", "pipeline/cartesian.sv", "pipeline/cam_search.sv", "pipeline/contrib_unit.sv",
        "pipeline/frame_mem.sv", "pipeline/pixel_value.sv", "pipeline/out_stream.sv", "pipeline/pano_top.sv"]

# (name, top module, files, parameters, thesis block it corresponds to)
BLOCKS = [
    ("angle generation", "angle_gen", PIPE, {}, "Angle generation"),
    ("Cartesian unit (3 sin/cos ROM sets)", "cartesian", PIPE, {}, "Cartesian coordinate"),
    ("camera search, 24 dot products + priority encoder", "cam_search", PIPE, {"NCAM": 24}, "Camera search"),
    ("distance + projection + tap address", "contrib_unit", PIPE, {}, "Pixel position"),
    ("pixel value (nn, linear) + boundary", "pixel_value", PIPE, {}, "Interpolation"),
    ("output stream (§6.3)", "out_stream", PIPE, {}, ""),
    ("configuration registers (Table 6.6)", "config_regs", PIPE, {"NCAM": 24}, ""),
    ("link deserialiser", "link_deser", FRONT, {}, ""),
    ("bilinear demosaic", "demosaic_bilinear", FRONT, {}, ""),
    ("single camera front end (deser + store + demosaic)", "single_cam_top", FRONT, {}, "Single Camera Int."),
]


def count(stat):
    cells = {m.group(1): int(m.group(2)) for m in re.finditer(r"^\s+(\w+)\s+(\d+)\s*$", stat, re.M)}
    lut = sum(v for k, v in cells.items() if re.fullmatch(r"LUT[1-6]", k))
    # distributed RAM / shift registers occupy LUTs too
    lutram = {"RAM32X1D": 2, "RAM64X1D": 2, "RAM128X1D": 4, "RAM32M": 4, "RAM64M": 4, "RAM256X1S": 4,
              "RAM128X1S": 2, "RAM64X1S": 1, "RAM32X1S": 1, "SRL16E": 1, "SRLC32E": 1}
    lut_mem = sum(v * lutram[k] for k, v in cells.items() if k in lutram)
    ff = sum(v for k, v in cells.items() if re.fullmatch(r"FD[A-Z]*", k))
    dsp = cells.get("DSP48E1", 0)
    bram = cells.get("RAMB36E1", 0) + 0.5 * cells.get("RAMB18E1", 0)
    return {"lut": lut + lut_mem, "lut_logic": lut, "lut_mem": lut_mem, "ff": ff, "dsp48": dsp, "bram36": bram,
            "carry4": cells.get("CARRY4", 0)}


def synth(block, gen):
    name, top, files, params, thesis = block
    t0 = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        paths = [f.replace("GEN", gen) if f.startswith("GEN") else os.path.join(RTL, f) for f in files]
        subprocess.run([sys.executable, os.path.join(RTL, "synth", "yosys_compat.py"), tmp] + paths, check=True)
        src = " ".join(os.path.join(tmp, os.path.basename(p)) for p in paths)
        chp = " ".join(f"-set {k} {v}" for k, v in params.items())
        script = (f"read_verilog -sv {src}; " + (f"chparam {chp} {top}; " if chp else "") +
                  f"synth_xilinx -family xc7 -top {top} -flatten; stat")
        r = subprocess.run(["yosys", "-p", script], cwd=gen, capture_output=True, text=True)
        out = r.stdout
    if r.returncode != 0:
        return {"block": name, "top": top, "error": (r.stderr or r.stdout)[-2000:]}
    stat = out[out.rfind("Printing statistics"):]
    res = {"block": name, "top": top, "thesis": thesis, "seconds": round(time.time() - t0, 1)}
    res.update(count(stat))
    return res


def main():
    args = sys.argv[1:]
    gen = os.path.abspath(args[0])
    jfile = args[args.index("--json") + 1] if "--json" in args else None
    only = args[args.index("--only") + 1:] if "--only" in args else None
    jobs = int(args[args.index("--jobs") + 1]) if "--jobs" in args else 1
    blocks = [b for b in BLOCKS if not only or b[1] in only]
    print("| block | top | LUTs | FFs | DSP48 | BRAM36 | yosys s |")
    print("|---|---|---:|---:|---:|---:|---:|", flush=True)

    def one(b):
        r = synth(b, gen)
        if "error" in r:
            print(f"| {r['block']} | {r['top']} | error | | | | |", flush=True)
            print(r["error"], file=sys.stderr)
        else:
            print(f"| {r['block']} | {r['top']} | {r['lut']} | {r['ff']} | {r['dsp48']} | {r['bram36']:g} | "
                  f"{r['seconds']} |", flush=True)
        return r

    with concurrent.futures.ThreadPoolExecutor(jobs) as ex:
        results = list(ex.map(one, blocks))
    if jfile:
        with open(jfile + ".tmp", "w") as fh:
            json.dump(results, fh, indent=1)
        os.replace(jfile + ".tmp", jfile)


if __name__ == "__main__":
    main()
