#!/usr/bin/python3
"""The test suites ctest must hold, and what each of them ran.

A test's suite is its name up to the first dot ("storage.WalTest.Replay" -> "storage"). Every
suite the project has is listed in tests/expected_suites.txt with the fewest tests it may
register; a build that registers fewer (a CMakeLists.txt that lost an add_subdirectory, a
gtest_discover_tests that went missing) or a test of a suite nobody listed fails the check.

  test_suites.py check BUILD_DIR EXPECTED_FILE
      Lists the tests ctest knows in BUILD_DIR (ctest --show-only=json-v1) and compares them with
      EXPECTED_FILE. Exit 0 when every suite is there with at least its minimum, 1 otherwise.
  test_suites.py summary JUNIT_FILE [EXPECTED_FILE]
      Prints, per suite, how many tests ran, passed, failed and were skipped, from the JUnit file
      that `ctest --output-junit` wrote; with EXPECTED_FILE also the suites that ran nothing.
      Its last line is "suites: N passed, M failed[, K skipped]".
"""

import collections
import json
import subprocess
import sys
import xml.etree.ElementTree as ElementTree


def suite_of(test_name):
    return test_name.split(".", 1)[0]


def read_expected(path):
    """{suite: minimum} from lines "suite minimum  # comment"."""
    expected = {}
    with open(path, encoding="utf-8") as lines:
        for number, line in enumerate(lines, 1):
            words = line.split("#", 1)[0].split()
            if not words:
                continue
            if len(words) != 2 or not words[1].isdigit():
                raise SystemExit(f"{path}:{number}: expected 'suite minimum', got {line.strip()!r}")
            expected[words[0]] = int(words[1])
    return expected


def registered_tests(build_dir):
    listing = subprocess.run(["ctest", "--show-only=json-v1"], cwd=build_dir, check=True,
                             capture_output=True, text=True).stdout
    return [test["name"] for test in json.loads(listing)["tests"]]


def check(build_dir, expected_path):
    expected = read_expected(expected_path)
    counts = collections.Counter(suite_of(name) for name in registered_tests(build_dir))
    problems = []
    for suite, minimum in expected.items():
        if counts[suite] < minimum:
            problems.append(f"suite {suite}: {counts[suite]} tests registered, expected at least {minimum}")
    for suite in sorted(set(counts) - set(expected)):
        problems.append(f"suite {suite}: {counts[suite]} tests registered but not listed in {expected_path}")
    for suite in sorted(expected):
        print(f"{suite:12} {counts[suite]:5} registered (minimum {expected[suite]})")
    for problem in problems:
        print(f"FAIL: {problem}")
    return 1 if problems else 0


def summary(junit_path, expected_path=None):
    tally = collections.defaultdict(collections.Counter)
    for case in ElementTree.parse(junit_path).getroot().iter("testcase"):
        outcome = case.get("status", "run")
        if case.find("failure") is not None or case.find("error") is not None or outcome == "fail":
            outcome = "failed"
        elif case.find("skipped") is not None or outcome in ("disabled", "notrun"):
            outcome = "skipped"
        else:
            outcome = "passed"
        tally[suite_of(case.get("name", ""))][outcome] += 1
    suites = set(tally)
    if expected_path:
        suites |= set(read_expected(expected_path))
    print(f"{'suite':12} {'ran':>5} {'passed':>7} {'failed':>7} {'skipped':>8}")
    totals = collections.Counter()
    for suite in sorted(suites):
        counts = tally[suite]
        ran = counts["passed"] + counts["failed"]
        note = "   <- ran no test" if ran == 0 else ""
        print(f"{suite:12} {ran:5} {counts['passed']:7} {counts['failed']:7} {counts['skipped']:8}{note}")
        totals.update(counts)
    line = f"suites: {totals['passed']} passed, {totals['failed']} failed"
    if totals["skipped"]:
        line += f", {totals['skipped']} skipped"
    print(line)
    return 0


def main(argv):
    if len(argv) == 4 and argv[1] == "check":
        return check(argv[2], argv[3])
    if len(argv) in (3, 4) and argv[1] == "summary":
        return summary(*argv[2:])
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
