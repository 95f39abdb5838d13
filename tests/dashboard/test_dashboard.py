"""The dashboard in a real browser (ctest e2e.dashboard_browser): Debian's chromium, headless,
driven by python3-selenium through chromium-driver, against a real fremend with read and write
tokens, fed `fremenctl demo` (a simulated week of an office: walls, free floor, a door with a
daily schedule, and a generic map of three named states).

What a person would check by looking, checked on the page itself:
- the overview asks for a token, then lists both demo maps with their figures;
- the grid's canvas pixels are 255·(1 − p) of the JSON region (GET /v1/maps/{map}/region, fetched
  here with urllib): walls dark, free floor light;
- moving the time slider from 03:00 to 09:00 changes the doorway cells (the door is shut at night);
- clicking the door cell opens its model and draws its week of p(t) (the chart has points and its
  line is on the canvas); on a lossless map the model's chart also holds the observed states;
- the generic map lists its states with p now and at t;
- "run the update now" with a read token asks for the write token, then shows a done operation.
A screenshot of each view is written to $FREMEN_ARTIFACTS_DIR (build/test-artifacts/dashboard/).
No JavaScript error may reach the console (refused API calls, 401/403, are expected and allowed).

Environment (set by tests/CMakeLists.txt): FREMEND_BINARY, FREMENCTL_BINARY, FREMEN_ARTIFACTS_DIR,
PYTHONPATH with build/python (the fremen package) and client/python/tests (its daemon harness).
"""

import base64
import json
import os
import re
import subprocess
import tempfile
import unittest
import urllib.parse
import urllib.request

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select, WebDriverWait

from fremend_process import FremendProcess

READ_TOKEN = "reader-token"
WRITE_TOKEN = "writer-token"
# Monday 27 November 2023, 00:00 UTC: the day after the demo's simulated week.
MONDAY = 1701043200
STEP = 15 * 60
DOORWAY = [(20, 9), (20, 10)]
WAIT_SECONDS = 60
# The lossless map "lab": a door open 08:00-18:00 every day of the week before MONDAY, seen every
# 10 minutes (one observation per lossless slot).
LAB_SAMPLING = 600
LAB_TIMES = range(MONDAY - 7 * 86400, MONDAY, LAB_SAMPLING)


def lab_door(t):
    return 1 if 8 <= (t % 86400) / 3600 < 18 else 0


_HTTP = re.compile(r"serving HTTP on (\S+) ")
# Chromium logs every refused fetch; those the dashboard answers with its token prompt are expected.
_EXPECTED_CONSOLE = re.compile(r"Failed to load resource: the server responded with a status of 40[13]")


class DashboardBrowserTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory(prefix="fremen_dashboard.")
        tokens = os.path.join(cls.dir.name, "tokens")
        with open(tokens, "w") as out:
            out.write(f"read:{READ_TOKEN}\nwrite:{WRITE_TOKEN}\n")
        cls.daemon = FremendProcess.start(os.path.join(cls.dir.name, "data"), ["--tokens-file", tokens])
        try:
            cls.base = "http://" + _HTTP.search(cls.daemon.log()).group(1)
            cls.fremenctl("demo")
            # A lossless map: the model view draws its observations (Reconstruct) over p(t).
            door = os.path.join(cls.dir.name, "door.txt")
            with open(door, "w") as out:
                out.writelines(f"{t} {lab_door(t)}\n" for t in LAB_TIMES)
            cls.fremenctl("maps", "create", "lab", "--generic", "--lossless-sampling", str(LAB_SAMPLING))
            cls.fremenctl("ingest", "--map", "lab", "--states", door, "--name", "door", "--update")
            # A map the overview watches while observations arrive (its live ingest rate).
            cls.fremenctl("maps", "create", "feed", "--generic")
            cls.artifacts = os.environ.get("FREMEN_ARTIFACTS_DIR", os.path.join(cls.dir.name, "artifacts"))
            os.makedirs(cls.artifacts, exist_ok=True)
            options = webdriver.ChromeOptions()
            options.binary_location = "/usr/bin/chromium"
            for argument in ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                             "--window-size=1280,1000", "--force-device-scale-factor=1"]:
                options.add_argument(argument)
            options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
            cls.browser = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
        except BaseException:
            cls.daemon.kill()
            cls.dir.cleanup()
            raise

    @classmethod
    def fremenctl(cls, *args):
        subprocess.run([os.environ["FREMENCTL_BINARY"], "--address", cls.daemon.address, "--token", WRITE_TOKEN, *args],
                       check=True, stdout=subprocess.DEVNULL, timeout=240)

    @classmethod
    def tearDownClass(cls):
        cls.browser.quit()
        code = cls.daemon.stop()
        log = cls.daemon.log()
        cls.dir.cleanup()
        if code != 0:
            raise AssertionError(f"fremend exited with {code}:\n{log}")

    def tearDown(self):
        errors = [entry["message"] for entry in self.browser.get_log("browser")
                  if entry["level"] == "SEVERE" and not _EXPECTED_CONSOLE.search(entry["message"])]
        self.assertEqual(errors, [], "errors in the browser's console")

    # --- helpers ---

    def api(self, path, query=None, body=None):
        """fremend's JSON API with the read token, as the page calls it."""
        url = self.base + path + ("?" + urllib.parse.urlencode(query, doseq=True) if query else "")
        request = urllib.request.Request(url, headers={"Authorization": "Bearer " + READ_TOKEN})
        if body is not None:
            request.data = json.dumps(body).encode()
            request.add_header("Content-Type", "application/json")
        with urllib.request.urlopen(request, timeout=30) as response:
            return json.load(response)

    def open(self, route, token=READ_TOKEN):
        """Loads the dashboard at #route in a fresh page, with `token` in the tab's sessionStorage."""
        self.browser.get(self.base + "/static/style.css")  # the origin, to set its storage
        if token:
            self.browser.execute_script("sessionStorage.setItem('fremen.token', arguments[0])", token)
        else:
            self.browser.execute_script("sessionStorage.clear()")
        self.browser.get(self.base + "/#" + route)

    def wait(self, condition, message):
        return WebDriverWait(self.browser, WAIT_SECONDS).until(lambda _: condition(), message)

    def js(self, script, *args):
        return self.browser.execute_script(script, *args)

    def wait_ready(self):
        self.wait(lambda: self.js("return document.getElementById('view').dataset.ready") == "true"
                  or self.banner(), "the view did not finish rendering")
        self.assertEqual(self.banner(), "", "the page shows an error")

    def banner(self):
        return self.js("const b = document.getElementById('error-banner'); return b.hidden ? '' : b.textContent")

    def screenshot(self, name, height=None):
        """The view as a PNG in the artifacts; with `height`, of a window that much high (no empty
        space below a short page)."""
        size = self.browser.get_window_size()
        if height:
            self.browser.set_window_size(size["width"], height)
        self.browser.save_screenshot(os.path.join(self.artifacts, name + ".png"))
        if height:
            self.browser.set_window_size(size["width"], size["height"])

    def set_slider(self, steps):
        """Moves the time slider as a user's drag does (an input event), and waits for that time's map."""
        self.js("const s = document.getElementById('time-slider'); s.value = arguments[0];"
                "s.dispatchEvent(new Event('input'))", steps)
        time = MONDAY + steps * STEP
        self.wait(lambda: self.js("return document.getElementById('grid-canvas').dataset.time") == str(time),
                  f"the canvas never showed time {time}")
        return time

    def cell_pixel(self, x, y):
        """Canvas coordinates of cell (x, y)'s center, as the canvas says it places the grid."""
        d = self.js("return Object.assign({}, document.getElementById('grid-canvas').dataset)")
        scale = float(d["scale"])
        return (float(d["offsetX"]) + (x + 0.5) * scale, float(d["offsetY"]) + (int(d["height"]) - 1 - y + 0.5) * scale)

    def grays(self):
        """The gray of every cell's center on the canvas, {(x, y): gray}; None for cells off it."""
        d = self.js("return Object.assign({}, document.getElementById('grid-canvas').dataset)")
        width, height = int(d["width"]), int(d["height"])
        centers = [[x, y, *self.cell_pixel(x, y)] for y in range(height) for x in range(width)]
        values = self.js("""
            const c = document.getElementById('grid-canvas'), g = c.getContext('2d');
            return arguments[0].map(([x, y, px, py]) => {
              if (px < 0 || py < 0 || px >= c.width || py >= c.height) return [x, y, null, null, null];
              const p = g.getImageData(Math.floor(px), Math.floor(py), 1, 1).data;
              return [x, y, p[0], p[1], p[2]];
            });""", centers)
        for x, y, r, g, b in values:
            self.assertTrue(r == g == b, f"cell ({x}, {y}) is not gray: {r}, {g}, {b}")
        return {(x, y): r for x, y, r, _, _ in values}

    def region(self, time):
        box = {"lo.x": 0, "lo.y": 0, "hi.x": 40, "hi.y": 20}
        answer = self.api("/v1/maps/demo-office/region", {**box, "time": time, "output": "REGION_OUTPUT_FLOAT"})
        values = answer["floatValues"]
        self.assertEqual(len(values), 40 * 20)
        return {(i % 40, i // 40): float(p) for i, p in enumerate(values)}

    # --- the views ---

    def test_overview_asks_for_a_token_then_lists_the_maps(self):
        self.open("/", token=None)
        self.wait(lambda: self.js("return document.getElementById('token-dialog').open"), "no token prompt")
        self.assertIn("token", self.browser.find_element(By.ID, "token-reason").text)
        self.browser.find_element(By.ID, "token-input").send_keys(READ_TOKEN)
        self.browser.find_element(By.ID, "token-save").click()
        self.wait_ready()
        office = self.browser.find_element(By.CSS_SELECTOR, "#maps-table tr[data-map='demo-office']").text
        self.assertIn("grid", office)
        self.assertIn("40 × 20 cells of 0.25 m", office)
        self.assertIn("806,400", office)  # the demo's observations
        states = self.browser.find_element(By.CSS_SELECTOR, "#maps-table tr[data-map='demo-states']").text
        self.assertIn("generic", states)
        self.assertIn("3,024", states)
        self.assertIn("fremend", self.browser.find_element(By.ID, "server-line").text)
        # Observations arriving show as a rate (the change of the count between two refreshes).
        rate = "#maps-table tr[data-map='feed'] td[data-column='rate']"
        self.assertIn(self.browser.find_element(By.CSS_SELECTOR, rate).text, ["—", "0.0 /s"])  # nothing arrived yet
        feed = os.path.join(self.dir.name, "feed.txt")
        with open(feed, "w") as out:
            out.writelines(f"{MONDAY + 60 * i} {i % 2}\n" for i in range(200))
        self.fremenctl("ingest", "--map", "feed", "--states", feed, "--name", "sensor")
        self.wait(lambda: re.fullmatch(r"[\d.]+ /s", self.browser.find_element(By.CSS_SELECTOR, rate).text)
                  and float(self.browser.find_element(By.CSS_SELECTOR, rate).text.split()[0]) > 0,
                  "no ingest rate after the ingest")
        self.screenshot("overview")

    def test_the_grid_canvas_shows_walls_dark_and_free_floor_light_as_the_region_says(self):
        self.open(f"/grid/demo-office?t={MONDAY}")
        self.wait_ready()
        time = self.set_slider(36)  # 09:00
        self.assertIn("2023-11-27 09:00 UTC", self.browser.find_element(By.ID, "time-label").text)
        p = self.region(time)
        grays = self.grays()
        for cell, probability in p.items():
            self.assertAlmostEqual(grays[cell], round(255 * (1 - probability)), delta=1, msg=f"cell {cell}")
        walls = [cell for cell, probability in p.items() if probability > 0.9]
        floor = [cell for cell, probability in p.items() if probability < 0.1]
        self.assertGreater(len(walls), 100)  # the outer walls alone are 116 cells
        self.assertGreater(len(floor), 200)
        self.assertTrue(all(grays[cell] < 26 for cell in walls))
        self.assertTrue(all(grays[cell] > 229 for cell in floor))
        self.assertLess(grays[(0, 0)], 26)  # a corner of the outer wall
        self.screenshot("grid", height=870)  # README.md's docs/dashboard.png

    def test_entropy_and_state_modes_and_zoom_draw_what_the_region_says(self):
        self.open(f"/grid/demo-office?t={MONDAY}")
        self.wait_ready()
        time = self.set_slider(36)
        canvas = self.browser.find_element(By.ID, "grid-canvas")
        box = {"lo.x": 0, "lo.y": 0, "hi.x": 40, "hi.y": 20, "time": time}

        Select(self.browser.find_element(By.ID, "mode-select")).select_by_value("entropy")
        self.wait(lambda: canvas.get_attribute("data-mode") == "entropy", "no entropy map")
        entropy = self.api("/v1/maps/demo-office/region", {**box, "output": "REGION_OUTPUT_ENTROPY"})["floatValues"]
        grays = self.grays()
        for i, h in enumerate(entropy):
            self.assertAlmostEqual(grays[(i % 40, i // 40)], round(255 * (1 - float(h))), delta=1)

        Select(self.browser.find_element(By.ID, "mode-select")).select_by_value("state")
        field = self.browser.find_element(By.ID, "confidence")
        field.clear()
        field.send_keys("0.3\n")
        self.wait(lambda: canvas.get_attribute("data-mode") == "state" and "c = 0.3" in
                  self.browser.find_element(By.ID, "grid-status").text, "no state map at c = 0.3")
        states = self.api("/v1/maps/demo-office/region", {**box, "output": "REGION_OUTPUT_STATES", "confidence": 0.3})
        occupied = base64.b64decode(states["bytesValues"])
        grays = self.grays()
        for i, s in enumerate(occupied):
            self.assertEqual(grays[(i % 40, i // 40)], 0 if s else 255, f"cell {(i % 40, i // 40)}")

        # The wheel zooms about the cursor; the cells stay where the canvas says they are.
        scale = float(canvas.get_attribute("data-scale"))
        self.js("""const c = document.getElementById('grid-canvas'), b = c.getBoundingClientRect();
                   c.dispatchEvent(new WheelEvent('wheel', {deltaY: -100, clientX: b.left + 100, clientY: b.top + 100,
                                                            bubbles: true, cancelable: true}));""")
        self.assertAlmostEqual(float(canvas.get_attribute("data-scale")), scale * 1.25)
        zoomed = self.grays()
        visible = [i for i in range(40 * 20) if zoomed[(i % 40, i // 40)] is not None]
        self.assertGreater(len(visible), 100)
        for i in visible:
            self.assertEqual(zoomed[(i % 40, i // 40)], 0 if occupied[i] else 255)
        self.screenshot("grid-states-zoomed")

    def test_moving_the_slider_from_03_to_09_changes_the_doorway(self):
        self.open(f"/grid/demo-office?t={MONDAY}")
        self.wait_ready()
        night_time = self.set_slider(12)
        self.assertIn("2023-11-27 03:00 UTC", self.browser.find_element(By.ID, "time-label").text)
        night = self.grays()
        morning_time = self.set_slider(36)
        morning = self.grays()
        night_p, morning_p = self.region(night_time), self.region(morning_time)
        for cell in DOORWAY:
            self.assertLess(night[cell], 102, f"the door is shut at 03:00: {cell} is dark")
            self.assertAlmostEqual(night[cell], round(255 * (1 - night_p[cell])), delta=1)
            self.assertAlmostEqual(morning[cell], round(255 * (1 - morning_p[cell])), delta=1)
            self.assertGreater(morning[cell] - night[cell], 10, f"doorway cell {cell} did not change")
        # The walls did not move.
        self.assertEqual(night[(0, 0)], morning[(0, 0)])
        # Play walks the slider forward, a drawn frame at a time.
        self.browser.find_element(By.ID, "play-button").click()
        self.wait(lambda: int(self.js("return document.getElementById('time-slider').value")) >= 40,
                  "play did not advance")
        self.browser.find_element(By.ID, "play-button").click()
        # Hovering a cell tells its p.
        canvas = self.browser.find_element(By.ID, "grid-canvas")
        px, py = self.cell_pixel(20, 9)
        ActionChains(self.browser).move_to_element_with_offset(
            canvas, int(px - canvas.size["width"] / 2), int(py - canvas.size["height"] / 2)).perform()
        self.wait(lambda: "cell (20, 9)" in self.browser.find_element(By.ID, "hover-info").text, "no hover readout")
        self.assertIn("p = ", self.browser.find_element(By.ID, "hover-info").text)

    def test_clicking_the_door_cell_draws_its_model(self):
        self.open(f"/grid/demo-office?t={MONDAY}")
        self.wait_ready()
        canvas = self.browser.find_element(By.ID, "grid-canvas")
        px, py = self.cell_pixel(*DOORWAY[0])
        ActionChains(self.browser).move_to_element_with_offset(
            canvas, int(px - canvas.size["width"] / 2), int(py - canvas.size["height"] / 2)).click().perform()
        self.wait(lambda: self.js("return location.hash").startswith("#/model/demo-office?x=20&y=9"), "no model view")
        self.wait_ready()
        points = self.js("return Chart.getChart(document.getElementById('model-chart')).data.datasets[0].data.length")
        self.assertEqual(points, 7 * 24 * 12 + 1)  # a week every 5 minutes
        self.assertEqual(self.js("return document.getElementById('model-chart').dataset.points"), str(points))
        # The curve is on the canvas: pixels of its color (#0b62a4).
        curve = self.js("""
            const c = document.getElementById('model-chart');
            const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
            let n = 0;
            for (let i = 0; i < d.length; i += 4) n += d[i] < 60 && d[i + 1] > 70 && d[i + 1] < 130 && d[i + 2] > 130;
            return n;""")
        self.assertGreater(curve, 300)
        model = self.api("/v1/maps/demo-office/model", {"state.cell.x": 20, "state.cell.y": 9})["model"]
        published = self.browser.find_elements(By.CSS_SELECTOR, "#published-components tbody tr")
        self.assertEqual(len(published), len(model.get("published", [])))
        self.assertGreater(len(published), 0)
        chosen = self.browser.find_element(By.CSS_SELECTOR, "#order-errors tr.chosen")
        self.assertEqual(chosen.get_attribute("data-order"), str(model.get("selectedOrder", 0)))
        self.assertIn("τ", self.browser.find_element(By.ID, "persistence").text)
        self.screenshot("model")

    def test_a_lossless_states_model_draws_its_observations(self):
        self.open("/model/lab?name=door")
        self.wait_ready()
        datasets = self.js("""return Chart.getChart(document.getElementById('model-chart')).data.datasets
                                  .map((d) => d.data.map((p) => [p.x, p.y]));""")
        self.assertEqual(len(datasets), 2)  # p(t) and the observed states
        predicted, observed = datasets
        self.assertEqual(len(predicted), 7 * 24 * 12 + 1)
        # The plotted week is the observed one; every slot of it is drawn at its middle, with the
        # state that was ingested there.
        self.assertEqual(len(observed), len(LAB_TIMES))
        for (x, y), t in zip(observed, LAB_TIMES):
            self.assertEqual((x, y), (t + LAB_SAMPLING / 2, lab_door(t)))
        self.assertIn("lossless history", self.browser.find_element(By.ID, "model-caption").text)
        self.assertIn("ε_e / ε_p", self.browser.find_element(By.ID, "lossless").text)
        self.screenshot("model-lossless")

    def test_the_generic_map_lists_its_states(self):
        self.open(f"/generic/demo-states?t={MONDAY + 13 * 3600}")
        self.wait_ready()
        rows = self.browser.find_elements(By.CSS_SELECTOR, "#states-table tbody tr")
        self.assertEqual([row.get_attribute("data-name") for row in rows], ["door", "kitchen-light", "meeting-room"])
        door = self.browser.find_element(By.CSS_SELECTOR, "#states-table tr[data-name='door']")
        cells = door.find_elements(By.TAG_NAME, "td")
        expected = self.api("/v1/maps/demo-states:predict",
                            body={"states": {"names": ["door"]}, "times": [MONDAY + 13 * 3600]})["probabilities"][0]
        self.assertAlmostEqual(float(cells[3].text), expected, delta=0.0006)  # p at t, 13:00 Monday: open
        self.assertGreater(float(cells[3].text), 0.6)
        self.assertRegex(cells[4].text, r"^\d+$")  # the selected order
        self.screenshot("generic")

    def test_run_update_asks_for_the_write_token_and_shows_the_done_operation(self):
        self.open("/jobs")
        self.wait_ready()
        Select(self.browser.find_element(By.ID, "update-map")).select_by_value("demo-office")
        self.browser.find_element(By.ID, "run-update").click()
        # A read token is refused (403): the prompt asks for a write token and the call is retried.
        self.wait(lambda: self.js("return document.getElementById('token-dialog').open"), "no token prompt on 403")
        self.assertIn("write token", self.browser.find_element(By.ID, "token-reason").text)
        field = self.browser.find_element(By.ID, "token-input")
        field.clear()
        field.send_keys(WRITE_TOKEN)
        self.browser.find_element(By.ID, "token-save").click()
        name = self.wait(lambda: self.js("return document.getElementById('run-update-result').dataset.operation"),
                         "the update did not start")
        done_row = f"#operations-table tr[data-operation='{name}'][data-stage='done']"
        self.wait(lambda: self.browser.find_elements(By.CSS_SELECTOR, done_row), "the operation never showed done")
        self.wait(lambda: name in self.browser.find_element(By.ID, "last-job").text, "the last job is not the new one")
        self.assertIn("No failed maps.", self.browser.find_element(By.ID, "failed-maps").text)
        self.screenshot("jobs")


if __name__ == "__main__":
    unittest.main()
