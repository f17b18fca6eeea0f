"""`cmake --install` gives a working executable, Python module and recipes."""

import os
import shutil
import subprocess
import sys

import pytest

from conftest import BUILD_DIR


def test_installed_tree_runs_and_imports(tmp_path):
    cmake = os.environ.get("CMAKE_COMMAND") or shutil.which("cmake")
    if cmake is None:
        pytest.skip("no cmake to install with")
    prefix = tmp_path / "prefix"
    subprocess.run([cmake, "--install", str(BUILD_DIR), "--prefix", str(prefix)], check=True,
                   stdout=subprocess.DEVNULL)
    exe = prefix / "bin" / "cadsynth"
    assert exe.is_file()
    assert (prefix / "share" / "cadsynth" / "recipes" / "bin_picking.yaml").is_file()
    version = subprocess.run([str(exe), "--version"], check=True, capture_output=True, text=True)
    assert "cadsynth" in version.stdout
    recipe = tmp_path / "r.yaml"
    recipe.write_text("parts: [{family: round_peg}]\n"
                      "camera: {width: 64, height: 48, fx: 60, fy: 60, cx: 31.5, cy: 23.5}\n"
                      "sweep: {yaw: [0, 90], pitch: [60], radius: [0.3 m]}\n")
    out = tmp_path / "out"
    subprocess.run([str(exe), "generate", str(recipe), "-o", str(out), "--quiet", "--no-cache"],
                   check=True)
    assert (out / "train" / "000000" / "rgb" / "000001.png").is_file()
    # The installed module, in a fresh interpreter that sees only the prefix.
    site = (prefix / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" /
            "dist-packages")
    # The type stub and its marker beside the module, for editors (PEP 561).
    assert (site / "cadsynth" / "_cadsynth.pyi").is_file()
    assert (site / "cadsynth" / "py.typed").is_file()
    code = ("import cadsynth, sys; "
            f"assert cadsynth.__file__.startswith({str(site)!r}), cadsynth.__file__; "
            f"run = cadsynth.Recipe.load({str(recipe)!r}).prepare(cache=False); "
            "f = run.frame(1); "
            f"png = open({str(out / 'train/000000/rgb/000001.png')!r}, 'rb').read(); "
            "assert cadsynth.encode_png(f['rgb']) == png; print('ok')")
    env = dict(os.environ, PYTHONPATH=str(site))
    result = subprocess.run([sys.executable, "-c", code], env=env, check=True,
                            capture_output=True, text=True)
    assert result.stdout.strip() == "ok"
