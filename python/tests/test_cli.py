"""The `omma` console command of the package (omma._cli: `python3 -m omma`, and the `omma` script
that `pip install .` puts on PATH, executing the binary bundled as omma/bin/omma), and the examples
in examples/python."""
import json
import os
import re
import shutil
import subprocess
import sys
import venv
from pathlib import Path

import pytest

import omma
from conftest import omma_binary

SOURCE = Path(os.environ.get("OMMA_SOURCE_DIR") or Path(__file__).resolve().parents[2])
PACKAGE_ROOT = str(Path(omma.__file__).resolve().parent.parent)
VERSION = (SOURCE / "VERSION").read_text().strip()


def clean_env(**extra):
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "OMMA_BINARY")}
    env.update(extra)
    return env


@pytest.mark.skipif(omma_binary() is None, reason="OMMA_BINARY (the built omma command) not given")
def test_python_m_omma_runs_the_command():
    r = subprocess.run([sys.executable, "-m", "omma", "plan", "--row", "1", "--json"],
                       env=clean_env(PYTHONPATH=PACKAGE_ROOT, OMMA_BINARY=omma_binary()),
                       capture_output=True, text=True)
    assert r.returncode == 1  # row 1 does not hold: the command's own exit status
    cli = json.loads(r.stdout)
    assert cli["camera"] == omma.plan(row=1)["camera"]
    r = subprocess.run([sys.executable, "-m", "omma", "--version"],
                       env=clean_env(PYTHONPATH=PACKAGE_ROOT, OMMA_BINARY=omma_binary()), capture_output=True,
                       text=True)
    assert r.returncode == 0 and r.stdout.splitlines()[0] == f"omma {VERSION}"


def test_without_a_binary_the_command_says_so():
    if (Path(omma.__file__).parent / "bin" / "omma").exists():
        pytest.skip("this package bundles the binary")
    r = subprocess.run([sys.executable, "-m", "omma", "--version"], env=clean_env(PYTHONPATH=PACKAGE_ROOT),
                       capture_output=True, text=True)
    assert r.returncode == 2 and "has no bundled omma binary" in r.stderr and "OMMA_BINARY" in r.stderr


def prebuilt_dir():
    exe = omma_binary()
    if not exe:
        return None
    build = Path(exe).resolve().parent
    return build if list((build / "python" / "omma").glob("_omma*.so")) else None


@pytest.mark.skipif(prebuilt_dir() is None, reason="needs the build folder (OMMA_BINARY=BUILD/omma)")
def test_pip_install_puts_an_omma_command_on_path(tmp_path):
    """pip install (offline: --no-build-isolation --no-deps, Debian's setuptools) of the package with
    OMMA_PREBUILT_DIR = this build: the wheel holds the module, the stubs and the binary, and the
    environment's bin/omma runs it."""
    try:
        import setuptools  # noqa: F401
        import wheel  # noqa: F401
    except ImportError:
        pytest.skip("setuptools and wheel (python3-setuptools, python3-wheel) are needed")
    src = tmp_path / "src"
    (src / "python").mkdir(parents=True)
    for f in ("pyproject.toml", "setup.py", "README.md", "VERSION", "LICENSE"):
        shutil.copy(SOURCE / f, src / f)
    shutil.copytree(SOURCE / "python" / "omma", src / "python" / "omma",
                    ignore=shutil.ignore_patterns("__pycache__"))
    env_dir = tmp_path / "env"
    venv.create(env_dir, system_site_packages=True, with_pip=False)
    env = clean_env(OMMA_PREBUILT_DIR=str(prebuilt_dir()), PIP_NO_INDEX="1")
    r = subprocess.run([str(env_dir / "bin" / "python"), "-m", "pip", "install", "-q", "--no-build-isolation",
                        "--no-deps", str(src)], env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    pkg = next((env_dir / "lib").glob("python3*/site-packages/omma"))
    assert {"__init__.pyi", "py.typed", "_cli.py"} <= {p.name for p in pkg.iterdir()}
    assert os.access(pkg / "bin" / "omma", os.X_OK)
    env = clean_env()
    r = subprocess.run([str(env_dir / "bin" / "omma"), "--version"], env=env, capture_output=True, text=True)
    assert r.returncode == 0 and r.stdout.splitlines()[0] == f"omma {VERSION}"
    r = subprocess.run([str(env_dir / "bin" / "omma"), "plan", "--row", "8", "--json"], env=env,
                       capture_output=True, text=True)
    cli = json.loads(r.stdout)
    py = json.loads(subprocess.run([str(env_dir / "bin" / "python"), "-c",
                                    "import json, omma; print(json.dumps(omma.plan(row=8)))"],
                                   env=env, capture_output=True, text=True, check=True).stdout)
    assert cli["camera"] == py["camera"] and r.returncode == (0 if py["feasible"] else 1)


@pytest.fixture(scope="module")
def equirect_folder(rig, tmp_path_factory):
    d = tmp_path_factory.mktemp("eq") / "frames"
    omma.simulate(rig, scene="colon", projection="equirect", size=(360, 90), supersample=1,
                  truth_supersample=1).save(d)
    return d


def compare(folder, out, *args):
    return subprocess.run([sys.executable, str(SOURCE / "examples" / "python" / "compare_methods.py"), str(folder),
                           "--seconds", "0.02", "--out", str(out), *args],
                          env=clean_env(PYTHONPATH=PACKAGE_ROOT), capture_output=True, text=True)


def psnrs(stdout):
    return [float(m.group(1)) for m in re.finditer(r"^(?:nn|mrf)\s+[\d.]+\s+[\d.]+\s+([\d.]+)", stdout, re.M)]


def test_compare_methods_reads_the_folders_projection(equirect_folder, tmp_path):
    r = compare(equirect_folder, tmp_path / "a")
    assert r.returncode == 0, r.stderr
    assert "24 cameras, equirect 360x90" in r.stdout and "UserWarning" not in r.stderr
    assert min(psnrs(r.stdout)) > 25  # 28.5 dB measured (14.6 dB when taken for vr180)
    # Without sim.json it cannot tell: it warns, and --projection says it.
    bare = tmp_path / "bare"
    shutil.copytree(equirect_folder, bare)
    (bare / "sim.json").unlink()
    r = compare(bare, tmp_path / "b")
    assert r.returncode == 0 and "assuming vr180" in r.stderr and "UserWarning" in r.stderr
    assert max(psnrs(r.stdout)) < 20
    r = compare(bare, tmp_path / "c", "--projection", "equirect")
    assert r.returncode == 0 and "assuming" not in r.stderr and min(psnrs(r.stdout)) > 25


@pytest.mark.skipif(shutil.which("ffprobe") is None, reason="ffprobe not installed")
def test_record_and_render_example(frames_dir, tmp_path):
    out = tmp_path / "rr"
    r = subprocess.run([sys.executable, str(SOURCE / "examples" / "python" / "record_and_render.py"),
                        "--source", f"frames:{frames_dir}", "--seconds", "0.3", "--frames", "4", "--size", "360x360",
                        "--out", str(out)], env=clean_env(PYTHONPATH=PACKAGE_ROOT), capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    sets = int(re.search(r"^(\d+) frame sets", r.stdout, re.M).group(1))
    assert sets == len(omma.Recording(out / "rec")) and sets >= 3
    assert "(360x360 vr180)" in r.stdout and omma.read_image(out / "pano.tif").shape == (360, 360, 3)
    probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-show_entries", "stream=nb_read_frames",
                            "-of", "csv=p=0", str(out / "live.mp4")], capture_output=True, text=True, check=True)
    assert int(re.match(r"\d+", probe.stdout).group()) == 4 and "live: 4 panoramas 360x360" in r.stdout
