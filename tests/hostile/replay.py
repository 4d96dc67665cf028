#!/usr/bin/env python3
"""The adversarial harness: replays the classes of hostile input that found omma's reliability bugs,
against the built `omma` binary, as a hostile user would.

  tests/hostile/replay.py --omma build/omma [--seed N] [--rounds K] [--only CLASS ...] [--json]

Classes (each a list of cases; a case fails if omma crashes, hangs, exits with anything but 0 or 1,
exits 1 without one "omma: error:" line, or breaks the class's own contract):
  rigs       lens, field and focal mutations of a rig -> rig check, simulate, stitch: a rig the check
             takes simulates and stitches (exit 0, frames not black); one it refuses is refused by
             simulate too (one validator)
  numbers    every FLOAT, INT and UINT option of every command (parsed from --help) with NaN, inf,
             -inf, out-of-range, negative-for-unsigned and trailing-garbage values: refused, naming
             the option
  fsize      outputs under `ulimit -f 1`: exit 1 with an error, no temporaries left
  signals    `omma run` to an .mp4 stopped by SIGHUP, SIGTERM and SIGINT: exit 0, a playable video
  hw         `omma hw import` of an export with mutated config integers and word streams
  recordings bit flips, truncations, FIFOs and manifest mutations of a recording -> recording check
             and render: exit 0 or 1 within a time bound, never a crash or a hang
  http       the live server (`omma run --sink http:PORT`) with idle, slowloris, multi-range and
             large-body clients: /stats.json answers within a second
Deterministic for a seed; --rounds scales the random cases. Exit status 1 if any case fails.
"""
import argparse
import concurrent.futures
import json
import os
import random
import re
import shutil
import signal
import socket
import stat
import subprocess
import sys
import tempfile
import time

OK_CODES = (0, 1)


class Harness:
    def __init__(self, omma, seed, rounds, verbose):
        self.omma = os.path.abspath(omma)
        self.rng = random.Random(seed)
        self.rounds = rounds
        self.verbose = verbose
        self.tmp = tempfile.mkdtemp(prefix="omma-hostile-")
        self.results = {}
        self.failures = []
        self.cls = ""

    # ------------------------------------------------------------------ running and judging
    def run(self, args, timeout=60, shell_prefix="", cwd=None):
        cmd = shell_prefix + " ".join([self.omma] + args) if shell_prefix else None
        cwd = cwd or self.tmp  # a command that does write (default outputs) writes here
        t0 = time.monotonic()
        try:
            if cmd:
                p = subprocess.run(["sh", "-c", cmd], capture_output=True, text=True, timeout=timeout,
                                   stdin=subprocess.DEVNULL, cwd=cwd)
            else:
                p = subprocess.run([self.omma] + args, capture_output=True, text=True, timeout=timeout,
                                   stdin=subprocess.DEVNULL, cwd=cwd)
            return p.returncode, p.stdout, p.stderr, time.monotonic() - t0
        except subprocess.TimeoutExpired:
            return None, "", "", time.monotonic() - t0

    def case(self, name, ok, detail=""):
        r = self.results.setdefault(self.cls, {"cases": 0, "failed": 0})
        r["cases"] += 1
        if not ok:
            r["failed"] += 1
            self.failures.append(f"[{self.cls}] {name}: {detail}")
            print(f"FAIL [{self.cls}] {name}: {detail}", file=sys.stderr)
        elif self.verbose:
            print(f"ok   [{self.cls}] {name}", file=sys.stderr)

    def judge(self, name, rc, err, seconds, limit_s=60, expect=None):
        """The common contract: exit 0 or 1 in time; exit 1 with an "omma: error:" line."""
        if rc is None:
            return self.case(name, False, f"hung (killed after {seconds:.0f} s)")
        if rc not in OK_CODES:
            how = f"killed by signal {-rc}" if rc < 0 else f"signal {rc - 128}" if rc > 128 else "exit code"
            return self.case(name, False, f"exit {rc} ({how})\n{err[-600:]}")
        if rc == 1 and "omma: error:" not in err:
            return self.case(name, False, f"exit 1 without 'omma: error:'\n{err[-600:]}")
        if seconds > limit_s:
            return self.case(name, False, f"took {seconds:.1f} s (limit {limit_s} s)")
        if expect is not None and rc != expect:
            return self.case(name, False, f"exit {rc}, expected {expect}\n{err[-600:]}")
        self.case(name, True)

    def path(self, *parts):
        return os.path.join(self.tmp, *parts)

    # ------------------------------------------------------------------ fixtures
    def fixture(self):
        """A small rig (the 24-camera prototype at 64 px) and its simulated frames."""
        rig = self.path("rig.json")
        rc, _, err, _ = self.run(["design", "--out", rig])
        assert rc == 0, err
        j = json.load(open(rig))
        for c in j["cameras"]:
            i = c["intrinsics"]
            s = 64 / i["width"]
            i.update(width=64, height=64, fu=i["fu"] * s, fv=i["fv"] * s, cu=i["cu"] * s, cv=i["cv"] * s)
        json.dump(j, open(rig, "w"))
        frames = self.path("frames")
        rc, _, err, _ = self.run(["simulate", "--rig", rig, "--scene", "checker", "--out", frames,
                                  "--truth-size", "128x128"])
        assert rc == 0, err
        return rig, frames

    # ------------------------------------------------------------------ classes
    def rigs(self, rig, frames):
        base = json.load(open(rig))
        lenses = [[-0.5, 0, 0, 0, 0], [-0.3, 0, 0, 0, 0], [-0.25, 0, 0, 0, 0], [-0.1, 0.01, 0, 0, 0],
                  [0.5, 0, 0, 0, 0], [2, 0, 0, 0, 0], [2.5, 0, 0, 0, 0], [10, 3, 0, 0, 1], [1e3, 0, 0, 0, 0],
                  [-1, 0, 0, 0, 0.3], [0, 0, 0.8, 0, 0], [0, 0, 0.02, -0.01, 0], [-0.3, 0.05, 0, 0, 0]]
        for _ in range(self.rounds):
            lenses.append([self.rng.uniform(-1, 3), self.rng.uniform(-1, 1), self.rng.uniform(-0.1, 0.1),
                           self.rng.uniform(-0.1, 0.1), self.rng.uniform(-1, 1)])
        variants = []
        for k in lenses:
            for aov in (64, 120):
                variants.append((f"k={k} aov={aov}", {"k": k, "aov_deg": aov}))
        variants += [("field image, k1=-0.3", {"k": [-0.3, 0, 0, 0, 0], "field": "image"}),
                     ("focal 1e-3 x side", {"fu": 0.064, "fv": 0.064}),
                     ("focal 1e4 x side", {"fu": 6.4e5, "fv": 6.4e5, "aov_deg": 1})]
        for name, change in variants:
            j = json.loads(json.dumps(base))
            for c in j["cameras"]:
                c["intrinsics"].update(change)
            f = self.path("mut_rig.json")
            json.dump(j, open(f, "w"))
            rc, _, err, s = self.run(["rig", "check", f])
            self.judge(name + ": rig check", rc, err, s, 10)
            out = self.path("mut_sim")
            shutil.rmtree(out, ignore_errors=True)
            rs, _, err_s, s = self.run(["simulate", "--rig", f, "--scene", "checker", "--out", out,
                                        "--truth-size", "64x64"], timeout=120)
            self.judge(name + ": simulate", rs, err_s, s, 120, expect=rc if rc in OK_CODES else None)
            if rs == 0:
                pano = self.path("mut_pano.png")
                rp, _, err_p, s = self.run(["stitch", "--rig", f, "--frames", out, "--out", pano,
                                            "--size", "128x128", "--method", "linear"])
                self.judge(name + ": stitch", rp, err_p, s, 60, expect=0)

    def numbers(self):
        bad = {"FLOAT": ["nan", "inf", "-inf", "3abc"], "INT": ["1e23", "99999999999999999999", "0x10zz"],
               "UINT": ["-1", "1e23", "18446744073709551616"]}
        rc, out, _, _ = self.run(["--help"])
        commands = re.findall(r"^  ([a-z][a-z0-9-]*)\s", out[out.find("Subcommands:"):], re.M)
        todo = [[c] for c in commands]
        runs = []
        while todo:
            cmd = todo.pop(0)
            rc, out, _, _ = self.run(cmd + ["--help"])
            if "Subcommands:" in out:
                todo += [cmd + [s] for s in re.findall(r"^  ([a-z][a-z0-9-]*)\s", out[out.find("Subcommands:"):], re.M)]
            for opt, kind in re.findall(r"^  (?:-\w,)?(--[a-z0-9-]+) (FLOAT|INT|UINT)\b", out, re.M):
                runs += [(cmd, opt, v) for v in bad[kind]]
        # omma starts in about 0.1 s (its shared libraries): four at a time.
        with concurrent.futures.ThreadPoolExecutor(4) as pool:
            results = list(pool.map(lambda r: self.run(r[0] + [r[1], r[2]], timeout=30), runs))
        for (cmd, opt, v), (rc, _, err, s) in zip(runs, results):
            name = " ".join(cmd + [opt, v])
            self.judge(name, rc, err, s, 10, expect=1)
            if rc == 1 and opt not in err:
                self.case(name + " names the option", False, err.strip()[:300])
        self.case(f"{len(runs)} option values tried", len(runs) > 100, "too few options found in --help")

    def fsize(self, rig, frames):
        out = self.path("fsize")
        shutil.rmtree(out, ignore_errors=True)
        os.makedirs(out)
        link_in = self.path("fsize_raw.png")
        cases = [
            ["stitch", "--rig", rig, "--frames", frames, "--out", f"{out}/s.png", "--size", "512x512"],
            ["render", frames, "--rig", rig, "--out", f"{out}/big.tif", "--size", "2048x1024", "--no-cache"],
            ["render", frames, "--rig", rig, "--out", f"{out}/big.png", "--size", "2048x1024", "--no-cache"],
            ["render", frames, "--rig", rig, "--out", f"{out}/t.tif", "--size", "2048x1024", "--no-cache",
             "--split", "tiles"],
            ["simulate", "--rig", rig, "--scene", "checker", "--out", f"{out}/sim", "--truth-size", "64x64"],
            ["pto", "export", rig, f"{out}/p.pto"],
            ["hw", "export", rig, f"{out}/chip"],
            ["record", "--rig", rig, "--source", f"frames:{frames}", "--out", f"{out}/rec", "--frames", "3",
             "--fps", "10"],
        ]
        for args in cases:
            rc, _, err, s = self.run(args, shell_prefix="ulimit -f 1; exec ", timeout=120)
            self.judge("ulimit -f 1: " + " ".join(args[:2]), rc, err, s, 120, expect=1)
            left = [n for _, ds, fs in os.walk(out) for n in ds + fs if ".tmp" in n or ".partial" in n]
            self.case("no temporaries after " + " ".join(args[:2]), not left, str(left))

    def signals(self, rig, frames):
        for sig in (signal.SIGHUP, signal.SIGTERM, signal.SIGINT):
            video = self.path(f"sig_{sig.name}.mp4")
            p = subprocess.Popen([self.omma, "run", "--rig", rig, "--source", f"frames:{frames}", "--sink", video,
                                  "--size", "256x256", "--fps", "20", "--duration", "60", "--json"],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
            time.sleep(3)
            p.send_signal(sig)
            try:
                out, err = p.communicate(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
                self.case(sig.name, False, "did not stop within 30 s")
                continue
            self.judge(f"{sig.name} stops omma run", p.returncode, err.decode(), 0, 60, expect=0)
            probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0",
                                    "-show_entries", "stream=nb_read_frames", "-of", "csv=p=0", video],
                                   capture_output=True, text=True)
            frames_read = int(probe.stdout.strip().strip(',') or 0) if probe.returncode == 0 else 0
            self.case(f"{sig.name}: playable video", frames_read > 5, f"ffprobe: {probe.stderr[-300:]}")

    def hw(self, rig):
        chip = self.path("chip")
        shutil.rmtree(chip, ignore_errors=True)
        rc, _, err, _ = self.run(["hw", "export", rig, chip])
        if rc != 0:
            return self.case("hw export", False, err)
        good = {n: open(os.path.join(chip, n), "rb").read() for n in os.listdir(chip)}
        config = json.loads(good["config.json"])
        out = self.path("hw_rig.json")

        def attempt(name, files):
            for n, data in files.items():
                open(os.path.join(chip, n), "wb").write(data)
            rc, _, err, s = self.run(["hw", "import", chip, out])
            self.judge(name, rc, err, s, 30)
            for n in files:
                open(os.path.join(chip, n), "wb").write(good[n])
            return rc

        for field in config["hw"]:
            if isinstance(config["hw"][field], bool):
                continue
            for v in (2 ** 32 + config["hw"][field], -2 ** 31, 1e300, 12.7, True, "12", None):
                c = json.loads(json.dumps(config))
                c["hw"][field] = v
                rc = attempt(f"config {field}={v!r}", {"config.json": json.dumps(c).encode()})
                if isinstance(v, (bool, str, float)) or v is None or v > 2 ** 31:
                    self.case(f"config {field}={v!r} refused", rc == 1, f"exit {rc}")
        for w in (-64, 0, 2 ** 32 + 64, 1080.5, "1080"):
            c = json.loads(json.dumps(config))
            c["grid"]["width"] = w
            rc = attempt(f"grid width {w!r}", {"config.json": json.dumps(c).encode()})
            self.case(f"grid width {w!r} refused", rc == 1, f"exit {rc}")
        hexes = [n for n in good if n.endswith(".hex") and n in ("regs.hex", "pix_pos.hex", "cam_search.hex",
                                                                  "pix_val.hex")]
        for _ in range(4 * self.rounds):
            n = self.rng.choice(hexes)
            lines = good[n].decode().splitlines(True)
            how = self.rng.choice(["drop", "flip", "garbage", "empty", "dup"])
            if how == "drop" and len(lines) > 1:
                del lines[self.rng.randrange(len(lines))]
            elif how == "flip":
                i = self.rng.randrange(len(lines))
                lines[i] = re.sub(r"[0-9A-Fa-f]", lambda m: self.rng.choice("0123456789ABCDEF"), lines[i], count=1)
            elif how == "garbage":
                lines.insert(self.rng.randrange(len(lines) + 1), "zz@@\n")
            elif how == "empty":
                lines = []
            else:
                lines.append(lines[self.rng.randrange(len(lines))] if lines else "")
            rc = attempt(f"{n}: {how}", {n: "".join(lines).encode()})
            if how in ("empty", "garbage"):
                self.case(f"{n}: {how} refused", rc == 1, f"exit {rc}")

    def recordings(self, rig, frames):
        rec = self.path("rec")
        shutil.rmtree(rec, ignore_errors=True)
        rc, _, err, _ = self.run(["record", "--rig", rig, "--source", f"frames:{frames}", "--out", rec,
                                  "--frames", "4", "--fps", "10"], timeout=120)
        if rc != 0:
            return self.case("record", False, err)
        streams = sorted(n for n in os.listdir(rec) if n.endswith(".h5"))
        good_manifest = json.load(open(os.path.join(rec, "manifest.json")))

        def check(name, work):
            for args in (["recording", "check", work], ["render", work, "--out", self.path("rec_pano.png"),
                                                         "--size", "256x128", "--no-cache", "--sets", "0"]):
                rc, _, err, s = self.run(args, timeout=60)
                self.judge(f"{name}: {args[0]}", rc, err, s, 30)

        def copy():
            work = self.path("rec_work")
            shutil.rmtree(work, ignore_errors=True)
            shutil.copytree(rec, work)
            return work

        for i in range(4 * self.rounds):
            work = copy()
            s = os.path.join(work, self.rng.choice(streams))
            data = bytearray(open(s, "rb").read())
            at = self.rng.randrange(len(data))
            data[at] ^= 1 << self.rng.randrange(8)
            open(s, "wb").write(bytes(data))
            check(f"bit flip at {at} of {os.path.basename(s)}", work)
        for frac in (0.0, 0.1, 0.5, 0.99):
            work = copy()
            s = os.path.join(work, streams[0])
            os.truncate(s, int(os.path.getsize(s) * frac))
            check(f"{streams[0]} truncated to {frac:.0%}", work)
        work = copy()
        os.remove(os.path.join(work, streams[0]))
        os.mkfifo(os.path.join(work, streams[0]))
        check("FIFO in place of a stream", work)
        mutations = [("bits", 2 ** 32 + 12), ("bits", 12.7), ("version", True), ("fps", 1e-12), ("fps", "30"),
                     ("fps", 1e300), ("clock_mhz", -1), ("bits", -4), ("start_unix_ns", 1.5)]
        mutations += [("streams", list(reversed(good_manifest["streams"]))),
                      ("streams", good_manifest["streams"][:1] * len(good_manifest["streams"])),
                      ("streams", [dict(s, file=s["file"] + "\u0000x") for s in good_manifest["streams"]]),
                      ("streams", [dict(s, file="../" + s["file"]) for s in good_manifest["streams"]]),
                      ("streams", [dict(s, width=2 ** 32 + s["width"]) for s in good_manifest["streams"]])]
        for key, value in mutations:
            work = copy()
            m = json.loads(json.dumps(good_manifest))
            m[key] = value
            json.dump(m, open(os.path.join(work, "manifest.json"), "w"))
            rc, _, err, s = self.run(["recording", "check", work], timeout=60)
            self.judge(f"manifest {key}={str(value)[:40]}", rc, err, s, 30, expect=1)

    def http(self, rig, frames):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        p = subprocess.Popen([self.omma, "run", "--rig", rig, "--source", f"frames:{frames}", "--sink",
                              f"http:{port}", "--size", "512x512", "--fps", "10", "--duration", "60"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
        try:
            for _ in range(100):
                try:
                    socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
                    break
                except OSError:
                    time.sleep(0.1)

            def get(path, timeout=5, extra=b""):
                """The whole answer; what arrived before `timeout` if the server stalls or resets."""
                data = b""
                try:
                    c = socket.create_connection(("127.0.0.1", port), timeout=timeout)
                    c.sendall(b"GET " + path.encode() + b" HTTP/1.1\r\nHost: x\r\n" + extra + b"\r\n")
                    while True:
                        chunk = c.recv(65536)
                        if not chunk:
                            break
                        data += chunk
                    c.close()
                except OSError:
                    pass
                return data

            time.sleep(2)
            frame = get("/frame.jpg")
            hold = []
            for _ in range(50):  # idle
                hold.append(socket.create_connection(("127.0.0.1", port)))
            slow = []
            for _ in range(12):  # slowloris: a header byte now and then
                c = socket.create_connection(("127.0.0.1", port))
                c.sendall(b"GET /stats.json HTTP/1.1\r\n")
                slow.append(c)
            ranges = b"Range: bytes=" + b",".join([b"0-"] * 500) + b"\r\n"
            big = get("/frame.jpg", extra=ranges)
            self.case("multi-range answer not amplified", len(big) <= len(frame) + 2048,
                      f"{len(big)} bytes for a {len(frame)}-byte frame")
            worst = 0
            for i in range(6):
                for c in slow:
                    try:
                        c.sendall(b"X")
                    except OSError:
                        pass
                t0 = time.monotonic()
                ok = b"200 OK" in get("/stats.json", timeout=3)[:64]
                worst = max(worst, time.monotonic() - t0 if ok else float("inf"))
                time.sleep(0.3)
            self.case("/stats.json within 1 s under idle and slowloris clients", worst < 1.0,
                      f"worst {worst:.2f} s" if worst < float("inf") else "a probe got no answer within 3 s")
            try:
                c = socket.create_connection(("127.0.0.1", port), timeout=5)
                c.sendall(b"POST /stats.json HTTP/1.1\r\nHost: x\r\nContent-Length: 1000000000\r\n\r\n")
                answer = c.recv(256)
                c.close()
            except OSError as e:
                answer = str(e).encode()
            self.case("a large POST is refused before its body", answer[:12] in (b"HTTP/1.1 405", b"HTTP/1.1 413"),
                      repr(answer[:40]))
            for c in hold + slow:
                c.close()
        finally:
            p.send_signal(signal.SIGTERM)
            try:
                _, err = p.communicate(timeout=30)
                self.judge("live server stops on SIGTERM", p.returncode, err.decode(), 0, 60, expect=0)
            except subprocess.TimeoutExpired:
                p.kill()
                self.case("live server stops on SIGTERM", False, "hung")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--omma", default="build/omma", help="the omma binary (default build/omma)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the random cases (default 1)")
    ap.add_argument("--rounds", type=int, default=3, help="scale of the random cases (default 3)")
    classes = ["rigs", "numbers", "fsize", "signals", "hw", "recordings", "http"]
    ap.add_argument("--only", nargs="*", choices=classes, help="run only these classes")
    ap.add_argument("--json", action="store_true", help="print a JSON summary on stdout")
    ap.add_argument("-v", "--verbose", action="store_true", help="print every case")
    ap.add_argument("--keep", action="store_true", help="keep the temporary folder")
    a = ap.parse_args()
    h = Harness(a.omma, a.seed, a.rounds, a.verbose)
    t0 = time.monotonic()
    try:
        rig, frames = h.fixture()
        for c in a.only or classes:
            h.cls = c
            t = time.monotonic()
            fn = getattr(h, c)
            if c == "numbers":
                fn()
            elif c == "hw":
                fn(rig)
            else:
                fn(rig, frames)
            h.results.setdefault(c, {"cases": 0, "failed": 0})["seconds"] = round(time.monotonic() - t, 1)
            r = h.results[c]
            print(f"{c:11s} {r['cases']:5d} cases  {r['failed']:3d} failed  {r['seconds']:6.1f} s", file=sys.stderr)
    finally:
        if not a.keep:
            shutil.rmtree(h.tmp, ignore_errors=True)
    total = sum(r["cases"] for r in h.results.values())
    failed = sum(r["failed"] for r in h.results.values())
    summary = {"seed": a.seed, "rounds": a.rounds, "cases": total, "failed": failed,
               "seconds": round(time.monotonic() - t0, 1), "classes": h.results, "failures": h.failures}
    if a.json:
        print(json.dumps(summary, indent=2))
    print(f"hostile replay: {total} cases, {failed} failed, {summary['seconds']} s", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
