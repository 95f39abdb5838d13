"""fremen.FlatArray, the numpy stand-in (no daemon needed): indexing and nesting in C order, as a
numpy array of the same shape does."""

import unittest

import fremen
from fremen import arrays


class FlatArrayTest(unittest.TestCase):
    def test_indexing_is_c_order(self):
        a = fremen.FlatArray(list(range(24)), (2, 3, 4))
        self.assertEqual(a[0, 0, 0], 0)
        self.assertEqual(a[0, 0, 3], 3)
        self.assertEqual(a[0, 2, 0], 8)
        self.assertEqual(a[1, 0, 0], 12)
        self.assertEqual(a[-1, -1, -1], 23)
        self.assertEqual(len(a), 2)

    def test_tolist_nests_like_numpy(self):
        a = fremen.FlatArray([1, 2, 3, 4, 5, 6], (2, 3))
        self.assertEqual(a.tolist(), [[1, 2, 3], [4, 5, 6]])
        if arrays.numpy_available():
            self.assertEqual(arrays.shaped([1, 2, 3, 4, 5, 6], (2, 3), "float32", True).tolist(), a.tolist())

    def test_bad_shapes_and_indices_are_refused(self):
        with self.assertRaises(ValueError):
            fremen.FlatArray([1, 2, 3], (2, 2))
        a = fremen.FlatArray([1, 2, 3, 4], (2, 2))
        with self.assertRaises(IndexError):
            a[2, 0]
        with self.assertRaises(IndexError):
            a[0]

    def test_bytes_without_numpy(self):
        flat = arrays.shaped_bytes(b"\x00\x01\x02\x03\x04\x05", (3, 2), False)
        self.assertEqual(flat.tolist(), [[0, 1], [2, 3], [4, 5]])


if __name__ == "__main__":
    unittest.main()
