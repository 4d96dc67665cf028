"""Rigs from Python: load, validate, save, JSON round trips, design; errors as the command line's."""
import json
import subprocess
from pathlib import Path

import pytest

import omma
from conftest import omma_binary


def test_prototype_rig(rig):
    assert len(rig) == 24
    assert rig.name == "thesis-24"
    assert rig.camera_ids == list(range(24))
    assert rig.camera_sizes == [(250, 250)] * 24


def test_save_load_round_trip(rig, tmp_path):
    path = tmp_path / "rig.json"
    rig.save(str(path))
    back = omma.Rig.load(str(path))
    assert back.to_dict() == rig.to_dict()
    assert omma.Rig.from_json(rig.to_json()).to_dict() == rig.to_dict()
    assert omma.Rig.from_dict(json.loads(path.read_text())).to_dict() == rig.to_dict()
    assert omma.load_rig(str(path)).to_dict() == rig.to_dict()


def test_design_max_volume_reproduces_thesis_layers():
    # thesis §3.4.2: 1x1x2 mm cameras on a 5 mm dome, AOV 64 deg -> 3 + 9 + 12 = 24
    d = omma.design("max-volume", aov_deg=64, r_phys_mm=5, cam_size="1x1x2", compute_r_virtual=False)
    assert d.layers == [3, 9, 12]
    assert len(d.rig) == 24
    d.rig.validate()


def test_design_layered_count():
    # README's table: layered, AOV 64 deg, R_vir 15 mm -> 29 cameras (1 + 5 + 10 + 13)
    d = omma.design("layered", aov_deg=64, r_virtual_mm=15, compute_r_virtual=False)
    assert d.layers == [1, 5, 10, 13]


def bad_rig_dict(rig):
    d = rig.to_dict()
    d["cameras"][3]["intrinsics"]["fu"] = -5
    return d


def test_invalid_rig_raises_rig_error(rig):
    with pytest.raises(omma.RigError) as e:
        omma.Rig.from_dict(bad_rig_dict(rig))
    assert isinstance(e.value, ValueError) and isinstance(e.value, omma.Error)
    assert "fu" in str(e.value)


def test_errors_have_the_command_lines_messages(rig, tmp_path):
    """The exception text is what `omma rig check` prints after 'omma: error: '."""
    exe = omma_binary()
    if exe is None:
        pytest.skip("OMMA_BINARY not set")
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(bad_rig_dict(rig)))
    missing = tmp_path / "missing.json"
    for path, error in ((bad, omma.RigError), (missing, omma.RigError)):
        with pytest.raises(error) as e:
            omma.Rig.load(str(path))
        cli = subprocess.run([exe, "rig", "check", str(path)], capture_output=True, text=True)
        assert cli.returncode == 1
        assert cli.stderr.strip() == "omma: error: " + str(e.value)


def test_missing_image_is_an_os_error(tmp_path):
    with pytest.raises(omma.IoError) as e:
        omma.read_image(str(tmp_path / "nothing.png"))
    assert isinstance(e.value, OSError)
    assert "nothing.png' does not exist" in str(e.value)


def test_set_verbosity(rig, capfd):
    d = rig.to_dict()
    d["cameras"] = d["cameras"][:3]
    small = omma.Rig.from_dict(d)
    run = lambda: omma.simulate(small, scene="checker", truth=False, supersample=1, progress=True)
    run()
    assert "simulate cameras: 100%" in capfd.readouterr().err
    omma.set_verbosity("quiet")
    try:
        run()
        assert capfd.readouterr().err == ""
    finally:
        omma.set_verbosity("info")
    with pytest.raises(ValueError, match="verbosity must be quiet, info or debug"):
        omma.set_verbosity("loud")


def test_version_is_the_version_file():
    version_file = Path(__file__).resolve().parents[2] / "VERSION"
    assert omma.__version__ == version_file.read_text().strip()
