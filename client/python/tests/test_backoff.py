"""fremen.Backoff and retrying(), the reconnect policy of connect(): pauses that grow by the
multiplier up to the maximum, shortened by at most the jitter, bounded in tries and in time, and
settings refused with the field named. Pure computation (a fake clock and fake draws), so no
daemon; test_reconnect.py runs the policy against a real fremend."""

import unittest

import grpc

import fremen
from fremen import retry


class FakeClock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now

    def sleep(self, seconds):
        self.now += seconds


class BackoffTest(unittest.TestCase):
    def test_delays_grow_by_the_multiplier_up_to_the_maximum(self):
        backoff = fremen.Backoff(initial=0.1, multiplier=2, maximum=1.0, jitter=0.5)
        no_jitter = [backoff.delay(n, draw=lambda: 0.0) for n in range(1, 7)]
        self.assertEqual(no_jitter, [0.1, 0.2, 0.4, 0.8, 1.0, 1.0])

    def test_jitter_shortens_a_delay_by_at_most_its_fraction(self):
        backoff = fremen.Backoff(initial=1.0, multiplier=1, maximum=1.0, jitter=0.25)
        self.assertEqual(backoff.delay(3, draw=lambda: 0.5), 0.875)
        drawn = [backoff.delay(1) for _ in range(200)]
        self.assertTrue(all(0.75 <= d <= 1.0 for d in drawn))
        self.assertGreater(len(set(drawn)), 100)  # random: robots do not come back in step

    def test_pauses_stop_after_max_attempts(self):
        backoff = fremen.Backoff(initial=0.1, max_attempts=4, max_elapsed=1e9, jitter=0)
        self.assertEqual(list(backoff.pauses()), [0.1, 0.2, 0.4])  # 3 retries after the first try
        self.assertEqual(list(fremen.Backoff(max_attempts=1).pauses()), [])

    def test_pauses_stop_before_max_elapsed(self):
        clock = FakeClock()
        backoff = fremen.Backoff(initial=1.0, multiplier=2, maximum=100, jitter=0, max_attempts=100, max_elapsed=10)
        taken = []
        for pause in backoff.pauses(clock=clock):
            taken.append(pause)
            clock.sleep(pause)
        self.assertEqual(taken, [1, 2, 4])  # the next one (8) would end at 15 s > 10 s

    def test_bad_settings_name_the_field(self):
        for field, value in [("initial", 0), ("multiplier", 0.5), ("maximum", 0.01), ("jitter", 1.5),
                             ("max_attempts", 0), ("max_attempts", 2.5), ("max_elapsed", -1)]:
            with self.assertRaises(fremen.InvalidArgument, msg=field) as raised:
                fremen.Backoff(**{field: value})
            self.assertIn(f"Backoff.{field}", raised.exception.message)
        with self.assertRaises(fremen.InvalidArgument) as raised:
            fremen.connect("127.0.0.1:1", reconnect=3)
        self.assertIn("reconnect", raised.exception.message)

    def test_channel_options_follow_the_backoff(self):
        options = dict(fremen.Backoff(initial=0.25, maximum=4).channel_options())
        self.assertEqual(options["grpc.initial_reconnect_backoff_ms"], 250)
        self.assertEqual(options["grpc.max_reconnect_backoff_ms"], 4000)


class RetryingTest(unittest.TestCase):
    def setUp(self):
        self.tries = 0
        self.slept = []

    def failing(self, times, error=None):
        def attempt():
            self.tries += 1
            if self.tries <= times:
                raise error or fremen.Unavailable(grpc.StatusCode.UNAVAILABLE, f"try {self.tries}")
            return "answer"
        return attempt

    def test_unavailable_is_retried_until_it_succeeds(self):
        backoff = fremen.Backoff(initial=0.1, jitter=0)
        self.assertEqual(retry.retrying(backoff, self.failing(3), sleep=self.slept.append), "answer")
        self.assertEqual(self.tries, 4)
        self.assertEqual(self.slept, [0.1, 0.2, 0.4])

    def test_the_last_unavailable_is_raised_at_the_bound(self):
        backoff = fremen.Backoff(initial=0.1, jitter=0, max_attempts=3)
        with self.assertRaises(fremen.Unavailable) as raised:
            retry.retrying(backoff, self.failing(10), sleep=self.slept.append)
        self.assertEqual(raised.exception.message, "try 3")
        self.assertEqual(self.tries, 3)

    def test_other_errors_and_no_backoff_are_not_retried(self):
        with self.assertRaises(fremen.NotFound):
            retry.retrying(fremen.Backoff(), self.failing(1, fremen.NotFound(grpc.StatusCode.NOT_FOUND, "x")),
                           sleep=self.slept.append)
        self.assertEqual(self.tries, 1)
        with self.assertRaises(fremen.Unavailable):
            retry.retrying(None, self.failing(2), sleep=self.slept.append)
        self.assertEqual(self.tries, 2)
        self.assertEqual(self.slept, [])


if __name__ == "__main__":
    unittest.main()
