"""The in-tree build backend (python/_backend/wsgemu_build.py), which makes
`pip install ./python` work without a package index: the wheel it builds
is a valid wheel of the package (every file listed in RECORD with its
hash, the pytest11 entry point declared), the metadata follows
pyproject.toml, and its TOML reader for Pythons without tomllib reads
pyproject.toml as tomllib does."""

import base64
import hashlib
import importlib.util
import os
import tarfile
import zipfile

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)  # python/


@pytest.fixture(scope="module")
def backend():
    spec = importlib.util.spec_from_file_location(
        "wsgemu_build", os.path.join(ROOT, "_backend", "wsgemu_build.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_subset_reader_matches_tomllib(backend):
    tomllib = pytest.importorskip("tomllib")  # Python 3.11 and later
    with open(os.path.join(ROOT, "pyproject.toml"), "rb") as f:
        expected = tomllib.load(f)
    with open(os.path.join(ROOT, "pyproject.toml"), encoding="utf-8") as f:
        assert backend.parse_toml_subset(f.read()) == expected


def test_the_subset_reader_handles_what_it_claims(backend):
    text = '''
        # comment
        top = "a \\"q\\" \\u00e9"  # trailing comment
        [t.sub]
        list = [
            "x",  # inside
            'lit\\eral',
        ]
        n = -3
        flag = true
        inline = { k = "v", m = 2 }
        dotted.key = "d"
    '''
    assert backend.parse_toml_subset(text) == {
        "top": 'a "q" \u00e9',
        "t": {"sub": {"list": ["x", "lit\\eral"], "n": -3, "flag": True,
                      "inline": {"k": "v", "m": 2},
                      "dotted": {"key": "d"}}},
    }


def _record_ok(z, record_name):
    rows = z.read(record_name).decode().splitlines()
    listed = set()
    for row in rows:
        name, digest, size = row.rsplit(",", 2)
        listed.add(name)
        if name == record_name:
            assert digest == "" and size == ""
            continue
        data = z.read(name)
        algo, _, value = digest.partition("=")
        assert algo == "sha256"
        want = base64.urlsafe_b64encode(
            hashlib.sha256(data).digest()).rstrip(b"=").decode()
        assert value == want, name
        assert int(size) == len(data), name
    assert listed == set(z.namelist())


def test_wheel_holds_the_package_and_its_entry_point(backend, tmp_path):
    name = backend.build_wheel(str(tmp_path))
    assert name == "wsgemu-0.1.0-py3-none-any.whl"
    with zipfile.ZipFile(tmp_path / name) as z:
        names = set(z.namelist())
        for mod in ("__init__", "client", "daemon", "plugin"):
            assert "wsgemu/%s.py" % mod in names
        assert not any("__pycache__" in n or n.startswith("tests/")
                       for n in names)
        info = "wsgemu-0.1.0.dist-info/"
        assert "[pytest11]\nwsgemu = wsgemu.plugin" in z.read(
            info + "entry_points.txt").decode()
        meta = z.read(info + "METADATA").decode()
        assert "Name: wsgemu\n" in meta
        assert "Requires-Python: >=3.9\n" in meta
        # pytest only for the plugin, as an extra: no runtime dependency.
        requires = [line for line in meta.splitlines()
                    if line.startswith("Requires-Dist:")]
        assert requires == ['Requires-Dist: pytest; extra == "pytest"']
        assert "Root-Is-Purelib: true" in z.read(info + "WHEEL").decode()
        _record_ok(z, info + "RECORD")
    # The same sources make the same wheel, byte for byte.
    again = tmp_path / "again"
    again.mkdir()
    backend.build_wheel(str(again))
    assert (again / name).read_bytes() == (tmp_path / name).read_bytes()


def test_metadata_hook_agrees_with_the_wheel(backend, tmp_path):
    info = backend.prepare_metadata_for_build_wheel(str(tmp_path))
    assert info == "wsgemu-0.1.0.dist-info"
    with open(tmp_path / info / "METADATA", encoding="utf-8") as f:
        assert f.read() == backend.metadata_text()


def test_editable_wheel_points_at_the_source_tree(backend, tmp_path):
    name = backend.build_editable(str(tmp_path))
    with zipfile.ZipFile(tmp_path / name) as z:
        pth = [n for n in z.namelist() if n.endswith(".pth")]
        assert len(pth) == 1
        assert z.read(pth[0]).decode().strip() == ROOT
        _record_ok(z, "wsgemu-0.1.0.dist-info/RECORD")


def test_sdist_can_be_built_again(backend, tmp_path):
    name = backend.build_sdist(str(tmp_path))
    with tarfile.open(tmp_path / name) as tar:
        names = tar.getnames()
    base = "wsgemu-0.1.0/"
    for need in ("PKG-INFO", "pyproject.toml", "README.md",
                 "_backend/wsgemu_build.py", "wsgemu/client.py"):
        assert base + need in names
    assert not any(n.endswith(".pyc") for n in names)


def test_build_hooks_need_nothing(backend):
    # No requirement: pip's isolated build environment stays empty and
    # needs no package index.
    assert backend.get_requires_for_build_wheel() == []
    assert backend.get_requires_for_build_editable() == []
    assert backend.get_requires_for_build_sdist() == []
