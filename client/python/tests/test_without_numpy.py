"""The package without numpy: a Python in which `import numpy` fails imports fremen, and predict
and region answer fremen.FlatArray values equal to what a numpy client gets."""

import json
import subprocess
import sys
import unittest

from fremend_process import DaemonTestCase

T = 1.7e9

# Run in a fresh interpreter: numpy made unimportable before fremen is imported.
SCRIPT = """
import json, sys
sys.modules["numpy"] = None
import fremen
assert not fremen.arrays.numpy_available()
client = fremen.connect(sys.argv[1])
region = client.region("lab", (0, 0), (4, 3), %r)
prediction = client.predict("lab", [%r], cells=[(0, 0), (3, 2)], confidence=0.5)
print(json.dumps({"types": [type(region).__name__, type(prediction.probabilities).__name__],
                  "region": region.tolist(), "shape": region.shape, "states": prediction.states.tolist(),
                  "probabilities": prediction.probabilities.tolist()}))
""" % (T, T)


class WithoutNumpyTest(DaemonTestCase):
    def test_flat_arrays_equal_numpy_arrays(self):
        self.client.create_map("lab", size=(4, 3), resolution=1.0)
        with self.client.ingest("lab") as session:
            session.send(T, [1, 0], cells=[(0, 0), (3, 2)])
        run = subprocess.run([sys.executable, "-c", SCRIPT, self.daemon.address], capture_output=True, text=True,
                             timeout=60, check=False)
        self.assertEqual(run.returncode, 0, run.stderr)
        answer = json.loads(run.stdout)
        self.assertEqual(answer["types"], ["FlatArray", "FlatArray"])
        self.assertEqual(answer["shape"], [3, 4])
        self.assertEqual(answer["region"], self.client.region("lab", (0, 0), (4, 3), T).tolist())
        self.assertEqual(answer["region"][0][0], 1.0)
        self.assertEqual(answer["probabilities"], [[1.0, 0.0]])
        self.assertEqual(answer["states"], [[True, False]])


if __name__ == "__main__":
    unittest.main()
