"""Tests of test_suites.py against the real build tree's ctest listing and a JUnit file."""

import contextlib
import io
import os
import tempfile
import unittest

import test_suites

BUILD_DIR = os.environ["FREMEN_BUILD_DIR"]


def write(directory, name, text):
    path = os.path.join(directory, name)
    with open(path, "w", encoding="utf-8") as out:
        out.write(text)
    return path


def run(function, *args):
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = function(*args)
    return code, printed.getvalue()


class CheckTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp()
        self.registered = {test_suites.suite_of(n) for n in test_suites.registered_tests(BUILD_DIR)}

    def expected_with(self, extra):
        lines = [f"{suite} 1" for suite in sorted(self.registered)] + extra
        return write(self.dir, "expected.txt", "\n".join(lines) + "\n")

    def test_every_registered_suite_at_minimum_one_passes(self):
        code, printed = run(test_suites.check, BUILD_DIR, self.expected_with([]))
        self.assertEqual(code, 0, printed)

    def test_a_missing_suite_fails_and_is_named(self):
        code, printed = run(test_suites.check, BUILD_DIR, self.expected_with(["nosuchsuite 1"]))
        self.assertEqual(code, 1)
        self.assertIn("suite nosuchsuite: 0 tests registered, expected at least 1", printed)

    def test_a_suite_below_its_minimum_fails(self):
        expected = write(self.dir, "expected.txt",
                         "\n".join(f"{s} {10**6 if s == 'meta' else 1}" for s in sorted(self.registered)))
        code, printed = run(test_suites.check, BUILD_DIR, expected)
        self.assertEqual(code, 1)
        self.assertIn("suite meta:", printed)
        self.assertIn("expected at least 1000000", printed)

    def test_an_unlisted_suite_fails(self):
        expected = write(self.dir, "expected.txt",
                         "\n".join(f"{s} 1" for s in sorted(self.registered) if s != "meta"))
        code, printed = run(test_suites.check, BUILD_DIR, expected)
        self.assertEqual(code, 1)
        self.assertIn("suite meta:", printed)
        self.assertIn("not listed", printed)

    def test_a_malformed_expected_line_is_refused_with_its_line_number(self):
        expected = write(self.dir, "expected.txt", "model 3\nstorage many\n")
        with self.assertRaises(SystemExit) as refused:
            test_suites.read_expected(expected)
        self.assertIn("expected.txt:2", str(refused.exception))


class SummaryTest(unittest.TestCase):
    def test_counts_per_suite_and_the_closing_line(self):
        directory = tempfile.mkdtemp()
        junit = write(directory, "junit.xml", """<?xml version="1.0" encoding="UTF-8"?>
<testsuite name="fremen" tests="4" failures="1" disabled="1">
  <testcase name="storage.A.b" classname="storage.A.b" status="run"/>
  <testcase name="storage.A.c" classname="storage.A.c" status="fail"><failure message="x"/></testcase>
  <testcase name="python.test_maps" classname="python.test_maps" status="run"/>
  <testcase name="model.X.y" classname="model.X.y" status="disabled"><skipped message="off"/></testcase>
</testsuite>
""")
        expected = write(directory, "expected.txt", "storage 2\npython 1\nmodel 1\ne2e 1\n")
        code, printed = run(test_suites.summary, junit, expected)
        self.assertEqual(code, 0)
        lines = printed.splitlines()
        self.assertEqual(lines[-1], "suites: 2 passed, 1 failed, 1 skipped")
        storage = next(line for line in lines if line.startswith("storage"))
        self.assertEqual(storage.split(), ["storage", "2", "1", "1", "0"])
        e2e = next(line for line in lines if line.startswith("e2e"))
        self.assertIn("ran no test", e2e)


if __name__ == "__main__":
    unittest.main()
