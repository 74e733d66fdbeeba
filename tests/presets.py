#!/usr/bin/env python3
"""presets.py: CMakePresets.json names the builds the scripts make, the same
way: `cmake --list-presets` reads it (release, asan, static), and each
preset's directory and settings are the ones scripts/test.sh (build,
build-asan and its sanitizer options) and scripts/container.sh
(build-static) pass to cmake, so that `cmake --preset X` and the scripts
make the same tree.

Usage: presets.py CMAKE SOURCE_DIR. Exit status 0 passed, 1 a check failed.
"""
import json
import re
import subprocess
import sys


def main():
    cmake, src = sys.argv[1], sys.argv[2]
    failures = []

    def check(ok, what):
        print(("ok   " if ok else "FAIL ") + what)
        if not ok:
            failures.append(what)

    out = subprocess.run([cmake, "--list-presets=all"], cwd=src,
                         capture_output=True, text=True)
    check(out.returncode == 0, "cmake --list-presets=all: status 0")
    for name in ("release", "asan", "static"):
        check(f'"{name}"' in out.stdout, f"cmake lists the preset {name}")

    with open(f"{src}/CMakePresets.json") as f:
        presets = json.load(f)
    conf = {p["name"]: p for p in presets["configurePresets"]}
    tests = {p["name"]: p for p in presets.get("testPresets", [])}

    def dir_of(name):
        return conf[name]["binaryDir"].replace("${sourceDir}/", "")

    def cache(name):
        return conf[name].get("cacheVariables", {})

    def script_defs(text):
        return dict(re.findall(r"-D(\w+)=(\S+)", text))

    with open(f"{src}/scripts/test.sh") as f:
        test_sh = f.read()
    # "run NAME DIR -DX=Y ...": the two builds the presets stand for.
    runs = {m.group(1): (m.group(2), script_defs(m.group(3)))
            for m in re.finditer(r"^run (\w+) (\S+)(.*)$", test_sh, re.M)}
    for preset, run in (("release", "normal"), ("asan", "sanitizers")):
        d, defs = runs.get(run, (None, {}))
        check(d == dir_of(preset),
              f"{preset}: directory {dir_of(preset)}, as test.sh's {run} ({d})")
        for k, v in defs.items():
            check(cache(preset).get(k) == v,
                  f"{preset}: {k}={v}, as test.sh's {run}")
    # The sanitizers' options test.sh exports, in the asan test preset.
    env = tests.get("asan", {}).get("environment", {})
    for k, v in re.findall(r"^export (\w+SAN_OPTIONS)=(\S+)$", test_sh, re.M):
        check(env.get(k) == v, f"asan test preset: {k}={v}, as test.sh")

    with open(f"{src}/scripts/container.sh") as f:
        container_sh = f.read()
    m = re.search(r'^BUILD=\$SRC/(\S+)$', container_sh, re.M)
    check(m is not None and m.group(1) == dir_of("static"),
          f"static: directory {dir_of('static')}, as container.sh's")
    m = re.search(r'cmake -S "\$SRC" -B "\$BUILD"(.*?)>', container_sh, re.S)
    defs = script_defs(m.group(1)) if m else {}
    check(bool(defs), "container.sh configures with -D settings")
    for k, v in defs.items():
        check(cache("static").get(k) == v, f"static: {k}={v}, as container.sh")

    print(f"presets: {len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
