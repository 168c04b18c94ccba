"""The report in a real browser: headless Chromium draws every plot, without script errors or console output,
without a single network request, and a screenshot of the page is not blank.

Chromium is driven by its own command line, no WebDriver: ``--dump-dom`` prints the page after its scripts ran,
and the page's script records on each plot what it drew (``data-rendered``, ``data-series``, ``data-points``) and
on ``<html>`` every error it caught (``data-js-errors``), so the serialized DOM says whether each plot rendered.
``--enable-logging=stderr`` shows any console message (the page prints none), ``--log-net-log`` every request
(the page makes none; a canary page with a broken plot and a remote image proves these checks can fail), and
``--screenshot`` the picture kept in the test's temporary directory.
"""

from __future__ import annotations

import json
import re
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from bldclab.cli import main
from conftest import require_tool

pytestmark = pytest.mark.slow  # headless Chromium: a few seconds a page

# Flags that keep headless Chromium off the network and quick to start (a fresh profile for every run); host
# names resolve to nothing, so even a request that slipped through could not leave the machine.
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync", "--hide-scrollbars",
         "--disable-extensions", "--host-resolver-rules=MAP * ~NOTFOUND")


class Dom(HTMLParser):
    """The rendered DOM: the <html> attributes, each plot figure's attributes and the series paths inside it."""

    def __init__(self, text: str) -> None:
        super().__init__(convert_charrefs=True)
        self.root: dict[str, str] = {}
        self.figures: dict[str, dict[str, str]] = {}
        self.paths: dict[str, list[str]] = {}
        self._figure: str | None = None
        self._depth = 0
        self.feed(text)

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = {k: v or "" for k, v in attrs}
        if tag == "html":
            self.root = a
        if tag == "figure":
            if "plot" in a.get("class", "").split():
                self._figure = a.get("data-plot", "")
                self.figures[self._figure] = a
                self.paths[self._figure] = []
            self._depth += 1
        elif self._figure is not None and tag == "path" and "series" in a.get("class", "").split():
            self.paths[self._figure].append(a.get("d", ""))

    def handle_endtag(self, tag: str) -> None:
        if tag == "figure":
            self._depth -= 1
            if self._depth == 0:
                self._figure = None


def _chromium(exe: str, page: Path, work: Path, name: str, *args: str) -> subprocess.CompletedProcess[str]:
    profile = work / f"profile-{name}"
    return subprocess.run([exe, *FLAGS, f"--user-data-dir={profile}", "--enable-logging=stderr", "--v=0",
                           f"--log-net-log={work / f'{name}-netlog.json'}", *args, page.as_uri()],
                          capture_output=True, text=True, timeout=180)


def _console(stderr: str) -> list[str]:
    """Console messages of the page (Chromium logs them as INFO:CONSOLE lines)."""
    return [line for line in stderr.splitlines() if ":CONSOLE" in line]


def _page_requests(netlog: Path, page: Path) -> list[str]:
    """URLs the page asked the network for: requests whose top frame is a local file (Chromium's own are not)."""
    log = json.loads(netlog.read_text())
    start = log["constants"]["logEventTypes"]["URL_REQUEST_START_JOB"]
    urls = []
    for ev in log["events"]:
        p = ev.get("params", {})
        if ev["type"] == start and "file://" in str(p.get("network_isolation_key", "")):
            if not str(p.get("url", "")).startswith("file:"):
                urls.append(str(p["url"]))
    return urls


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, Path, Path]:
    exe = require_tool("chromium")
    work = tmp_path_factory.mktemp("browser")
    page = work / "report.html"
    assert main(["report", "htm-48v", "--speeds", "3", "--torque-control", "--workers", "1", "--no-progress",
                 "--out", str(page)]) == 0
    return exe, work, page


def test_every_plot_renders_without_errors_or_network(built: tuple[str, Path, Path]) -> None:
    exe, work, page = built
    source = page.read_text(encoding="utf-8")
    expected = re.findall(r'<figure class="plot" id="fig-[^"]*" data-plot="([^"]+)"', source)
    spec = json.loads(re.search(r'<script type="application/json" id="bldclab-data">(.*?)</script>', source,
                                flags=re.S).group(1))["plots"]
    assert len(expected) >= 13 and set(expected) == set(spec)
    proc = _chromium(exe, page, work, "report", "--window-size=1280,900", "--dump-dom")
    assert proc.returncode == 0, proc.stderr[-2000:]
    dom = Dom(proc.stdout)
    assert dom.root.get("data-js-errors") == "0", dom.root.get("data-js-error-log")
    assert dom.root.get("data-plots-total") == dom.root.get("data-plots-ok") == str(len(expected))
    assert "js" in dom.root.get("class", "").split()
    assert set(dom.figures) == set(expected)
    for pid in expected:
        fig = dom.figures[pid]
        assert fig.get("data-rendered") == "ok", (pid, fig.get("data-error"))
        shown = [s for s in spec[pid]["series"] if not s.get("hidden")]
        assert int(fig["data-series"]) == len(shown), pid
        assert int(fig["data-points"]) >= 2 * len(shown), pid
        paths = dom.paths[pid]
        assert len(paths) >= len(shown), pid
        drawn = sum(d.count("M") + d.count("L") for d in paths)  # line vertices and markers
        assert drawn >= int(fig["data-points"]), pid
    # the waveform panels are big: thousands of points each
    assert int(dom.figures["wave-0.3-currents-square"]["data-points"]) > 3000
    assert _console(proc.stderr) == []
    assert _page_requests(work / "report-netlog.json", page) == []


def test_the_checks_catch_a_broken_page(built: tuple[str, Path, Path]) -> None:
    """Canary: a plot whose data is missing, a script error and a remote image are all detected."""
    exe, work, page = built
    source = page.read_text(encoding="utf-8")
    broken = source.replace('"y":"T_pu"', '"y":"no_such_column"', 1)
    assert broken != source
    broken = broken.replace("</main>", '<img src="http://canary.invalid/pixel.png" alt=""></main>', 1)
    broken = broken.replace("</body>", "<script>console.log('canary'); undefinedFunction();</script></body>", 1)
    canary = work / "canary.html"
    canary.write_text(broken, encoding="utf-8")
    proc = _chromium(exe, canary, work, "canary", "--window-size=1280,900", "--dump-dom")
    dom = Dom(proc.stdout)
    assert dom.figures["torque"].get("data-rendered") == "error"
    assert "no_such_column" in dom.figures["torque"].get("data-error", "")
    assert int(dom.root.get("data-js-errors", "0")) >= 2  # the plot and the undefined function
    assert int(dom.root["data-plots-ok"]) == int(dom.root["data-plots-total"]) - 1
    assert any("canary" in line for line in _console(proc.stderr))
    assert _page_requests(work / "canary-netlog.json", canary) == ["http://canary.invalid/pixel.png"]


# Drives the page's own plot object with synthetic mouse events and records what happened.
_INTERACT = """<script>(function () {
  var out = {};
  try {
    var fig = document.getElementById("fig-torque"), plot = fig.bldclabPlot, area = fig.querySelector(".plot-area");
    fig.scrollIntoView();
    function at(px, py) {
      var r = plot.svg.getBoundingClientRect();
      return {clientX: r.left + px * r.width / 640, clientY: r.top + py * r.height / 400, bubbles: true, button: 0};
    }
    function fire(target, type, px, py) { target.dispatchEvent(new MouseEvent(type, at(px, py))); }
    var s = plot.series[4];
    fire(area, "mousemove", plot.sx(s.x[0]), plot.sy(s.y[0]));
    var tip = fig.querySelector(".plot-tip");
    out.tip = tip.hidden ? null : tip.textContent;
    fire(area, "mousedown", 100, 60);
    fire(area, "mousemove", 300, 200);
    fire(window, "mouseup", 300, 200);
    out.zoomed = [plot.view.x0, plot.view.x1, plot.view.y0, plot.view.y1];
    area.dispatchEvent(new MouseEvent("dblclick", {bubbles: true}));
    out.reset = [plot.view.x0, plot.view.x1];
    var before = fig.getAttribute("data-series");
    fig.querySelectorAll(".legend-item")[0].click();
    out.series = [before, fig.getAttribute("data-series")];
    document.querySelector('input[name="wave-speed"][value="0.8"]').click();
    out.groups = Array.prototype.map.call(document.querySelectorAll(".wave-group"), function (g) {
      return g.getAttribute("data-value") + (g.hidden ? " hidden" : " shown");
    });
  } catch (e) { out.error = String(e); }
  document.documentElement.setAttribute("data-interaction", JSON.stringify(out));
}());</script>"""


def test_hover_zoom_legend_and_selector_work(built: tuple[str, Path, Path]) -> None:
    exe, work, page = built
    probe = work / "interact.html"
    probe.write_text(page.read_text(encoding="utf-8").replace("</body>", _INTERACT + "</body>", 1), encoding="utf-8")
    proc = _chromium(exe, probe, work, "interact", "--window-size=1280,900", "--dump-dom")
    dom = Dom(proc.stdout)
    assert dom.root.get("data-js-errors") == "0", dom.root.get("data-js-error-log")
    out = json.loads(dom.root["data-interaction"])
    assert "error" not in out, out
    # hovering the first simulated square-wave point shows its name and values
    assert out["tip"].startswith("simulated, square-wave") and "\u03a9 [p.u.] = 0.05" in out["tip"], out["tip"]
    x0, x1, y0, y1 = out["zoomed"]
    assert 0.0 < x0 < x1 < 1.0 and x1 - x0 < 0.5 and y1 - y0 < 1.0  # the box became the view
    assert out["reset"] == [0, 1]  # double-click: the full view again
    assert int(out["series"][1]) == int(out["series"][0]) - 1  # a legend click hid a series
    assert out["groups"] == ["0.3 hidden", "0.8 shown"]


def test_screenshot_is_not_blank(built: tuple[str, Path, Path]) -> None:
    from matplotlib import image

    exe, work, page = built
    shot = work / "report.png"
    proc = _chromium(exe, page, work, "shot", "--window-size=1280,9000", f"--screenshot={shot}")
    assert proc.returncode == 0 and shot.is_file(), proc.stderr[-2000:]
    img = image.imread(shot)[..., :3]
    assert img.shape[:2] == (9000, 1280)
    assert float(img.std()) > 0.08
    ink = np.any(img < 0.9, axis=2)
    assert 0.03 < float(ink.mean()) < 0.8  # text, tables and plots on a white page

    def near(rgb: tuple[int, int, int]) -> int:
        return int(np.count_nonzero(np.all(np.abs(img - np.array(rgb) / 255.0) < 0.08, axis=2)))

    # the plots are drawn: the sinusoidal (blue) and square-wave (red) series colour thousands of pixels, and the
    # header bar is there
    assert near((31, 119, 180)) > 2000 and near((214, 39, 40)) > 2000
    assert near((23, 50, 77)) > 1280 * 40
    print(f"screenshot: {shot}")
