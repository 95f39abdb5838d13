"""The package as pip users get it: pip builds the wheel of the assembled project
($FREMEN_PYTHON_PROJECT, <build>/python: pyproject.toml, README.md and the fremen tree) with
setuptools, the wheel holds the generated fremen.v1 modules, their type stubs and py.typed, and once
installed into a fresh virtual environment (Debian's grpcio and protobuf seen through
--system-site-packages, nothing downloaded) a Python without the build tree on its path imports it
from there, reports the project's version, and talks to a real fremend."""

import glob
import json
import os
import shutil
import subprocess
import sys
import unittest
import zipfile

import fremen
from fremend_process import DaemonTestCase

# Run by the virtual environment's Python, outside the build tree: which fremen it imported, its
# versions, and a round trip with the daemon at argv[1].
SCRIPT = """
import importlib.metadata, json, sys
import fremen
with fremen.connect(sys.argv[1]) as client:
    made = client.create_map("installed", size=(4, 2), resolution=0.5)
    print(json.dumps({
        "file": fremen.__file__, "version": fremen.__version__,
        "metadata_version": importlib.metadata.version("fremen"),
        "server_version": client.server_status().version,
        "made": [type(made).__name__, made.name, made.kind, list(made.size)],
        "maps": [m.name for m in client.list_maps()],
    }))
"""
# pip must neither download (there is no index to reach) nor read the user's settings or cache.
PIP_OPTIONS = ["--no-index", "--no-build-isolation", "--no-cache-dir", "--disable-pip-version-check", "--isolated"]


def project_dir():
    project = os.environ.get("FREMEN_PYTHON_PROJECT")
    if not project:
        raise unittest.SkipTest("FREMEN_PYTHON_PROJECT is not set (ctest sets it to <build>/python)")
    return project


class PackageTest(DaemonTestCase):
    def run_checked(self, args, **kwargs):
        done = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, check=False,
                              **kwargs)
        self.assertEqual(done.returncode, 0, f"{' '.join(args)}:\n{done.stdout}")
        return done.stdout

    def test_pip_builds_a_wheel_that_installs_and_works(self):
        # A copy, so that setuptools' build/ and egg-info stay out of the build tree.
        source = self.path("project")
        shutil.copytree(project_dir(), source, ignore=shutil.ignore_patterns("__pycache__", "build", "*.egg-info"))
        venv = self.path("venv")
        self.run_checked([sys.executable, "-m", "venv", "--system-site-packages", venv])
        python = os.path.join(venv, "bin", "python")
        wheels = self.path("wheels")
        self.run_checked([python, "-m", "pip", "wheel", *PIP_OPTIONS, "--no-deps", "--wheel-dir", wheels, source])

        built = glob.glob(os.path.join(wheels, "fremen-*.whl"))
        self.assertEqual(len(built), 1, os.listdir(wheels))
        self.assertEqual(os.path.basename(built[0]), f"fremen-{fremen.__version__}-py3-none-any.whl")
        with zipfile.ZipFile(built[0]) as wheel:
            names = set(wheel.namelist())
        for expected in ("fremen/__init__.py", "fremen/_version.py", "fremen/py.typed", "fremen/v1/__init__.py",
                         "fremen/v1/maps_pb2.py", "fremen/v1/maps_pb2.pyi", "fremen/v1/maps_pb2_grpc.py",
                         "fremen/v1/admin_pb2_grpc.py"):
            self.assertIn(expected, names)
        self.assertFalse([n for n in names if n.endswith(".in") or "tests/" in n], names)

        # pip checks the dependencies (grpcio, protobuf) against what the environment has: Debian's.
        self.run_checked([python, "-m", "pip", "install", *PIP_OPTIONS, built[0]])
        environment = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
        out = self.run_checked([python, "-c", SCRIPT, self.daemon.address], cwd=self.path("."), env=environment)
        result = json.loads(out.splitlines()[-1])
        self.assertTrue(result["file"].startswith(os.path.realpath(venv) + os.sep) or
                        result["file"].startswith(venv + os.sep), result["file"])
        self.assertEqual(result["version"], fremen.__version__)
        self.assertEqual(result["metadata_version"], fremen.__version__)
        self.assertEqual(result["server_version"], fremen.__version__)  # the project's one version
        self.assertEqual(result["made"], ["MapInfo", "installed", "grid", [4, 2, 1]])
        self.assertEqual(result["maps"], ["installed"])


if __name__ == "__main__":
    unittest.main()
