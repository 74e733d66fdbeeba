"""Hold the Python package's protocol tables against the C schema.

Usage: check_schema.py SCHEMA_DUMP CLIENT_PY

SCHEMA_DUMP is the schema_dump program (the schema of include/wsg/schema.h
as JSON); CLIENT_PY is python/wsgemu/client.py, loaded by its path alone so
nothing is installed and no bytecode is written into the source tree. Every
difference is listed (command IDs, status codes, system flag names and
bits, the finger flags of 61h and 71h, grasping states, the motion
commands, the device types of 50h and the fields of 42h), and any makes
the exit status 1.
"""

import importlib.util
import json
import subprocess
import sys


def load_client(path):
    sys.dont_write_bytecode = True
    spec = importlib.util.spec_from_file_location("wsgemu_client", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def compare(what, python, schema, problems):
    if python == schema:
        print("ok: %s (%d)" % (what, len(schema)))
        return
    for key in sorted(set(python) | set(schema), key=str):
        p, s = python.get(key), schema.get(key)
        if p != s:
            problems.append("%s %s: Python %r, schema %r" % (what, key, p, s))


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    schema = json.loads(subprocess.check_output([argv[1]]))
    client = load_client(argv[2])
    commands = {c["symbol"]: c for c in schema["commands"]}
    problems = []

    compare("command", {m.name: m.value for m in client.Cmd},
            {s: c["id"] for s, c in commands.items()}, problems)
    compare("status", {m.name: m.value for m in client.Status},
            schema["statuses"], problems)
    compare("system flag", {m.name: m.value for m in client.SystemFlag},
            {n: 1 << bit for n, bit in schema["system_flags"].items()},
            problems)
    flags = commands["GET_FINGER1_FLAGS"]["reply"][0]
    compare("finger flag", {m.name: m.value for m in client.FingerFlag},
            {n.upper(): 1 << bit for bit, n in enumerate(flags["names"])
             if n}, problems)
    compare("finger flag (71h)", {0: flags},
            {0: commands["GET_FINGER2_FLAGS"]["reply"][0]}, problems)
    compare("grasping state", {m.name: m.value for m in client.GraspState},
            schema["grasp_states"], problems)
    compare("motion command",
            {int(m): True for m in client.MOTION_COMMANDS},
            {c["id"]: True for c in commands.values()
             if "async" in c["flags"]}, problems)
    info = {f["name"]: f for f in commands["GET_SYSTEM_INFO"]["reply"]}
    compare("device type", client._DEVICE_TYPES,
            dict(enumerate(info["type"]["names"])), problems)
    compare("grasping statistics field",
            dict(enumerate(client.GraspStats._fields)),
            dict(enumerate(f["name"].replace("-", "_")
                           for f in commands["GET_GRASP_STATS"]["reply"])),
            problems)
    for p in problems:
        print("differs: " + p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
