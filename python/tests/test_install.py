"""`make install` puts the package where Debian's python3 finds it: <prefix>/lib/python3.X/
dist-packages (for the default prefix /usr/local, on sys.path already)."""

import os
import subprocess
import sys

import pytest


def test_installed_package_imports(tmp_path):
    build = os.environ.get("LAZYBOE_BUILD_DIR")
    if not build:
        pytest.skip("LAZYBOE_BUILD_DIR not set (run through ctest)")
    subprocess.run(["cmake", "--install", build, "--component", "python", "--prefix",
                    str(tmp_path)], check=True, capture_output=True)
    version = f"python{sys.version_info.major}.{sys.version_info.minor}"
    site = tmp_path / "lib" / version / "dist-packages"
    assert (site / "lazyboe" / "__init__.py").is_file()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PYTHONPATH"] = str(site)
    out = subprocess.run(
        [sys.executable, "-c", "import lazyboe; r = lazyboe.Robot(); "
         "print(lazyboe.__file__, r.forward_kinematics([0] * 7).shape)"],
        check=True, capture_output=True, text=True, env=env, cwd=tmp_path).stdout
    assert out.startswith(str(site / "lazyboe")) and "(4, 4)" in out
    # The default prefix's directory is one Debian's python3 searches.
    assert "/usr/local/lib/" + version + "/dist-packages" in sys.path


def test_installed_package_reads_the_installed_data(tmp_path):
    """With the data installed beside it (<prefix>/share/lazyboe), the module reads that, not
    the source tree's (issue 30: the install stands alone)."""
    build = os.environ.get("LAZYBOE_BUILD_DIR")
    if not build:
        pytest.skip("LAZYBOE_BUILD_DIR not set (run through ctest)")
    for component in ("python", "data"):
        subprocess.run(["cmake", "--install", build, "--component", component, "--prefix",
                        str(tmp_path)], check=True, capture_output=True)
    version = f"python{sys.version_info.major}.{sys.version_info.minor}"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "LAZYBOE_DATA_DIR")}
    env["PYTHONPATH"] = str(tmp_path / "lib" / version / "dist-packages")
    out = subprocess.run(
        [sys.executable, "-c", "import lazyboe; print(lazyboe.data_dir()); "
         "print(lazyboe.default_robot_path())"],
        check=True, capture_output=True, text=True, env=env, cwd=tmp_path).stdout.split()
    data = tmp_path / "share" / "lazyboe"
    assert out == [str(data), str(data / "robots" / "panda.json")]
