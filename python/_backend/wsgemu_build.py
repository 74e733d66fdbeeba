"""A PEP 517 build backend for the wsgemu package, on the standard library.

pip builds a project in an isolated environment into which it installs the
backend's requirements from a package index. A machine that reaches no index
cannot get setuptools that way, so this backend requires nothing: pip finds
it through ``backend-path`` in pyproject.toml, and ``pip install ./python``
works offline. It builds a pure-Python wheel of the ``wsgemu`` package, an
editable wheel (a .pth file naming this source tree) and an sdist. The
metadata comes from the ``[project]`` table of pyproject.toml; the few
fields this package uses are the ones it understands.
"""

import base64
import hashlib
import io
import os
import re
import tarfile
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGE = "wsgemu"
# Fixed timestamps make the same sources give the same wheel, byte for byte
# (zip cannot store dates before 1980).
ZIP_DATE = (1980, 1, 1, 0, 0, 0)
WHEEL_TEXT = (
    "Wheel-Version: 1.0\n"
    "Generator: wsgemu_build\n"
    "Root-Is-Purelib: true\n"
    "Tag: py3-none-any\n"
)


# ---- pyproject.toml ----

def _parse_string(s, i):
    """A basic ("...") or literal ('...') TOML string at s[i]: (value, end)."""
    quote = s[i]
    j = i + 1
    out = []
    while j < len(s):
        c = s[j]
        if c == quote:
            return "".join(out), j + 1
        if c == "\\" and quote == '"':
            esc = s[j + 1]
            simple = {"n": "\n", "t": "\t", '"': '"', "\\": "\\", "r": "\r"}
            if esc in simple:
                out.append(simple[esc])
                j += 2
                continue
            if esc in "uU":
                n = 4 if esc == "u" else 8
                out.append(chr(int(s[j + 2:j + 2 + n], 16)))
                j += 2 + n
                continue
            raise ValueError("unsupported escape \\%s" % esc)
        out.append(c)
        j += 1
    raise ValueError("unterminated string")


def _skip(s, i):
    """Past whitespace, newlines and comments."""
    while i < len(s):
        if s[i] in " \t\r\n":
            i += 1
        elif s[i] == "#":
            while i < len(s) and s[i] != "\n":
                i += 1
        else:
            break
    return i


def _parse_value(s, i):
    i = _skip(s, i)
    c = s[i]
    if c in "\"'":
        return _parse_string(s, i)
    if c == "[":
        items = []
        i += 1
        while True:
            i = _skip(s, i)
            if s[i] == "]":
                return items, i + 1
            v, i = _parse_value(s, i)
            items.append(v)
            i = _skip(s, i)
            if s[i] == ",":
                i += 1
    if c == "{":
        table = {}
        i += 1
        while True:
            i = _skip(s, i)
            if s[i] == "}":
                return table, i + 1
            m = re.compile(r"([A-Za-z0-9_-]+)\s*=").match(s, i)
            if not m:
                raise ValueError("bad inline table at %d" % i)
            table[m.group(1)], i = _parse_value(s, m.end())
            i = _skip(s, i)
            if s[i] == ",":
                i += 1
    m = re.compile(r"true|false|[+-]?[0-9]+").match(s, i)
    if not m:
        raise ValueError("unsupported value at %d" % i)
    t = m.group(0)
    return (t == "true") if t in ("true", "false") else int(t), m.end()


def parse_toml_subset(text):
    """The part of TOML this project's pyproject.toml uses: [tables] with
    dotted bare keys, strings, integers, booleans, arrays (over several
    lines too) and inline tables. Used where tomllib is missing
    (Python < 3.11)."""
    data = {}
    table = data
    i = 0
    key_re = re.compile(r"([A-Za-z0-9_.-]+)\s*=")
    head_re = re.compile(r"\[([A-Za-z0-9_.-]+)\]")
    while True:
        i = _skip(text, i)
        if i >= len(text):
            return data
        m = head_re.match(text, i)
        if m:
            table = data
            for part in m.group(1).split("."):
                table = table.setdefault(part, {})
            i = m.end()
            continue
        m = key_re.match(text, i)
        if not m:
            raise ValueError("pyproject.toml: cannot read line at %d" % i)
        value, i = _parse_value(text, m.end())
        parts = m.group(1).split(".")
        t = table
        for part in parts[:-1]:
            t = t.setdefault(part, {})
        t[parts[-1]] = value


def load_pyproject(root=ROOT):
    with open(os.path.join(root, "pyproject.toml"), "rb") as f:
        raw = f.read()
    try:
        import tomllib
    except ImportError:
        return parse_toml_subset(raw.decode("utf-8"))
    return tomllib.loads(raw.decode("utf-8"))


# ---- metadata ----

def _project(root=ROOT):
    return load_pyproject(root)["project"]


def _dist_name(project):
    # The file name form of the distribution name (PEP 427, PEP 503).
    return re.sub(r"[-_.]+", "_", project["name"]).lower()


def metadata_text(root=ROOT):
    """Core metadata (METADATA, PKG-INFO), version 2.1."""
    p = _project(root)
    lines = [
        "Metadata-Version: 2.1",
        "Name: %s" % p["name"],
        "Version: %s" % p["version"],
    ]
    if "description" in p:
        lines.append("Summary: %s" % p["description"])
    if "requires-python" in p:
        lines.append("Requires-Python: %s" % p["requires-python"])
    for c in p.get("classifiers", []):
        lines.append("Classifier: %s" % c)
    for d in p.get("dependencies", []):
        lines.append("Requires-Dist: %s" % d)
    for extra, deps in sorted(p.get("optional-dependencies", {}).items()):
        lines.append("Provides-Extra: %s" % extra)
        for d in deps:
            lines.append('Requires-Dist: %s; extra == "%s"' % (d, extra))
    body = ""
    if "readme" in p:
        lines.append("Description-Content-Type: text/markdown")
        with open(os.path.join(root, p["readme"]), encoding="utf-8") as f:
            body = f.read()
    return "\n".join(lines) + "\n\n" + body


def entry_points_text(root=ROOT):
    p = _project(root)
    groups = dict(p.get("entry-points", {}))
    if p.get("scripts"):
        groups["console_scripts"] = p["scripts"]
    out = []
    for group in sorted(groups):
        out.append("[%s]" % group)
        for name, target in sorted(groups[group].items()):
            out.append("%s = %s" % (name, target))
        out.append("")
    return "\n".join(out)


def _dist_info_files(root=ROOT):
    """(name, bytes) of the .dist-info directory, RECORD excepted."""
    return [
        ("METADATA", metadata_text(root).encode("utf-8")),
        ("WHEEL", WHEEL_TEXT.encode("ascii")),
        ("entry_points.txt", entry_points_text(root).encode("utf-8")),
        ("top_level.txt", (PACKAGE + "\n").encode("ascii")),
    ]


def _package_files(root=ROOT):
    """(path in the wheel, absolute path) of the package's sources."""
    out = []
    base = os.path.join(root, PACKAGE)
    for dirpath, dirnames, filenames in os.walk(base):
        dirnames[:] = sorted(d for d in dirnames if d != "__pycache__")
        for name in sorted(filenames):
            if name.endswith(".py") or name == "py.typed":
                full = os.path.join(dirpath, name)
                rel = os.path.relpath(full, root).replace(os.sep, "/")
                out.append((rel, full))
    return out


# ---- wheels ----

def _record_line(name, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest())
    return "%s,sha256=%s,%d" % (name, digest.rstrip(b"=").decode(), len(data))


def _write_wheel(wheel_directory, contents, root=ROOT):
    """Write a wheel holding contents [(name, bytes)] plus the dist-info."""
    p = _project(root)
    dist = "%s-%s" % (_dist_name(p), p["version"])
    info = dist + ".dist-info"
    files = list(contents)
    files += [(info + "/" + n, d) for n, d in _dist_info_files(root)]
    record = [_record_line(n, d) for n, d in files]
    record.append(info + "/RECORD,,")
    files.append((info + "/RECORD", ("\n".join(record) + "\n").encode()))
    filename = dist + "-py3-none-any.whl"
    with zipfile.ZipFile(os.path.join(wheel_directory, filename), "w",
                         zipfile.ZIP_DEFLATED) as z:
        for name, data in files:
            zi = zipfile.ZipInfo(name, ZIP_DATE)
            zi.external_attr = 0o644 << 16
            zi.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(zi, data)
    return filename


def get_requires_for_build_wheel(config_settings=None):
    return []


def get_requires_for_build_editable(config_settings=None):
    return []


def get_requires_for_build_sdist(config_settings=None):
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    p = _project()
    info = "%s-%s.dist-info" % (_dist_name(p), p["version"])
    os.makedirs(os.path.join(metadata_directory, info), exist_ok=True)
    for name, data in _dist_info_files():
        with open(os.path.join(metadata_directory, info, name), "wb") as f:
            f.write(data)
    return info


prepare_metadata_for_build_editable = prepare_metadata_for_build_wheel


def build_wheel(wheel_directory, config_settings=None,
                metadata_directory=None):
    contents = []
    for rel, full in _package_files():
        with open(full, "rb") as f:
            contents.append((rel, f.read()))
    return _write_wheel(wheel_directory, contents)


def build_editable(wheel_directory, config_settings=None,
                   metadata_directory=None):
    # A .pth file puts this source tree on sys.path: edits to the package
    # take effect without reinstalling.
    pth = (ROOT + "\n").encode("utf-8")
    return _write_wheel(wheel_directory, [("_%s_editable.pth" % PACKAGE, pth)])


def build_sdist(sdist_directory, config_settings=None):
    p = _project()
    base = "%s-%s" % (_dist_name(p), p["version"])
    members = [("PKG-INFO", metadata_text().encode("utf-8"))]
    for rel in ("pyproject.toml", p.get("readme", "README.md")):
        with open(os.path.join(ROOT, rel), "rb") as f:
            members.append((rel, f.read()))
    for sub in ("_backend", PACKAGE, "tests"):
        for dirpath, dirnames, filenames in os.walk(os.path.join(ROOT, sub)):
            dirnames[:] = sorted(d for d in dirnames if d != "__pycache__")
            for name in sorted(filenames):
                if name.endswith(".pyc"):
                    continue
                full = os.path.join(dirpath, name)
                with open(full, "rb") as f:
                    members.append((os.path.relpath(full, ROOT), f.read()))
    filename = base + ".tar.gz"
    with tarfile.open(os.path.join(sdist_directory, filename), "w:gz",
                      format=tarfile.PAX_FORMAT) as tar:
        for rel, data in members:
            ti = tarfile.TarInfo(base + "/" + rel.replace(os.sep, "/"))
            ti.size = len(data)
            ti.mode = 0o644
            ti.mtime = 0
            tar.addfile(ti, io.BytesIO(data))
    return filename
