"""The package's build with setuptools, Debian's (python3-setuptools,
python3-wheel): `pip wheel --no-build-isolation` makes a wheel without a
package index, and that wheel holds the package, its py.typed marker (so
mypy checks users' code against its annotations) and the pytest11 entry
point, depends on nothing at run time, and is tagged pure (py3-none-any):
only scripts/wheel.sh's wheel carries programs and a platform tag."""

import email.parser
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent  # python/


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    pytest.importorskip("setuptools")
    pytest.importorskip("wheel")
    tmp = tmp_path_factory.mktemp("build")
    # A copy: setuptools writes build/ and *.egg-info beside the sources.
    src = tmp / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    shutil.copytree(ROOT / "wsgemu", src / "wsgemu",
                    ignore=shutil.ignore_patterns("__pycache__", "bin"))
    out = tmp / "out"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet",
                    "--no-deps", "--no-index", "--no-build-isolation",
                    "-w", str(out), str(src)], check=True)
    [whl] = out.iterdir()
    return whl


def test_wheel_is_pure_and_named_for_its_version(wheel: Path) -> None:
    assert wheel.name == "wsgemu-0.1.0-py3-none-any.whl"


def test_wheel_holds_the_package_py_typed_and_entry_point(
        wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as z:
        names = set(z.namelist())
        for mod in ("__init__", "client", "daemon", "plugin"):
            assert "wsgemu/%s.py" % mod in names
        assert "wsgemu/py.typed" in names
        assert not any(n.startswith(("tests/", "wsgemu/bin/"))
                       or "__pycache__" in n for n in names)
        info = "wsgemu-0.1.0.dist-info/"
        entry_points = z.read(info + "entry_points.txt").decode()
        assert "[pytest11]\nwsgemu = wsgemu.plugin" in entry_points
        meta = email.parser.Parser().parsestr(
            z.read(info + "METADATA").decode())
    assert meta["Name"] == "wsgemu"
    assert meta["Requires-Python"] == ">=3.9"
    # pytest only for the plugin, as an extra: no runtime dependency.
    # (Spelt "pytest (>=7) ; extra == 'pytest'" by setuptools: compared
    # without blanks, parentheses and quotes.)
    requires = [r.replace(" ", "").replace("(", "").replace(")", "")
                .replace("'", '"')
                for r in meta.get_all("Requires-Dist")]
    assert requires == ['pytest>=7;extra=="pytest"']


def test_the_wheel_is_importable_on_its_own(wheel: Path,
                                           tmp_path: Path) -> None:
    # Unpacked alone on sys.path, without the source tree: the client
    # imports with the standard library only.
    with zipfile.ZipFile(wheel) as z:
        z.extractall(tmp_path)
    out = subprocess.run(
        [sys.executable, "-S", "-c",
         "import wsgemu; print(wsgemu.__file__, wsgemu.__version__)"],
        cwd=str(tmp_path), env={**os.environ, "PYTHONPATH": str(tmp_path)},
        check=True, capture_output=True, text=True).stdout.split()
    assert out == [str(tmp_path / "wsgemu" / "__init__.py"), "0.1.0"]
