#!/usr/bin/python3
"""The -march the objects are compiled with (README, "Configuration": FREMEN_MARCH).

  march_check.py tree BUILD_DIR
      Every compile command of BUILD_DIR (compile_commands.json) has exactly the -march its
      FREMEN_MARCH names, and none has -march=native unless FREMEN_MARCH is native: what a binary
      of this tree may need of a CPU is what its cache says.
  march_check.py default SOURCE_DIR CXX
      Configures SOURCE_DIR afresh, with no options, in a temporary directory (configure only,
      nothing is compiled) and checks that the default is portable: FREMEN_MARCH=x86-64-v2 on
      x86-64 and no compile command with -march=native.
Exit 0 when the check holds, 1 (with the offending commands named) otherwise.
"""

import json
import os
import platform
import shlex
import subprocess
import sys
import tempfile


def cached(build_dir, name):
    with open(os.path.join(build_dir, "CMakeCache.txt"), encoding="utf-8") as cache:
        for line in cache:
            key, _, value = line.rstrip("\n").partition("=")
            if key.split(":", 1)[0] == name:
                return value
    return None


def marches(build_dir):
    """{source file: [-march values]} of every compile command."""
    with open(os.path.join(build_dir, "compile_commands.json"), encoding="utf-8") as commands:
        entries = json.load(commands)
    return {e["file"]: [w[len("-march="):] for w in shlex.split(e["command"]) if w.startswith("-march=")]
            for e in entries}


def check(build_dir, want):
    """Failures (strings) unless every command has -march=want (want "": none at all)."""
    per_file = marches(build_dir)
    if not per_file:
        return [f"{build_dir}: compile_commands.json lists no command"]
    failures = []
    for source, found in sorted(per_file.items()):
        expected = [want] if want else []
        if found != expected:
            failures.append(f"{source}: -march={found} where FREMEN_MARCH says {expected}")
        elif want != "native" and "native" in found:
            failures.append(f"{source}: -march=native")
    print(f"{build_dir}: {len(per_file)} compile commands, -march={want or '(none)'}: "
          f"{len(failures)} differ")
    return failures


def check_tree(build_dir):
    march = cached(build_dir, "FREMEN_MARCH")
    if march is None:
        return [f"{build_dir}: no FREMEN_MARCH in CMakeCache.txt"]
    return check(build_dir, march)


def check_default(source_dir, cxx):
    with tempfile.TemporaryDirectory(prefix="fremen-march-") as build_dir:
        configure = subprocess.run(
            ["cmake", "-S", source_dir, "-B", build_dir, f"-DCMAKE_CXX_COMPILER={cxx}"],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, check=False)
        if configure.returncode != 0:
            return [f"a fresh configure failed:\n{configure.stdout}"]
        march = cached(build_dir, "FREMEN_MARCH")
        want = "x86-64-v2" if platform.machine() in ("x86_64", "AMD64") else ""
        if march != want:
            return [f"a fresh tree's FREMEN_MARCH is {march!r}, not the portable {want!r}"]
        return check(build_dir, want)


def main(argv):
    if len(argv) == 3 and argv[1] == "tree":
        failures = check_tree(argv[2])
    elif len(argv) == 4 and argv[1] == "default":
        failures = check_default(argv[2], argv[3])
    else:
        print(__doc__, file=sys.stderr)
        return 2
    for failure in failures[:20]:
        print(failure)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
