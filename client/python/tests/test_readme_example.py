"""Runs the example of client/python/README.md (FREMEN_PYTHON_README) against a real fremend, so
that the documented usage keeps working."""

import contextlib
import io
import os
import re
import unittest

from fremend_process import DaemonTestCase

README = os.environ.get("FREMEN_PYTHON_README", os.path.join(os.path.dirname(__file__), "..", "README.md"))


def example_code():
    """The first ```python block after the "## Example" heading."""
    with open(README) as readme:
        text = readme.read()
    match = re.search(r"^## Example\n.*?^```python\n(.*?)^```", text, re.S | re.M)
    if match is None:
        raise AssertionError(f"{README} has no ```python block under '## Example'")
    return match.group(1)


class ReadmeExampleTest(DaemonTestCase):
    def test_the_example_runs_and_says_what_it_promises(self):
        code = example_code()
        self.assertIn('"127.0.0.1:50051"', code)
        code = code.replace('"127.0.0.1:50051"', repr(self.daemon.address))
        output = io.StringIO()
        with contextlib.redirect_stdout(output):
            exec(compile(code, README, "exec"), {"__name__": "readme_example"})
        lines = output.getvalue().splitlines()
        self.assertEqual(lines[:2], ["acknowledged: 168", "acknowledged: 168"])
        door = re.fullmatch(r"kitchen door open: ([\d.]+) at noon, ([\d.]+) at midnight", lines[2])
        self.assertIsNotNone(door, lines[2])
        self.assertGreater(float(door.group(1)), 0.7)
        self.assertLess(float(door.group(2)), 0.3)
        self.assertEqual(lines[3], "region: (30, 40) 1.0")
        self.assertEqual(lines[4], "strongest period: 24.0 h")


if __name__ == "__main__":
    unittest.main()
