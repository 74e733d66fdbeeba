"""The examples of python/README.md run as written (the daemon's path put
in), so the package's documentation cannot drift from what it does."""

import os
import re

README = os.path.join(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))), "README.md")


def _blocks(lang):
    with open(README, encoding="utf-8") as f:
        text = f.read()
    return re.findall(r"```%s\n(.*?)```" % lang, text, re.S)


def test_client_example(wsgemu_binary, capsys):
    [code] = [b for b in _blocks("python") if "with Emulator(" in b]
    code = code.replace('"build/wsgemu"', repr(wsgemu_binary))
    exec(compile(code, README, "exec"), {})
    out = capsys.readouterr().out.split("\n")
    # What the block says it prints, as it says it ("#  " lines).
    shown = [ln[3:] for ln in code.split("\n") if ln.startswith("#  ")]
    assert shown == ["E_NOT_INITIALIZED", "39.2 mm, squeezed with 40 N"]
    assert out[:2] == shown


def test_fixture_examples(pytester, wsgemu_binary):
    [code] = [b for b in _blocks("python")
              if "(wsgemu)" in b and "wsgemu_script" not in b]
    [ini] = _blocks("ini")
    pytester.makepyfile(test_readme_example=code)
    # The block's first line is "# pytest.ini".
    pytester.makefile(".ini", pytest=ini.split("\n", 1)[1])
    result = pytester.runpytest("-p", "no:cacheprovider",
                                "--wsgemu=" + wsgemu_binary)
    result.assert_outcomes(passed=code.count("\ndef test_"))
    assert code.count("\ndef test_") == 3


def test_script_example(pytester, wsgemu_binary):
    [code] = [b for b in _blocks("python") if "wsgemu_script" in b]
    [lua] = _blocks("lua")
    # The block's first line names the script's file.
    name = lua.split("\n", 1)[0].split()[1].rstrip(":")
    assert name == "scripts/echo.lua"
    (pytester.path / "scripts").mkdir()
    (pytester.path / name).write_text(lua)
    pytester.makepyfile(test_readme_script=code)
    result = pytester.runpytest("-p", "no:cacheprovider",
                                "--wsgemu=" + wsgemu_binary)
    result.assert_outcomes(passed=1)
